/*
 * cancel.test.mjs - DELETE in each state of a job (running: 202 and cancelled within 2 s;
 * queued: 200 cancelled; finished: 204 and gone), POST ?wait=, and a SIGTERM while a job runs:
 * the job is re-queued and runs again, from t = 0, after the restart.
 */
import assert from 'node:assert/strict';
import test from 'node:test';

import { cliCsv, keepAliveClient, sleep, startServer, submit, waitFor, waitIdle, waitJob } from './lib.mjs';

/* runs for many minutes: only ever cancelled */
const LONG = { preset: 'n_link_pendulum', n: 64, duration: 600, integrator: { method: 'rk4', step: 0.0001 }, output: { interval: 0.1 } };
const SHORT = { preset: 'triple_pendulum_pid', duration: 0.5 };
/* about 0.75 s of work (5-6 s under ASan): 300000 RK4 steps of the triple pendulum; the test
   must see it running, so it may not be much shorter (4 s of it took 0.24 s by 2026-11) */
const MEDIUM = { preset: 'triple_pendulum_pid', name: 'medium', duration: 12, integrator: { method: 'rk4', step: 0.00004 } };

const running = (j) => j.status === 'running' && j.progress > 0;

let srv;
let cancelledId;

test('the server starts', async () => {
    srv = await startServer({ workers: 2 });
});

test('DELETE a running job: 202, then cancelled within 2 s, stopped early', async () => {
    const id = (await submit(srv, LONG)).id;
    await waitJob(srv, id, { until: running, timeoutMs: 10000 });
    const t0 = Date.now();
    const res = await srv.del(`/api/jobs/${id}`);
    assert.equal(res.status, 202, res.text);
    assert.equal(res.json.id, id);
    assert.equal(res.json.location, `/api/jobs/${id}`);
    const job = await waitJob(srv, id, { timeoutMs: 5000, intervalMs: 20 });
    const ms = Date.now() - t0;
    assert.equal(job.status, 'cancelled');
    assert.ok(ms < 2000, `cancelled after ${ms} ms`);
    assert.ok(job.metrics, 'a cancelled run has metrics');
    assert.ok(job.metrics.t_end > 0 && job.metrics.t_end < 600, `t_end ${job.metrics.t_end}`);
    assert.ok(job.progress < 1);
    assert.match(job.finished, /Z$/);
    const series = await srv.get(`/api/jobs/${id}/series`);
    assert.ok(series.status === 200 || series.status === 404, `series: ${series.status} ${series.text}`);
    cancelledId = id;
});

test('DELETE a queued job: 200 with the job cancelled, no series', async () => {
    /* both workers busy, so the third job waits */
    const a = (await submit(srv, LONG)).id;
    const b = (await submit(srv, LONG)).id;
    await waitJob(srv, a, { until: running, timeoutMs: 10000 });
    await waitJob(srv, b, { until: running, timeoutMs: 10000 });
    const q = (await submit(srv, SHORT)).id;
    assert.equal((await srv.get(`/api/jobs/${q}`)).json.status, 'queued');
    const res = await srv.del(`/api/jobs/${q}`);
    assert.equal(res.status, 200, res.text);
    assert.equal(res.json.id, q);
    assert.equal(res.json.status, 'cancelled');
    assert.ok('spec' in res.json && 'metrics' in res.json, 'the answer is the whole job');
    const job = (await srv.get(`/api/jobs/${q}`)).json;
    assert.equal(job.status, 'cancelled');
    assert.equal(job.started, null);
    const series = await srv.get(`/api/jobs/${q}/series`);
    assert.equal(series.status, 404, series.text);
    assert.equal(series.json.error.code, 'NOT_FOUND');
    /* the two long ones */
    for (const id of [a, b]) assert.equal((await srv.del(`/api/jobs/${id}`)).status, 202);
    for (const id of [a, b]) assert.equal((await waitJob(srv, id, { timeoutMs: 5000 })).status, 'cancelled');
    await waitIdle(srv);
});

test('DELETE a finished job: 204, then 404 everywhere', async () => {
    const id = (await submit(srv, SHORT)).id;
    assert.equal((await waitJob(srv, id)).status, 'done');
    const res = await srv.del(`/api/jobs/${id}`);
    assert.equal(res.status, 204, res.text);
    assert.equal(res.text, '');
    for (const [method, p] of [['GET', `/api/jobs/${id}`], ['GET', `/api/jobs/${id}/series`], ['DELETE', `/api/jobs/${id}`]]) {
        const r = await srv.request(method, p);
        assert.equal(r.status, 404, `${method} ${p}: ${r.text}`);
        assert.equal(r.json.error.code, 'NOT_FOUND');
    }
    /* a cancelled job is finished too */
    assert.equal((await srv.del(`/api/jobs/${cancelledId}`)).status, 204);
    assert.equal((await srv.get(`/api/jobs/${cancelledId}`)).status, 404);
    const rows = (await srv.get('/api/jobs?limit=200')).json.jobs.map((r) => r.id);
    assert.ok(!rows.includes(id) && !rows.includes(cancelledId), 'deleted jobs are not listed');
});

test('POST ?wait=10 on a short job answers 200 with the finished job', async () => {
    const t0 = Date.now();
    const res = await srv.post('/api/jobs?wait=10', SHORT);
    assert.equal(res.status, 200, res.text);
    assert.ok(Date.now() - t0 < 10000);
    assert.equal(res.json.status, 'done');
    assert.equal(res.json.progress, 1);
    assert.equal(res.json.metrics.status, 'done');
    assert.equal(res.json.spec.duration, SHORT.duration);
    assert.deepEqual(res.json, (await srv.get(`/api/jobs/${res.json.id}`)).json);
});

test('POST ?wait=0.5 on a long job answers 202 with the row when the wait runs out', async () => {
    const t0 = Date.now();
    const res = await srv.post('/api/jobs?wait=0.5', LONG);
    const ms = Date.now() - t0;
    assert.equal(res.status, 202, res.text);
    assert.ok(ms >= 450 && ms < 3000, `answered after ${ms} ms`);
    assert.ok(['queued', 'running'].includes(res.json.status));
    assert.equal(res.headers.location, `/api/jobs/${res.json.id}`);
    assert.equal((await srv.del(`/api/jobs/${res.json.id}`)).status, 202);
    assert.equal((await waitJob(srv, res.json.id, { timeoutMs: 5000 })).status, 'cancelled');
});

test('SIGTERM while a job runs: it is re-queued, and runs again to done after a restart', async () => {
    const id = (await submit(srv, MEDIUM)).id;
    await waitJob(srv, id, { until: running, timeoutMs: 10000 });
    const r = await srv.stop('SIGTERM', 10000);
    assert.equal(r.killed, undefined, `SIGTERM did not stop the server\n${srv.output()}`);
    assert.equal(r.code, 0, srv.output());
    assert.ok(r.ms < 3000, `shutdown took ${r.ms} ms`);

    srv = await startServer({ workers: 2, dir: srv.dir });
    const again = (await srv.get(`/api/jobs/${id}`)).json;
    assert.ok(['queued', 'running'].includes(again.status), `after the restart: ${again.status}`);
    assert.equal(again.metrics, null);
    /* the undisturbed run, on the other core meanwhile */
    const reference = cliCsv(again.spec);
    reference.catch(() => {}); /* awaited below; no unhandled rejection meanwhile */
    const job = await waitJob(srv, id, { timeoutMs: 60000 });
    assert.equal(job.status, 'done', job.message);
    assert.equal(job.metrics.t_end, MEDIUM.duration);
    /* it ran from t = 0 again: the same series as an undisturbed run */
    const csv = await srv.get(`/api/jobs/${id}/series?format=csv`);
    assert.ok(csv.text === (await reference), 'CSV differs from the CLI\'s');
});

test('a client waiting on ?wait= does not hold up requests on other keep-alive connections', async () => {
    /* 8 idle keep-alive connections, spread over the server's HTTP threads */
    const clients = Array.from({ length: 8 }, () => keepAliveClient(srv.port));
    try {
        for (const c of clients) assert.equal((await c.get('/api/health')).status, 200);
        const waiting = srv.raw('POST', '/api/jobs?wait=3', { headers: { 'content-type': 'application/json' }, body: JSON.stringify(LONG) });
        await sleep(300);
        const answers = await Promise.all(clients.map((c) => c.get('/api/health')));
        const res = await waiting;
        assert.equal(res.status, 202, res.text);
        assert.equal((await srv.del(`/api/jobs/${res.json.id}`)).status, 202);
        await waitJob(srv, res.json.id, { timeoutMs: 5000 });
        const slow = answers.filter((a) => a.status !== 200 || a.ms > 1000);
        assert.equal(slow.length, 0, `GET /api/health on idle keep-alive connections while one client waits 3 s: ${answers.map((a) => `${a.status} in ${a.ms} ms`).join(', ')}`);
    } finally {
        clients.forEach((c) => c.close());
    }
});

test('SIGTERM answers a client waiting on ?wait= (202 with the row, or 503), not a dropped connection', async () => {
    /* requests here go on new connections: a waiting client may hold up others (see above) */
    const get = async (p) => (await srv.raw('GET', p)).json;
    const before = new Set((await get('/api/jobs?limit=200')).jobs.map((j) => j.id));
    let answered = false;
    const waiting = srv.raw('POST', '/api/jobs?wait=20', { headers: { 'content-type': 'application/json' }, body: JSON.stringify(LONG) })
        .catch((e) => ({ status: `no answer (${e.code || e.message})`, text: '' }))
        .finally(() => (answered = true));
    /* let the server take that connection first: a request accepted along with it by the same
       HTTP thread would wait with it */
    await sleep(300);
    /* the job is stored and running, its client still waiting */
    const row = await waitFor(async () => (await get('/api/jobs?status=running')).jobs.find((j) => !before.has(j.id) && j.progress > 0), { timeoutMs: 10000 });
    assert.ok(!answered, 'the client was answered before the SIGTERM (the polls above were held up)');
    const r = await srv.stop('SIGTERM', 30000);
    assert.equal(r.code, 0, srv.output());
    const res = await waiting;
    /* the job stays stored and runs again after a restart, so its client must learn its id */
    srv = await startServer({ workers: 2, dir: srv.dir });
    const del = await srv.del(`/api/jobs/${row.id}`);
    assert.ok([200, 202].includes(del.status), `the job was lost: DELETE ${del.status} ${del.text}`);
    assert.ok(res.status === 202 || res.status === 503, `the waiting client got ${res.status} ${res.text}`);
    if (res.status === 202) assert.equal(res.json.id, row.id);
    else assert.equal(res.json.error.code, 'SHUTTING_DOWN');
});

test('the server stops cleanly on SIGTERM', async () => {
    const r = await srv.stop('SIGTERM');
    assert.equal(r.killed, undefined, 'it had to be killed');
    assert.equal(r.code, 0, srv.output());
});
