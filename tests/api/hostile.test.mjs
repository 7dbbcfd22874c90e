/*
 * hostile.test.mjs - the service against requests made to stall or fool it (issue 25): a preset
 * request of 100k keys is answered at once (the merge is linear, not quadratic); one address cannot
 * hold more connections than --max-connections-per-ip, and silent ones are closed after
 * --idle-timeout; a Host the server does not answer for is refused (DNS rebinding), and an
 * HTTP/1.1 request without Host too; the token can come from a file (--token-file) rather than a
 * flag that ps shows.
 */
import assert from 'node:assert/strict';
import { spawnSync } from 'node:child_process';
import { chmodSync, writeFileSync } from 'node:fs';
import http from 'node:http';
import net from 'node:net';
import path from 'node:path';
import test from 'node:test';

import { SERVER, sleep, startServer, tempDir } from './lib.mjs';

let srv;

test('the server starts', async () => {
    srv = await startServer({ workers: 1 });
});

test('a preset request with 100k keys is answered in well under 5 s (linear merge)', async () => {
    /* 1.5 MB: {"preset":"triple_pendulum_pd","x0":0,...,"x99999":0}; a merge that scans the
       target for each key takes about 70 s on it */
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

/* ---- the Host check (defect 13, DNS rebinding) ---- */

/* GET path with the given Host header, or none at all (host null). Resolves {status, json}. */
function getWithHost(port, path, host) {
    return new Promise((resolve, reject) => {
        const headers = host === null ? {} : { host };
        const req = http.request({ host: '127.0.0.1', port, path, headers, setHost: false, agent: false }, (res) => {
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
                resolve({ status: res.statusCode, json, text });
            });
        });
        req.on('error', reject);
        req.end();
    });
}

test('Host: the default allows the bind address, localhost, 127.0.0.1 and [::1] only', async () => {
    const p = srv.port;
    for (const host of [`127.0.0.1:${p}`, '127.0.0.1', `localhost:${p}`, 'LocalHost', 'localhost.', `[::1]:${p}`]) {
        const r = await getWithHost(p, '/api/health', host);
        assert.equal(r.status, 200, `Host: ${host}: ${r.text}`);
    }
    for (const host of [`evil.example:${p}`, 'evil.example', 'localhost.evil.example', '127.0.0.2', `[::2]:${p}`, 'localhostx']) {
        const r = await getWithHost(p, '/api/health', host);
        assert.equal(r.status, 421, `Host: ${host}: ${r.text}`);
        assert.equal(r.json.error.code, 'HOST_NOT_ALLOWED');
        assert.equal(r.json.error.field, '');
        assert.match(r.json.error.message, /^this server does not answer for host ".*" \(--allowed-hosts\)$/);
    }
    /* a page fetched from the rebinding host gets nothing either, nor may it post */
    const page = await getWithHost(p, '/', 'evil.example');
    assert.equal(page.status, 421);
});

test('Host: an HTTP/1.1 request without one is 400 MISSING_HOST', async () => {
    const r = await getWithHost(srv.port, '/api/health', null);
    assert.equal(r.status, 400, r.text);
    assert.deepEqual(r.json.error, { code: 'MISSING_HOST', message: 'an HTTP/1.1 request needs a Host header', field: '' });
});

test('--allowed-hosts replaces the default (names trimmed, bare IPv6 bracketed); * allows any', async () => {
    const named = await startServer({ workers: 1, args: ['--allowed-hosts', ' ctcsim.example , 127.0.0.1,::1'] });
    try {
        assert.equal((await getWithHost(named.port, '/api/health', `ctcsim.example:${named.port}`)).status, 200);
        assert.equal((await getWithHost(named.port, '/api/health', `[::1]:${named.port}`)).status, 200);
        assert.equal((await getWithHost(named.port, '/api/health', `localhost:${named.port}`)).status, 421);
    } finally {
        await named.stop();
    }
    const any = await startServer({ workers: 1, args: ['--allowed-hosts', '*'] });
    try {
        assert.equal((await getWithHost(any.port, '/api/health', 'evil.example')).status, 200);
    } finally {
        await any.stop();
    }
});

/* ---- the token from a file (defect 14: a --token flag shows in ps) ---- */

test('--token-file: the file\'s line is the token, its line end stripped', async () => {
    const dir = tempDir();
    const file = path.join(dir, 'token');
    writeFileSync(file, 's3cret\r\n', { mode: 0o600 });
    const t = await startServer({ workers: 1, args: ['--token-file', file] });
    try {
        const job = { preset: 'triple_pendulum_pd', duration: 0.1 };
        assert.equal((await t.post('/api/validate', job)).status, 401);
        assert.equal((await t.post('/api/validate', job, { authorization: 'Bearer s3cre' })).status, 401);
        assert.equal((await t.post('/api/validate', job, { authorization: 'Bearer s3cret' })).status, 200);
        assert.doesNotMatch(t.output(), /warning/);
    } finally {
        await t.stop();
    }
});

test('--token-file and CTCSIM_TOKEN_FILE: empty, missing, two lines or with --token stop the start', () => {
    const dir = tempDir();
    const empty = path.join(dir, 'empty');
    writeFileSync(empty, '\n', { mode: 0o600 });
    const twoLines = path.join(dir, 'two');
    writeFileSync(twoLines, 'a\nb\n', { mode: 0o600 });
    const ok = path.join(dir, 'ok');
    writeFileSync(ok, 'x\n', { mode: 0o600 });
    const db = ['--db', path.join(dir, 'jobs.db'), '--port', '0'];
    const cases = [
        { args: ['--token-file', empty], stderr: `ctcsim-server: --token-file ${empty} is empty\n` },
        { args: [], env: { CTCSIM_TOKEN_FILE: empty }, stderr: `ctcsim-server: --token-file ${empty} is empty\n` },
        { args: ['--token-file', path.join(dir, 'none')], stderr: `ctcsim-server: --token-file ${path.join(dir, 'none')}: No such file or directory\n` },
        { args: ['--token-file', twoLines], stderr: `ctcsim-server: --token-file ${twoLines} must hold one line of text\n` },
        { args: ['--token-file', ok, '--token', 'y'], stderr: 'ctcsim-server: give the token once: --token or --token-file, not both\n' },
    ];
    for (const c of cases) {
        const env = { ...process.env, ...(c.env || {}) };
        for (const k of Object.keys(process.env)) if (k.startsWith('CTCSIM') && !(c.env && k in c.env)) delete env[k];
        const r = spawnSync(SERVER, [...db, ...c.args], { encoding: 'utf8', env, timeout: 10000 });
        assert.equal(r.status, 2, `${c.args.join(' ')}: exit ${r.status}, ${r.stderr}`);
        assert.equal(r.stderr, c.stderr);
    }
});

test('--token-file: a file other users may read is used, with a warning', async () => {
    const dir = tempDir();
    const file = path.join(dir, 'token');
    writeFileSync(file, 'open\n');
    chmodSync(file, 0o644);
    const t = await startServer({ workers: 1, args: ['--token-file', file] });
    try {
        assert.match(t.output(), new RegExp(`warning: --token-file ${file} can be read by other users \\(chmod 600 it\\)`));
        const job = { preset: 'triple_pendulum_pd', duration: 0.1 };
        assert.equal((await t.post('/api/validate', job, { authorization: 'Bearer open' })).status, 200);
    } finally {
        await t.stop();
    }
});

test('the server stops cleanly', async () => {
    const r = await srv.stop();
    assert.equal(r.code, 0, srv.output());
});
