/*
 * compression.test.mjs - replies in gzip (server/http_gzip.h) on the wire: node:http sends only
 * the headers given and hands back the raw bytes, which node:zlib inflates. A reply built in
 * memory (JSON, CSV) of 1 KiB or more, and a streamed series as JSON or CSV, goes in gzip to a
 * client whose Accept-Encoding admits it, and inflates to the very bytes a client that names no
 * coding gets; every such reply says "Vary: Accept-Encoding". Small replies, errors among them,
 * clients that refuse gzip (q=0) or name other codings only, and binary series (float32) are
 * sent as they are. fetch() names gzip itself, so every other test of this suite reads gzip
 * replies too.
 */
import assert from 'node:assert/strict';
import http from 'node:http';
import test from 'node:test';
import { gunzipSync } from 'node:zlib';

import { startServer, waitFor } from './lib.mjs';

let srv;
let familyId;
let jobId;

/* GET (or method) rawPath with exactly these headers; resolves {status, headers, body (Buffer)} */
function fetchRaw(port, rawPath, headers = {}, method = 'GET') {
    return new Promise((resolve, reject) => {
        const req = http.request({ host: '127.0.0.1', port, method, path: rawPath, headers, agent: false }, (res) => {
            const chunks = [];
            res.on('data', (c) => chunks.push(c));
            res.on('error', reject);
            res.on('end', () => resolve({ status: res.statusCode, headers: res.headers, body: Buffer.concat(chunks) }));
        });
        req.on('error', reject);
        req.end();
    });
}

test('the server starts and runs a family of 40 members', async () => {
    srv = await startServer({ workers: 2 });
    const res = await srv.post('/api/families', {
        base: { preset: 'triple_pendulum_pd', duration: 0.01 },
        axes: [{ path: 'controller.kp', logspace: [1, 3, 40] }],
    });
    assert.equal(res.status, 202, res.text);
    familyId = res.json.id;
    jobId = res.json.first_job;
    await waitFor(async () => {
        const f = (await srv.get(`/api/families/${familyId}`)).json;
        return f.counts.queued + f.counts.running === 0;
    }, { timeoutMs: 60000, what: 'the family to finish' });
});

test('a large JSON or CSV reply goes in gzip to a client that accepts it, and inflates to the plain reply', async () => {
    for (const path of [`/api/families/${familyId}`, `/api/families/${familyId}?format=csv`, '/api/jobs?limit=40', `/api/jobs/${jobId}`]) {
        const plain = await fetchRaw(srv.port, path);
        assert.equal(plain.status, 200, path);
        assert.equal(plain.headers['content-encoding'], undefined, path);
        assert.equal(plain.headers.vary, 'Accept-Encoding', path);
        assert.ok(plain.body.length >= 1024, `${path}: ${plain.body.length} bytes`);
        for (const accept of ['gzip', 'gzip, deflate, br', 'br;q=1, gzip;q=0.5', 'x-gzip', '*', 'GZIP']) {
            const gz = await fetchRaw(srv.port, path, { 'accept-encoding': accept });
            assert.equal(gz.status, 200, `${path}, ${accept}`);
            assert.equal(gz.headers['content-encoding'], 'gzip', `${path}, ${accept}`);
            assert.equal(gz.headers.vary, 'Accept-Encoding', `${path}, ${accept}`);
            assert.equal(gz.headers['content-type'], plain.headers['content-type'], `${path}, ${accept}`);
            assert.equal(Number(gz.headers['content-length']), gz.body.length, `${path}, ${accept}`);
            assert.ok(gz.body.length < plain.body.length, `${path}: ${gz.body.length} of ${plain.body.length} bytes`);
            const inflated = gunzipSync(gz.body);
            /* the timing columns of a job row do not change between two reads of a finished job */
            assert.ok(inflated.equals(plain.body), `${path}, ${accept}: inflates to other bytes`);
        }
    }
    /* the family table, the reply a family's page polls: several times smaller */
    const table = await fetchRaw(srv.port, `/api/families/${familyId}`, { 'accept-encoding': 'gzip' });
    const plain = await fetchRaw(srv.port, `/api/families/${familyId}`);
    assert.ok(table.body.length * 3 < plain.body.length, `${table.body.length} of ${plain.body.length} bytes`);
});

test('HEAD says what GET would send', async () => {
    const path = `/api/families/${familyId}`;
    const get = await fetchRaw(srv.port, path, { 'accept-encoding': 'gzip' });
    const head = await fetchRaw(srv.port, path, { 'accept-encoding': 'gzip' }, 'HEAD');
    assert.equal(head.status, 200);
    assert.equal(head.body.length, 0);
    assert.equal(head.headers['content-encoding'], 'gzip');
    assert.equal(head.headers['content-length'], get.headers['content-length']);
});

test('a streamed series as JSON or CSV goes in gzip too, and inflates to the plain stream', async () => {
    for (const query of ['format=json', 'format=csv', 'format=csv&channels=q,tau&every=2', 'format=json&max_points=7']) {
        const path = `/api/jobs/${jobId}/series?${query}`;
        const plain = await fetchRaw(srv.port, path);
        assert.equal(plain.status, 200, path);
        assert.equal(plain.headers['content-encoding'], undefined, path);
        assert.equal(plain.headers['content-length'], undefined, `${path}: streamed`);
        assert.equal(plain.headers.vary, 'Accept-Encoding', path);
        const gz = await fetchRaw(srv.port, path, { 'accept-encoding': 'gzip' });
        assert.equal(gz.status, 200, path);
        assert.equal(gz.headers['content-encoding'], 'gzip', path);
        assert.equal(gz.headers['content-length'], undefined, `${path}: streamed`);
        assert.ok(gunzipSync(gz.body).equals(plain.body), `${path}: inflates to other bytes`);
    }
});

test('sent as they are: refused or unnamed gzip, small replies, errors, binary series', async () => {
    const path = `/api/families/${familyId}`;
    for (const accept of ['gzip;q=0', 'gzip;q=0.000, br', 'identity', 'br', 'deflate', '*;q=0', '']) {
        const r = await fetchRaw(srv.port, path, { 'accept-encoding': accept });
        assert.equal(r.status, 200, accept);
        assert.equal(r.headers['content-encoding'], undefined, `"${accept}"`);
        JSON.parse(r.body.toString('utf8'));
    }
    const health = await fetchRaw(srv.port, '/api/health', { 'accept-encoding': 'gzip' });
    assert.equal(health.status, 200);
    assert.ok(health.body.length < 1024);
    assert.equal(health.headers['content-encoding'], undefined);
    assert.equal(JSON.parse(health.body.toString('utf8')).status, 'ok');
    const missing = await fetchRaw(srv.port, '/api/jobs/999999', { 'accept-encoding': 'gzip' });
    assert.equal(missing.status, 404);
    assert.equal(missing.headers['content-encoding'], undefined);
    assert.equal(JSON.parse(missing.body.toString('utf8')).error.code, 'NOT_FOUND');
    const path32 = `/api/jobs/${jobId}/series?format=f32`;
    const f32 = await fetchRaw(srv.port, path32, { 'accept-encoding': 'gzip' });
    assert.equal(f32.status, 200);
    assert.equal(f32.headers['content-encoding'], undefined);
    assert.equal(f32.headers.vary, undefined);
    assert.ok(f32.body.equals((await fetchRaw(srv.port, path32)).body));
});

test('fetch() reads the gzip replies as the plain ones', async () => {
    const viaFetch = await srv.get(`/api/families/${familyId}`);
    assert.equal(viaFetch.headers['content-encoding'], 'gzip');
    const plain = await fetchRaw(srv.port, `/api/families/${familyId}`);
    assert.equal(viaFetch.text, plain.body.toString('utf8'));
});

test('the server stops cleanly', async () => {
    const r = await srv.stop();
    assert.equal(r.code, 0, srv.output());
});
