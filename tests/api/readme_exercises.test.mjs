/*
 * readme_exercises.test.mjs - the README's exercises ("Teaching with ctcsim"), posted to the
 * service as the README's curl commands post them (POST /api/jobs?wait=60 with the same bodies), and the figures
 * the README quotes checked against the jobs' metrics and series. Each figure is also looked up
 * in the README's text (whitespace folded), so that neither can change without the other. The
 * README's way to give a deleted job's space back (DELETE, then `sqlite3 ctcsim.db 'VACUUM'` with
 * the service running) is run too.
 */
import assert from 'node:assert/strict';
import { spawnSync } from 'node:child_process';
import { readFileSync, statSync } from 'node:fs';
import path from 'node:path';
import test from 'node:test';

import { BACKEND, ROOT, startServer } from './lib.mjs';

const README = readFileSync(path.join(ROOT, 'README.md'), 'utf8').replace(/\s+/g, ' ');
let srv;

/* the README quotes this phrase */
function quoted(phrase) {
    assert.ok(README.includes(phrase), `README.md no longer says "${phrase}"`);
}

/* POST /api/jobs?wait=60 with body; the finished job */
async function run(body) {
    const res = await srv.request('POST', '/api/jobs?wait=60', { json: body });
    assert.equal(res.status, 200, `POST ${JSON.stringify(body)}: ${res.status} ${res.text}`);
    assert.equal(res.json.status, 'done', JSON.stringify(res.json));
    return res.json;
}

/* the largest |tau| of a finished job's series */
async function peakTorque(id) {
    const res = await srv.get(`/api/jobs/${id}/series?channels=tau`);
    assert.equal(res.status, 200, res.text);
    return Math.max(...res.json.tau.flat().map(Math.abs));
}

const maxAbs = (v) => Math.max(...v.map(Math.abs));

test('the server starts', async () => {
    srv = await startServer({ workers: 2 });
});

test('four controllers, one task: the final errors and the peak torques the README quotes', async () => {
    const jobs = {};
    for (const c of ['pd', 'pid', 'poles', 'lqr']) jobs[c] = await run({ preset: `triple_pendulum_${c}` });

    /* PD keeps an error against the constant disturbance; PID removes most of it */
    quoted('ends 5 s with errors up to 0.015 rad');
    assert.equal(maxAbs(jobs.pd.metrics.e_final).toFixed(3), '0.015');
    quoted("PID's integral term takes it to about 0.0015 rad");
    assert.equal(maxAbs(jobs.pid.metrics.e_final).toFixed(4), '0.0015');
    /* the designed controllers converge more slowly */
    for (const c of ['poles', 'lqr']) {
        for (let i = 0; i < 3; i++) assert.ok(jobs[c].metrics.e_rms[i] > jobs.pid.metrics.e_rms[i], `${c} e_rms[${i}]`);
    }

    /* faster gains cost torque, for the PD and the PID preset */
    quoted('with K_p = 400, K_v = 40 the peak |tau| of `triple_pendulum_pd` grows from 259 to 1068 N m');
    quoted('that of `triple_pendulum_pid` from 525 to 1171 N m');
    const fast = { controller: { kp: 400, kv: 40 } };
    for (const [c, before, after] of [['pd', 259, 1068], ['pid', 525, 1171]]) {
        assert.equal(Math.round(await peakTorque(jobs[c].id)), before, `${c} peak torque`);
        const j = await run({ preset: `triple_pendulum_${c}`, ...fast });
        assert.equal(Math.round(await peakTorque(j.id)), after, `${c} peak torque with kp 400, kv 40`);
    }
});

test('another controller type renames the job, in the service as on the command line', async () => {
    const lqr = await run({ preset: 'triple_pendulum_pid', controller: { type: 'lqr', Q: [1, 1, 1], lambda: 0.01 } });
    const name = 'Triple pendulum, LQR (scene of Kingsley et al. 2017, sec. 7.1)';
    quoted(`("${name}")`);
    assert.equal(lqr.name, name);
    assert.equal(lqr.spec.name, name);
    const mine = await run({ preset: 'triple_pendulum_pid', name: 'mine', controller: { type: 'lqr', Q: [1, 1, 1], lambda: 0.01 } });
    assert.equal(mine.name, 'mine');
});

test('model error against the integral term: the offsets the README quotes', async () => {
    const hold = (c) => ({
        preset: `triple_pendulum_${c}`, controller: { model: { mass_scale: 0.8 } },
        trajectory: { type: 'constant', value: 0.5 }, disturbance: { type: 'none' }, duration: 10,
    });
    const pd = await run(hold('pd'));
    const pid = await run(hold('pid'));
    quoted('PD settles with a steady offset (0.017 rad at the second joint)');
    assert.equal(Math.abs(pd.metrics.e_final[1]).toFixed(3), '0.017');
    assert.equal(maxAbs(pd.metrics.e_final), Math.abs(pd.metrics.e_final[1]), 'the second joint has the largest offset');
    quoted('PID removes it (below 1e-11 rad at 10 s)');
    assert.ok(maxAbs(pid.metrics.e_final) < 1e-11, `PID e_final ${pid.metrics.e_final}`);
});

test("the passive pendulum's energy drift with dopri5 and with rk4", async () => {
    const dopri = await run({ preset: 'triple_pendulum_passive' });
    const rk4 = await run({ preset: 'triple_pendulum_passive', integrator: { method: 'rk4', step: 0.01 } });
    quoted("(`metrics.energy_drift`: 1e-7 with the preset's `dopri5`, 3e-3 with");
    assert.equal(Math.abs(dopri.metrics.energy_drift).toExponential(0), '1e-7');
    assert.equal(Math.abs(rk4.metrics.energy_drift).toExponential(0), '3e-3');
});

test("a deleted job's space: kept by the file, given back by VACUUM while the service runs", async (t) => {
    if (BACKEND !== 'sqlite') {
        t.skip("the README's SQLite file and VACUUM; PostgreSQL's autovacuum gives space back itself");
        return;
    }
    if (spawnSync('sqlite3', ['-version']).error) {
        t.skip('no sqlite3 command');
        return;
    }
    quoted("`sqlite3 ctcsim.db 'VACUUM'`");
    /* the database file's size with the WAL folded into it */
    const size = () => {
        const r = spawnSync('sqlite3', [srv.db, 'PRAGMA wal_checkpoint(TRUNCATE);'], { encoding: 'utf8' });
        assert.equal(r.status, 0, r.stderr);
        return statSync(srv.db).size;
    };
    const big = await run({ preset: 'n_link_pendulum', n: 256 });
    const before = size();
    const del = await srv.del(`/api/jobs/${big.id}`);
    assert.equal(del.status, 204, del.text);
    assert.equal(size(), before, 'the file shrank on DELETE alone');
    const vac = spawnSync('sqlite3', [srv.db, 'VACUUM'], { encoding: 'utf8' });
    assert.equal(vac.status, 0, vac.stderr);
    const after = size();
    assert.ok(after < before - 4e6, `VACUUM: ${before} -> ${after} bytes`);
    /* the service goes on with the vacuumed file */
    const j = await run({ preset: 'triple_pendulum_pd', duration: 0.5 });
    const got = await srv.get(`/api/jobs/${j.id}/series?channels=e&format=csv`);
    assert.equal(got.status, 200, got.text);
});

test('the server stops', async () => {
    const r = await srv.stop();
    assert.equal(r.code, 0, srv.output());
});
