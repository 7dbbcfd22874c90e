/*
 * quotas.test.mjs - per-client limits (issue 25, defects 5 and 12): one client address may hold
 * --max-jobs-per-client jobs queued or running, and past them POST /api/jobs answers 429
 * TOO_MANY_JOBS with Retry-After, whatever the queue's room; a job cancelled or finished gives its
 * place back. One address may have --max-waiters-per-client ?wait replies waiting; past them a
 * ?wait is answered at once, 202. Another address keeps its own count: the requests come from
 * 127.0.0.1 and 127.0.0.2 (both loopback on Linux; the server counts loopback like any other).
 */
import assert from 'node:assert/strict';
import http from 'node:http';
import test from 'node:test';

import { sleep, startServer } from './lib.mjs';

/* runs for many minutes: only ever cancelled */
const LONG = { preset: 'n_link_pendulum', n: 64, duration: 600, integrator: { method: 'rk4', step: 0.0001 }, output: { interval: 0.1 } };
const SHORT = { preset: 'triple_pendulum_pd', duration: 0.05 };

/* POST or DELETE from a given local address. Resolves {status, headers, json, text}. */
function requestFrom(from, port, method, urlPath, body) {
    return new Promise((resolve, reject) => {
        const data = body === undefined ? undefined : JSON.stringify(body);
        const headers = data === undefined ? {} : { 'content-type': 'application/json', 'content-length': Buffer.byteLength(data) };
        const req = http.request({ host: '127.0.0.1', port, method, path: urlPath, headers, localAddress: from, agent: false }, (res) => {
            const chunks = [];
            res.on('data', (c) => chunks.push(c));
            res.on('end', () => {
                const text = Buffer.concat(chunks).toString('utf8');
                let json;
                try {
                    json = JSON.parse(text);
                } catch {
                    json = undefined;
                }
                resolve({ status: res.statusCode, headers: res.headers, json, text });
            });
        });
        req.on('error', reject);
        req.end(data);
    });
}

let srv;
const A = '127.0.0.1';
const B = '127.0.0.2';

test('the server starts with --max-jobs-per-client 2 --max-waiters-per-client 1', async () => {
    srv = await startServer({ workers: 1, args: ['--max-jobs-per-client', '2', '--max-waiters-per-client', '1', '--max-queue', '100'] });
});

test('a client with 2 jobs queued or running gets 429 TOO_MANY_JOBS with Retry-After', async () => {
    const running = await requestFrom(A, srv.port, 'POST', '/api/jobs', LONG);
    const queued = await requestFrom(A, srv.port, 'POST', '/api/jobs', SHORT);
    assert.equal(running.status, 202, running.text);
    assert.equal(queued.status, 202, queued.text);
    const third = await requestFrom(A, srv.port, 'POST', '/api/jobs', SHORT);
    assert.equal(third.status, 429, third.text);
    assert.equal(third.headers['retry-after'], '5');
    assert.deepEqual(third.json.error, {
        code: 'TOO_MANY_JOBS',
        message: 'this client (127.0.0.1) has 2 jobs queued or running, the most one client may have (--max-jobs-per-client); try again once one has finished',
        field: '',
    });
    /* nothing was stored for it */
    const h = await srv.get('/api/health');
    assert.equal(h.json.jobs.queued + h.json.jobs.running, 2);

    /* another address has its own count */
    const other = await requestFrom(B, srv.port, 'POST', '/api/jobs', SHORT);
    assert.equal(other.status, 202, other.text);

    /* a queued job cancelled gives its place back at once */
    const del = await requestFrom(A, srv.port, 'DELETE', `/api/jobs/${queued.json.id}`);
    assert.equal(del.status, 200, del.text);
    const again = await requestFrom(A, srv.port, 'POST', '/api/jobs', SHORT);
    assert.equal(again.status, 202, again.text);
    assert.equal((await requestFrom(A, srv.port, 'POST', '/api/jobs', SHORT)).status, 429);

    /* the running one cancelled: its place comes back once its worker has stopped it, and the
       queued ones then finish and give theirs back too */
    assert.equal((await requestFrom(A, srv.port, 'DELETE', `/api/jobs/${running.json.id}`)).status, 202);
    let res;
    for (let i = 0; i < 100; i++) {
        res = await requestFrom(A, srv.port, 'POST', '/api/jobs?wait=30', SHORT);
        if (res.status !== 429) break;
        await sleep(100);
    }
    assert.equal(res.status, 200, res.text);
    assert.equal(res.json.status, 'done');
    /* finished jobs hold no place: two more fit */
    for (let i = 0; i < 2; i++) assert.equal((await requestFrom(A, srv.port, 'POST', '/api/jobs?wait=30', SHORT)).status, 200);
});

test('a second ?wait from one address is answered at once, 202; another address still waits', async () => {
    const long = await requestFrom(B, srv.port, 'POST', '/api/jobs', LONG);
    assert.equal(long.status, 202, long.text);
    const first = requestFrom(A, srv.port, 'POST', '/api/jobs?wait=30', SHORT);
    assert.equal(await Promise.race([first.then(() => 'answered'), sleep(500).then(() => 'waiting')]), 'waiting');

    const t0 = Date.now();
    const second = await requestFrom(A, srv.port, 'POST', '/api/jobs?wait=30', SHORT);
    assert.equal(second.status, 202, second.text);
    assert.equal(second.json.status, 'queued');
    assert.ok(Date.now() - t0 < 2000, `answered after ${Date.now() - t0} ms`);

    const other = requestFrom(B, srv.port, 'POST', '/api/jobs?wait=30', SHORT);
    assert.equal(await Promise.race([other.then(() => 'answered'), sleep(500).then(() => 'waiting')]), 'waiting');

    /* the long job cancelled, the waiters get their jobs done */
    assert.equal((await requestFrom(B, srv.port, 'DELETE', `/api/jobs/${long.json.id}`)).status, 202);
    for (const p of [first, other]) {
        const res = await p;
        assert.equal(res.status, 200, res.text);
        assert.equal(res.json.status, 'done');
    }
});

test('the server stops', async () => {
    await srv.stop();
});
