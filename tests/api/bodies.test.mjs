/*
 * bodies.test.mjs - large bodies are parsed off the HTTP threads (issue 25, defect 11): with one
 * HTTP thread, health answers at once while four 5.6 MB bodies are parsed. A body of more than
 * 64 KiB takes one of the places of --max-waiters (and of --max-waiters-per-client) while it is
 * parsed: with every place taken it is answered at once, 503 BUSY (429 TOO_MANY_REQUESTS past the
 * client's own), with Retry-After, while small bodies are still parsed at once; with a place free,
 * a large POST /api/jobs?wait and a large POST /api/validate are answered as small ones are.
 */
import assert from 'node:assert/strict';
import http from 'node:http';
import test from 'node:test';

import { sleep, startServer } from './lib.mjs';

/* runs for many minutes: only ever cancelled */
const LONG = { preset: 'n_link_pendulum', n: 64, duration: 600, integrator: { method: 'rk4', step: 0.0001 }, output: { interval: 0.1 } };
const SHORT = { preset: 'triple_pendulum_pd', duration: 0.05 };
/* the short job padded with white space past 64 KiB */
const LARGE = `{"preset": "triple_pendulum_pd", "duration": 0.05${' '.repeat(70000)}}`;

/* A POST of text from a given local address. Resolves {status, headers, json, text}. */
function postFrom(from, port, urlPath, text) {
    return new Promise((resolve, reject) => {
        const headers = { 'content-type': 'application/json', 'content-length': Buffer.byteLength(text) };
        const req = http.request({ host: '127.0.0.1', port, method: 'POST', path: urlPath, headers, localAddress: from, agent: false }, (res) => {
            const chunks = [];
            res.on('data', (c) => chunks.push(c));
            res.on('end', () => {
                const body = Buffer.concat(chunks).toString('utf8');
                let json;
                try {
                    json = JSON.parse(body);
                } catch {
                    json = undefined;
                }
                resolve({ status: res.statusCode, headers: res.headers, json, text: body });
            });
        });
        req.on('error', reject);
        req.end(text);
    });
}

test('health answers at once while four 5.6 MB bodies are parsed (one HTTP thread)', async () => {
    const srv = await startServer({ workers: 1, args: ['--http-threads', '1'] });
    try {
        const big = `{"preset": "triple_pendulum_pd", "scene": {"q0": [${Array(700000).fill('0.12345').join(',')}]}}`;
        const posts = [];
        for (let i = 0; i < 4; i++) posts.push(srv.request('POST', '/api/jobs', { body: big, headers: { 'content-type': 'application/json' }, signal: AbortSignal.timeout(60000) }));
        await sleep(150);
        let worst = 0;
        for (let i = 0; i < 5; i++) {
            const t0 = Date.now();
            const h = await srv.get('/api/health', { signal: AbortSignal.timeout(20000) });
            assert.equal(h.status, 200);
            worst = Math.max(worst, Date.now() - t0);
            await sleep(50);
        }
        for (const p of posts) {
            const res = await p;
            assert.equal(res.status, 400, res.text);
            assert.equal(res.json.error.field, 'scene.q0');
        }
        assert.ok(worst < 500, `health took ${worst} ms while the bodies were parsed`);
    } finally {
        await srv.stop();
    }
});

test('with every place taken a large body is 503 BUSY at once, a small one still parsed', async () => {
    const srv = await startServer({ workers: 1, args: ['--max-waiters', '1'] });
    try {
        const long = await srv.post('/api/jobs', LONG);
        assert.equal(long.status, 202, long.text);
        const waiter = srv.request('POST', '/api/jobs?wait=30', { json: SHORT, signal: AbortSignal.timeout(60000) });
        assert.equal(await Promise.race([waiter.then(() => 'answered'), sleep(500).then(() => 'waiting')]), 'waiting');

        for (const urlPath of ['/api/jobs', '/api/validate']) {
            const t0 = Date.now();
            const res = await postFrom('127.0.0.1', srv.port, urlPath, LARGE);
            assert.equal(res.status, 503, res.text);
            assert.equal(res.headers['retry-after'], '5');
            assert.deepEqual(res.json.error, {
                code: 'BUSY',
                message: 'every place for a body of more than 65536 bytes is taken (--max-waiters); try again in a few seconds',
                field: '',
            });
            assert.ok(Date.now() - t0 < 2000);
        }
        assert.equal((await srv.post('/api/validate', SHORT)).status, 200, 'a small body is parsed at once');

        /* the place free again, a large ?wait waits for its job, a large validate validates */
        assert.equal((await srv.request('DELETE', `/api/jobs/${long.json.id}`)).status, 202);
        assert.equal((await waiter).status, 200);
        const done = await postFrom('127.0.0.1', srv.port, '/api/jobs?wait=30', LARGE);
        assert.equal(done.status, 200, done.text);
        assert.equal(done.json.status, 'done');
        const valid = await postFrom('127.0.0.1', srv.port, '/api/validate', LARGE);
        assert.equal(valid.status, 200, valid.text);
        assert.equal(valid.json.valid, true);
    } finally {
        await srv.stop();
    }
});

test('past the client\'s own places a large body is 429 TOO_MANY_REQUESTS; another address passes', async () => {
    const srv = await startServer({ workers: 1, args: ['--max-waiters-per-client', '1'] });
    try {
        const long = await postFrom('127.0.0.2', srv.port, '/api/jobs', JSON.stringify(LONG));
        assert.equal(long.status, 202, long.text);
        const waiter = postFrom('127.0.0.1', srv.port, '/api/jobs?wait=30', JSON.stringify(SHORT));
        assert.equal(await Promise.race([waiter.then(() => 'answered'), sleep(500).then(() => 'waiting')]), 'waiting');

        const res = await postFrom('127.0.0.1', srv.port, '/api/validate', LARGE);
        assert.equal(res.status, 429, res.text);
        assert.equal(res.headers['retry-after'], '5');
        assert.deepEqual(res.json.error, {
            code: 'TOO_MANY_REQUESTS',
            message: 'this client (127.0.0.1) has as many requests being answered off the HTTP threads as it may (--max-waiters-per-client); try again in a few seconds',
            field: '',
        });
        assert.equal((await postFrom('127.0.0.2', srv.port, '/api/validate', LARGE)).status, 200);
        await srv.request('DELETE', `/api/jobs/${long.json.id}`);
        assert.equal((await waiter).status, 200);
    } finally {
        await srv.stop();
    }
});
