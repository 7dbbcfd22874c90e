/*
 * hostile.test.mjs - the service against requests made to stall or fool it (issue 25): a preset
 * request of 100k keys is answered at once (the merge is linear, not quadratic); one address cannot
 * hold more connections than --max-connections-per-ip, and silent ones are closed after
 * --idle-timeout.
 */
import assert from 'node:assert/strict';
import net from 'node:net';
import test from 'node:test';

import { sleep, startServer } from './lib.mjs';

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

/* ---- connection limits (defect 3, slowloris) ---- */

/* A TCP connection that sends nothing. Resolves once connected, to {sock, closed (a promise of
 * the ms from connect to the server's close), isClosed()}. */
function idleConnection(port) {
    return new Promise((resolve, reject) => {
        const sock = net.connect(port, '127.0.0.1');
        let closedAt = null;
        sock.on('error', () => {}); /* a reset counts as closed */
        sock.once('connect', () => {
            const t0 = Date.now();
            const closed = new Promise((r) => sock.once('close', () => r((closedAt = Date.now()) - t0)));
            resolve({ sock, closed, isClosed: () => closedAt !== null });
        });
        sock.once('error', reject);
    });
}

test('per-IP limit and idle timeout: the 5th idle connection is closed, the 4 time out', async () => {
    const IDLE_S = 2;
    const lim = await startServer({ workers: 1, args: ['--max-connections-per-ip', '4', '--idle-timeout', String(IDLE_S)] });
    try {
        /* the health checks of the start-up left keep-alive connections: let them time out */
        await sleep(IDLE_S * 1000 + 1000);
        const idle = [];
        for (let i = 0; i < 4; i++) idle.push(await idleConnection(lim.port));
        const fifth = await idleConnection(lim.port);
        const fifthMs = await Promise.race([fifth.closed, sleep(1500).then(() => null)]);
        assert.ok(fifthMs !== null && fifthMs < 1500, 'the 5th connection from one address was not closed');
        assert.ok(idle.every((c) => !c.isClosed()), 'the first 4 were closed along with the 5th');
        /* the 4 are closed once silent for the idle timeout, and then the service answers */
        const ms = await Promise.race([Promise.all(idle.map((c) => c.closed)), sleep(IDLE_S * 1000 + 3000).then(() => null)]);
        assert.ok(ms !== null, `the idle connections were still open after ${IDLE_S + 3} s`);
        for (const t of ms) assert.ok(t >= IDLE_S * 1000 - 200, `an idle connection closed after ${t} ms, before the timeout`);
        const h = await lim.get('/api/health');
        assert.equal(h.status, 200);
    } finally {
        const r = await lim.stop();
        assert.equal(r.code, 0, lim.output());
    }
});
