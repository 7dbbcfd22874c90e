/*
 * loops.test.mjs - closed chains through the service: the five-bar preset run with ?wait, its
 * loop metrics and controlled coordinates, its series with the loop channel (JSON and CSV, the
 * CSV byte-identical to `ctcsim run`), a run that stops as singular (status failed, the metrics'
 * status "singular", its samples kept), and bad loops answered 400 at their field.
 */
import assert from 'node:assert/strict';
import test from 'node:test';

import { cliCsv, parseCsv, startServer } from './lib.mjs';

let srv;
let five; /* the five-bar job, finished */

test('the server starts', async () => {
    srv = await startServer({ workers: 2 });
});

test('POST five_bar_pd with ?wait answers the finished job with its loop metrics', async () => {
    const res = await srv.post('/api/jobs?wait=60', { preset: 'five_bar_pd', duration: 1, output: { interval: 0.05 } });
    assert.equal(res.status, 200, res.text);
    five = res.json;
    assert.deepEqual(five, (await srv.get(`/api/jobs/${five.id}`)).json);
    assert.equal(five.status, 'done', five.message);
    assert.equal(five.scene.bodies, 5);
    assert.equal(five.scene.coordinates, 5);
    const m = five.metrics;
    assert.equal(m.status, 'done');
    assert.equal(m.nv, 5);
    assert.equal(m.nind, 3);
    assert.deepEqual(m.coordinates, [0, 1, 2].map((k) => ({ joint: k, coordinate: k })));
    assert.equal(m.e_max.length, 3);
    assert.equal(m.gains.length, 3);
    assert.equal(five.e_max, Math.max(...m.e_max));
    const loop = m.loop;
    assert.ok(loop, 'metrics.loop');
    for (const key of ['residual_max', 'velocity_residual_max', 'cond_max']) {
        assert.equal(typeof loop[key], 'number', key);
        assert.ok(loop[key] >= 0, `${key} = ${loop[key]}`);
    }
    assert.ok(loop.residual_max < 1e-6, `residual_max ${loop.residual_max}`);
    assert.ok(Number.isInteger(loop.projections) && loop.projections >= 0);
    assert.deepEqual(Object.keys(loop.initial), ['iterations', 'dq_max', 'dv_max', 'residual_before',
        'residual_after', 'velocity_residual_before', 'velocity_residual_after']);
    /* the normalised spec writes the loop and every joint's flag */
    assert.deepEqual(five.spec.scene.bodies.map((b) => b.joint.independent), [true, true, true, false, false]);
    assert.equal(five.spec.scene.loop.joint.independent, false);
    assert.deepEqual(five.spec.scene.loop.stabilization, { method: 'project', tol: 1e-12 });
    assert.equal(five.spec.scene.loop.cond_max, 1e5);
    assert.ok(five.spec.output.channels.includes('loop'));
});

test('the series has the loop channel and one e, tau, w column per independent coordinate', async () => {
    const res = await srv.get(`/api/jobs/${five.id}/series`);
    assert.equal(res.status, 200, res.text);
    const s = res.json;
    const n = 21;
    assert.equal(s.t.length, n);
    assert.equal(s.q.length, 5);
    assert.equal(s.qdot.length, 5);
    for (const ch of ['q_des', 'qdot_des', 'e', 'tau', 'w']) assert.equal(s[ch].length, 3, ch);
    assert.equal(s.loop.length, 2);
    for (const col of s.loop) {
        assert.equal(col.length, n);
        for (const x of col) assert.ok(x === null || (x >= 0 && x < 1e-6), `loop residual ${x}`);
    }
    /* e = q_d - q on the independent joints 0, 1, 2 */
    for (let i = 0; i < 3; i++) {
        for (let j = 0; j < n; j++) assert.ok(Math.abs(s.e[i][j] - (s.q_des[i][j] - s.q[i][j])) < 1e-12);
    }

    /* only the loop; the CSV names its columns */
    const only = await srv.get(`/api/jobs/${five.id}/series?channels=loop`);
    assert.deepEqual(Object.keys(only.json), ['t', 'loop']);
    const csv = await srv.get(`/api/jobs/${five.id}/series?format=csv&channels=e,loop`);
    assert.equal(csv.status, 200, csv.text);
    assert.deepEqual(parseCsv(csv.text).header, ['t', 'e[0]', 'e[1]', 'e[2]', 'loop[position]', 'loop[velocity]']);

    /* joints= picks columns of q (one per coordinate), not of the loop */
    const picked = parseCsv((await srv.get(`/api/jobs/${five.id}/series?format=csv&channels=q,loop&joints=1,4`)).text);
    assert.deepEqual(picked.header, ['t', 'q[1]', 'q[4]', 'loop[position]', 'loop[velocity]']);

    /* the whole CSV is the command line's for the normalised spec */
    const all = await srv.get(`/api/jobs/${five.id}/series?format=csv`);
    assert.ok(all.text === (await cliCsv(five.spec)), "the service's CSV differs from the CLI's");
});

test('the passive four-bar runs with every joint dependent: no torque channel', async () => {
    const res = await srv.post('/api/jobs?wait=60', { preset: 'four_bar_passive', duration: 0.5 });
    assert.equal(res.status, 200, res.text);
    const job = res.json;
    assert.equal(job.status, 'done', job.message);
    assert.equal(job.metrics.nind, 0);
    assert.deepEqual(job.metrics.coordinates, []);
    assert.deepEqual(job.spec.output.channels, ['q', 'qdot', 'energy', 'loop']);
    assert.equal(typeof job.metrics.energy_drift, 'number');
    const s = (await srv.get(`/api/jobs/${job.id}/series`)).json;
    assert.deepEqual(Object.keys(s), ['t', 'q', 'qdot', 'energy', 'loop']);
});

test('a loop driven where its joints cannot move it stops as singular: failed, samples kept', async () => {
    const res = await srv.post('/api/jobs?wait=60', {
        preset: 'five_bar_pd', duration: 3, scene: { loop: { cond_max: 100 } },
        trajectory: [{ type: 'constant', value: 1.5 }, { type: 'constant', value: 0.785 }, { type: 'constant', value: -2.356 }],
    });
    assert.equal(res.status, 200, res.text);
    const job = res.json;
    assert.equal(job.status, 'failed');
    assert.equal(job.metrics.status, 'singular');
    assert.match(job.message, /cannot drive the loop/);
    assert.ok(job.metrics.t_end < 3);
    const s = await srv.get(`/api/jobs/${job.id}/series?channels=loop`);
    assert.equal(s.status, 200, s.text);
    assert.equal(s.json.t.length, job.metrics.samples);
});

test('bad loops are 400 at their field, through /api/jobs and /api/validate', async () => {
    const cases = [
        /* four independent coordinates against a mobility of 3 */
        [{ preset: 'five_bar_pd', scene: { loop: { joint: { independent: true } } }, trajectory: { type: 'constant', value: 0 } },
            'INVALID_FIELD', 'scene.loop', /mobility/],
        /* rods straight down: the loop cannot move as the count says */
        [{ preset: 'five_bar_pd', scene: { q0: [0, 0, 0, 0, 0] } }, 'INVALID_FIELD', 'scene.loop', /over-constrained|singular/],
        /* an anchor out of reach */
        [{ preset: 'five_bar_pd', scene: { loop: { anchor: [5, 0, 0] } } }, 'INVALID_FIELD', 'scene.q0', /does not close/],
        [{ preset: 'five_bar_pd', scene: { loop: { anchor: null } } }, 'MISSING_FIELD', 'scene.loop.anchor', /^is required$/],
        [{ preset: 'five_bar_pd', scene: { loop: { stabilization: { method: 'baumgarte', tol: 1e-9 } } } },
            'UNKNOWN_FIELD', 'scene.loop.stabilization.tol', /^key "tol" does not apply to method "baumgarte"$/],
        [{ preset: 'five_bar_pd', trajectory: { type: 'constant', value: 0 }, controller: { joints: [{}, {}, {}, {}, {}] } },
            'INVALID_FIELD', 'controller.joints', /^must have 3 entries, one per independent coordinate \(got 5\)$/],
        [{ preset: 'triple_pendulum_pd', output: { channels: ['q', 'loop'] } },
            'INVALID_FIELD', 'output.channels[1]', /^channel "loop" needs a loop \("scene.loop"\)$/],
    ];
    for (const [job, code, field, message] of cases) {
        for (const path of ['/api/jobs', '/api/validate']) {
            const res = await srv.post(path, job);
            assert.equal(res.status, 400, `${path} ${JSON.stringify(job)}: ${res.text}`);
            assert.equal(res.json.error.code, code, res.text);
            assert.equal(res.json.error.field, field, res.text);
            assert.match(res.json.error.message, message);
        }
    }
});

test('the server stops cleanly on SIGTERM', async () => {
    const r = await srv.stop('SIGTERM');
    assert.equal(r.code, 0, srv.output());
});
