/*
 * hostile.test.mjs - the service against requests made to stall or fool it (issue 25): a preset
 * request of 100k keys is answered at once (the merge is linear, not quadratic).
 */
import assert from 'node:assert/strict';
import test from 'node:test';

import { startServer } from './lib.mjs';

let srv;

test('the server starts', async () => {
    srv = await startServer({ workers: 1 });
});

test('a preset request with 100k keys is answered in well under 5 s (linear merge)', async () => {
    /* 1.5 MB: {"preset":"triple_pendulum_pd","x0":0,...,"x99999":0}; the quadratic merge took
       about 70 s for this */
    const keys = [];
    for (let i = 0; i < 100000; i++) keys.push(`"x${i}":0`);
    const body = `{"preset":"triple_pendulum_pd",${keys.join(',')}}`;
    const t0 = Date.now();
    const res = await srv.request('POST', '/api/jobs', {
        body,
        headers: { 'content-type': 'application/json' },
        signal: AbortSignal.timeout(20000),
    });
    const ms = Date.now() - t0;
    assert.equal(res.status, 400, res.text);
    assert.equal(res.json.error.code, 'UNKNOWN_FIELD');
    assert.ok(ms < 5000, `answered in ${ms} ms`);
    const h = await srv.get('/api/health');
    assert.equal(h.status, 200);
});

test('the server stops cleanly', async () => {
    const r = await srv.stop();
    assert.equal(r.code, 0, srv.output());
});
