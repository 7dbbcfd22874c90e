/*
 * waiters.test.mjs - POST /api/jobs?wait under a flood of waiters (issue 25, defect 5): with
 * --max-waiters 2 and one HTTP thread, two clients wait on jobs queued behind a long one; a third
 * ?wait is answered at once, 202 with its job still queued (never held on the HTTP thread), and
 * health answers at once meanwhile. Once a place is free again, ?wait waits again.
 */
import assert from 'node:assert/strict';
import test from 'node:test';

import { sleep, startServer, submit } from './lib.mjs';

/* runs for many minutes: only ever cancelled */
const LONG = { preset: 'n_link_pendulum', n: 64, duration: 600, integrator: { method: 'rk4', step: 0.0001 }, output: { interval: 0.1 } };
const SHORT = { preset: 'triple_pendulum_pd', duration: 0.05 };

let srv;
let longId;
const waiting = [];

test('the server starts with --max-waiters 2 and one HTTP thread', async () => {
    srv = await startServer({ workers: 1, args: ['--max-waiters', '2', '--http-threads', '1'] });
    longId = (await submit(srv, LONG)).id;
});

test('two clients wait on jobs queued behind a long one', async () => {
    for (let i = 0; i < 2; i++) {
        const t0 = Date.now();
        const p = srv.request('POST', '/api/jobs?wait=30', { json: SHORT, signal: AbortSignal.timeout(60000) });
        const early = await Promise.race([p.then(() => 'answered'), sleep(500).then(() => 'waiting')]);
        assert.equal(early, 'waiting', `waiter ${i} was answered after ${Date.now() - t0} ms`);
        waiting.push(p);
    }
});

test('a third ?wait is answered at once, 202 with the job queued', async () => {
    const t0 = Date.now();
    const res = await srv.request('POST', '/api/jobs?wait=30', { json: SHORT, signal: AbortSignal.timeout(10000) });
    const ms = Date.now() - t0;
    assert.equal(res.status, 202, res.text);
    assert.equal(res.json.status, 'queued');
    assert.equal(res.headers.location, `/api/jobs/${res.json.id}`);
    assert.ok(ms < 2000, `answered after ${ms} ms`);
});

test('health answers at once while the two wait', async () => {
    const t0 = Date.now();
    const h = await srv.get('/api/health', { signal: AbortSignal.timeout(10000) });
    assert.equal(h.status, 200);
    assert.equal(h.json.jobs.running, 1);
    assert.equal(h.json.jobs.queued, 3);
    assert.ok(Date.now() - t0 < 1000, `health after ${Date.now() - t0} ms`);
});

test('once the long job is cancelled the waiters get their jobs, 200 done', async () => {
    const del = await srv.request('DELETE', `/api/jobs/${longId}`);
    assert.equal(del.status, 202, del.text);
    for (const p of waiting) {
        const res = await p;
        assert.equal(res.status, 200, res.text);
        assert.equal(res.json.status, 'done');
    }
});

test('with the places free again, ?wait waits for the job', async () => {
    const res = await srv.request('POST', '/api/jobs?wait=30', { json: SHORT, signal: AbortSignal.timeout(60000) });
    assert.equal(res.status, 200, res.text);
    assert.equal(res.json.status, 'done');
});

test('the server stops', async () => {
    await srv.stop();
});
