/*
 * kinematics.test.mjs - the page's loop closure (web/kinematics.js closeLoop, which draws a
 * closed chain's desired pose) against the simulation: for samples of a five-bar run (the
 * server's recorded q, whose loop residual the run reports below 1e-8 m), the dependent
 * coordinates are pushed off and solved for again from the independent ones; the solution must
 * close the loop and give back the recorded coordinates. Runs in Node (no browser).
 */
import assert from 'node:assert/strict';
import { after, before, test } from 'node:test';

import { chainLayout, closeLoop } from '../../web/kinematics.js';
import { runJob, startWebServer } from './lib.mjs';

let srv;
let job;
let series;

before(async () => {
    srv = await startWebServer();
    job = await runJob(srv, { preset: 'five_bar_pd', duration: 1 });
    series = (await srv.get(`/api/jobs/${job.id}/series?channels=q`)).json;
});

after(async () => {
    await srv?.stop();
});

test('closeLoop gives back the recorded dependent coordinates of a five-bar run', () => {
    const { bodies, loop } = job.spec.scene;
    const layout = chainLayout(bodies, loop);
    /* the server's list of controlled coordinates (revolute joints: a joint's row is its index) */
    const independent = new Set(job.metrics.coordinates.map((c) => c.joint).filter((j) => j < bodies.length));
    const free = bodies.map((_, i) => i).filter((i) => !independent.has(i));
    assert.deepEqual(free, [3, 4], 'the five-bar\'s dependent joints');
    assert.ok(job.metrics.loop.residual_max < 1e-8, 'the run keeps its loop closed');
    let checked = 0;
    for (let k = 0; k < series.t.length; k += 10) {
        const q = series.q.map((row) => row[k]);
        const start = q.slice();
        for (const i of free) start[i] += 0.05;
        const { q: x, gap } = closeLoop(layout, loop, start, free);
        assert.ok(gap < 1e-9, `t = ${series.t[k]}: gap ${gap} m`);
        for (const i of free) assert.ok(Math.abs(x[i] - q[i]) < 1e-6, `t = ${series.t[k]}: q[${i}] ${x[i]}, recorded ${q[i]}`);
        for (const i of independent) assert.equal(x[i], q[i], 'the independent coordinates are kept');
        checked++;
    }
    assert.ok(checked >= 10, `${checked} samples`);
});
