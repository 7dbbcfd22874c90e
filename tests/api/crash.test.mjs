/*
 * crash.test.mjs - a job answered 202 is never lost: 50 jobs submitted, the server killed with
 * SIGKILL while some are running and others queued, restarted on the same database; every job
 * then finishes, with the series the command line computes for its spec, and the database is
 * intact (PRAGMA integrity_check with the sqlite3 command when there is one, and through the
 * service in any case).
 */
import assert from 'node:assert/strict';
import { spawnSync } from 'node:child_process';
import test from 'node:test';

import { BACKEND, cliCsv, FINAL, listAll, mapLimit, startServer, submit, waitFor } from './lib.mjs';

const NJOBS = 50;
const PRESETS = [
    'triple_pendulum_pid', 'triple_pendulum_pd', 'triple_pendulum_lqr', 'triple_pendulum_poles',
    'triple_pendulum_passive', 'spatial_double_pendulum_pd', 'spatial_double_pendulum_lqr',
];
/* about 0.06 s of work each (0.5 s under ASan): 5000 RK4 steps */
const DURATION = 0.5;
const jobOf = (i) => ({
    preset: PRESETS[i % PRESETS.length],
    name: `crash ${i}`,
    duration: DURATION,
    integrator: { method: 'rk4', step: 0.0001 },
});

let srv;
let dir;
const ids = [];

test('50 jobs are accepted', async () => {
    srv = await startServer({ workers: 2 });
    dir = srv.dir;
    for (let i = 0; i < NJOBS; i++) ids.push((await submit(srv, jobOf(i))).id);
    assert.equal(new Set(ids).size, NJOBS);
});

test('SIGKILL while jobs run and others wait', async () => {
    /* both workers busy and some jobs still queued, then kill at once */
    const h = await waitFor(
        async () => {
            const r = await srv.get('/api/health');
            return r.json.busy > 0 && r.json.queued > 0 ? r.json : null;
        },
        { timeoutMs: 10000, intervalMs: 20 },
    );
    const r = await srv.kill();
    assert.equal(r.signal, 'SIGKILL');
    assert.ok(h.jobs.done === undefined || h.jobs.done < NJOBS, JSON.stringify(h));
});

test('after a restart on the same database every job finishes done', async () => {
    srv = await startServer({ workers: 2, dir });
    const rows = await waitFor(
        async () => {
            const all = await listAll(srv, { limit: 200 });
            return all.length === NJOBS && all.every((j) => FINAL.has(j.status)) ? all : null;
        },
        { timeoutMs: 90000, intervalMs: 200 },
    );
    assert.deepEqual(rows.map((j) => j.id).sort((a, b) => a - b), [...ids].sort((a, b) => a - b));
    for (const row of rows) assert.equal(row.status, 'done', `job ${row.id}: ${row.status}`);
});

test("each job's series CSV equals the CLI's for its spec", async () => {
    const cache = new Map(); /* spec text -> CLI CSV */
    const jobs = await mapLimit(ids, 4, async (id) => (await srv.get(`/api/jobs/${id}`)).json);
    for (const [i, job] of jobs.entries()) {
        assert.equal(job.name, `crash ${i}`);
        assert.equal(job.progress, 1);
        assert.equal(job.metrics.t_end, DURATION);
        const key = JSON.stringify({ ...job.spec, name: null }); /* the name does not change the run */
        if (!cache.has(key)) cache.set(key, await cliCsv(job.spec));
        const res = await srv.get(`/api/jobs/${job.id}/series?format=csv`);
        assert.equal(res.status, 200, res.text);
        assert.ok(res.text === cache.get(key), `job ${job.id} (${job.name}): CSV differs from the CLI's`);
    }
    assert.equal(cache.size, PRESETS.length);
});

test('the database is intact: through the service', async () => {
    const h = await srv.get('/api/health');
    assert.equal(h.status, 200);
    assert.deepEqual(h.json.database, { state: 'ok' });
    assert.equal(h.json.jobs.done, NJOBS);
    for (const s of ['queued', 'running', 'failed', 'diverged', 'cancelled']) {
        assert.ok(!h.json.jobs[s], `${s}: ${h.json.jobs[s]}`);
    }
    const done = await listAll(srv, { limit: 7, status: 'done' });
    assert.equal(done.length, NJOBS);
});

test('the server stops cleanly on SIGTERM', async () => {
    const r = await srv.stop('SIGTERM');
    assert.equal(r.killed, undefined, 'it had to be killed');
    assert.equal(r.code, 0, srv.output());
});

test('the database is intact: PRAGMA integrity_check (sqlite3 command)', (t) => {
    if (BACKEND !== 'sqlite') {
        t.skip('an SQLite file check; PostgreSQL keeps its own consistency (checked through the service above)');
        return;
    }
    const probe = spawnSync('sqlite3', ['-version'], { encoding: 'utf8' });
    if (probe.error) {
        t.skip('no sqlite3 command; checked through the service only');
        return;
    }
    const r = spawnSync('sqlite3', [srv.db, 'PRAGMA integrity_check;', 'SELECT count(*) FROM jobs;'], { encoding: 'utf8' });
    assert.equal(r.status, 0, r.stderr);
    assert.equal(r.stdout, `ok\n${NJOBS}\n`);
});
