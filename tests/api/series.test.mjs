/*
 * series.test.mjs - GET /api/jobs/{id}/series of a large job: streamed in bounded memory,
 * decimated on request (?every, ?max_points), at most --max-series-streams large replies at
 * once, and a job deleted or a server stopped while its series is being sent.
 *
 * The job: a 32-link pendulum, 10 s sampled every 1 ms with rk4 - 10001 samples of 227 columns,
 * a 39 MB JSON reply, made in a fraction of a second. Oracles, apart from the code under test:
 * the command line (`ctcsim run` writes the CSV, and the series inside --format json, through
 * result_out.c) for the bytes; the server's own /proc/PID/status (VmRSS sampled while the
 * replies are read, and VmHWM) for its memory; counting samples for max_points.
 */
import assert from 'node:assert/strict';
import { readFileSync } from 'node:fs';
import http from 'node:http';
import { after, before, test } from 'node:test';

import { cliCsv, runCli, startServer, tempDir, waitFor } from './lib.mjs';
import { writeFile } from 'node:fs/promises';
import path from 'node:path';

const BIG = {
    preset: 'n_link_pendulum',
    n: 32,
    duration: 10,
    output: { interval: 0.001 },
    integrator: { method: 'rk4', step: 0.001 },
};
const SAMPLES = 10001;
const MB = 1024 * 1024;

let srv;
let job; /* the finished big job */

before(async () => {
    srv = await startServer({ workers: 1 });
    const res = await srv.post('/api/jobs?wait=60', BIG);
    assert.equal(res.status, 200, res.text);
    assert.equal(res.json.status, 'done');
    assert.equal(res.json.metrics.samples, SAMPLES);
    job = res.json;
});

after(async () => {
    if (srv) await srv.stop();
});

/* the server's memory figures, kB */
function memory(server) {
    const text = readFileSync(`/proc/${server.proc.pid}/status`, 'utf8');
    const kb = (key) => Number(new RegExp(`^${key}:\\s+(\\d+) kB`, 'm').exec(text)[1]);
    return { rss: kb('VmRSS'), hwm: kb('VmHWM') };
}

/* Opens GET urlPath on a connection of its own and pauses it at its first bytes. Resolves
 * {status, headers, bytes() (received so far), resume(), destroy(), done (resolves {complete,
 * bytes} when the reply ends or breaks)}. */
function openPaused(server, urlPath) {
    return new Promise((resolve, reject) => {
        const req = http.get({ host: '127.0.0.1', port: server.port, path: urlPath, agent: false }, (res) => {
            let bytes = 0;
            const done = new Promise((end) => {
                res.on('data', (c) => {
                    bytes += c.length;
                });
                res.on('error', () => {});
                res.on('close', () => end({ complete: res.complete, bytes }));
            });
            res.once('data', () => {
                res.pause();
                resolve({
                    status: res.statusCode,
                    headers: res.headers,
                    bytes: () => bytes,
                    resume: () => res.resume(),
                    destroy: () => req.destroy(),
                    done,
                });
            });
        });
        req.on('error', (e) => reject(e));
    });
}

/* the CLI's series JSON for the job's spec, as the service sends it: the "series" member of
 * `ctcsim run --format json`, and a newline */
async function cliSeriesJson(spec, args = []) {
    const file = path.join(tempDir('ctcsim-series-'), 'job.json');
    await writeFile(file, JSON.stringify(spec));
    const r = await runCli(['run', file, '--quiet', '--format', 'json', ...args]);
    assert.equal(r.code, 0, r.stderr);
    const at = r.stdout.indexOf('"series":');
    assert.ok(at > 0 && r.stdout.endsWith('}\n'));
    return r.stdout.slice(at + '"series":'.length, -2) + '\n';
}

/* Starts a server whose memory measures what it holds: under AddressSanitizer (make check-asan)
 * freed memory waits in a quarantine of up to 256 MB before reuse, which would count every
 * allocation the replies ever made; a 1 MB quarantine keeps the measure to what is held. Other
 * builds ignore ASAN_OPTIONS. */
async function startMeasured() {
    const saved = process.env.ASAN_OPTIONS;
    process.env.ASAN_OPTIONS = `${saved ? `${saved}:` : ''}quarantine_size_mb=1`;
    try {
        return await startServer({ workers: 1 });
    } finally {
        if (saved === undefined) delete process.env.ASAN_OPTIONS;
        else process.env.ASAN_OPTIONS = saved;
    }
}

test('three concurrent reads of a 39 MB series grow the server by a few MB, not by the series', async (t) => {
    const lean = await startMeasured();
    t.after(() => lean.stop());
    const res = await lean.post('/api/jobs?wait=60', BIG);
    assert.equal(res.status, 200, res.text);
    const start = memory(lean);
    let peak = start.rss;
    const timer = setInterval(() => {
        peak = Math.max(peak, memory(lean).rss);
    }, 5);
    const replies = await Promise.all([0, 1, 2].map(() => lean.get(`/api/jobs/${res.json.id}/series`)));
    clearInterval(timer);
    const end = memory(lean);
    peak = Math.max(peak, end.rss);
    const grew = Math.max(peak - start.rss, end.hwm - start.hwm) / 1024;
    t.diagnostic(`the server grew by ${grew.toFixed(1)} MB (VmRSS ${start.rss} kB before, ${peak} kB at most)`);
    assert.ok(grew < 24, `the server grew by ${grew.toFixed(1)} MB reading 3 x ${(replies[0].text.length / MB).toFixed(1)} MB`);
    for (const r of replies) {
        assert.equal(r.status, 200);
        assert.equal(r.headers['transfer-encoding'], 'chunked', 'the reply is not streamed');
        assert.equal(r.headers['content-length'], undefined);
        assert.ok(r.text.length > 35 * MB, `${r.text.length} bytes`);
        assert.equal(r.text, replies[0].text);
    }
});

test('the streamed series equals the command line, byte for byte, in JSON and CSV', async () => {
    const json = await srv.get(`/api/jobs/${job.id}/series`);
    assert.ok(json.text === (await cliSeriesJson(job.spec)), 'the JSON differs from the CLI');
    const csv = await srv.get(`/api/jobs/${job.id}/series?format=csv`);
    assert.ok(csv.text === (await cliCsv(job.spec)), 'the CSV differs from the CLI');
    const some = await srv.get(`/api/jobs/${job.id}/series?format=csv&channels=qdot,energy&every=7&joints=0,31`);
    const cli = await cliCsv(job.spec, ['--channels', 'qdot,energy', '--every', '7']);
    /* the CLI has no coordinate filter: keep its t, qdot[0], qdot[31] and energy columns */
    const keep = [0, 1, 32, 33, 34];
    const picked = cli.split('\n').map((l) => (l ? keep.map((k) => l.split(',')[k]).join(',') : l)).join('\n');
    assert.ok(some.text === picked, 'the selected CSV differs from the CLI');
});

/* the samples kept with stride s of n: 0, s, 2s, ... and the last */
const kept = (n, s) => Math.floor((n - 1) / s) + 1 + ((n - 1) % s ? 1 : 0);

test('max_points keeps at most N samples, first and last included, and every K is kept with it', async () => {
    for (const n of [2, 3, 100, 5000, 10000, SAMPLES, 20000]) {
        const res = await srv.get(`/api/jobs/${job.id}/series?max_points=${n}&channels=energy`);
        assert.equal(res.status, 200, res.text);
        const t = res.json.t;
        assert.ok(t.length <= n, `max_points=${n}: ${t.length} samples`);
        assert.equal(t[0], 0);
        assert.equal(t[t.length - 1], 10);
        /* the smallest stride that fits: one less would keep more than n */
        const stride = Math.max(1, Math.ceil((SAMPLES - 1) / (n - 1)));
        assert.equal(t.length, kept(SAMPLES, stride), `max_points=${n}`);
        if (stride > 1) assert.ok(kept(SAMPLES, stride - 1) > n);
        /* the same samples as every=stride, and as the CLI's --every */
        const every = await srv.get(`/api/jobs/${job.id}/series?every=${stride}&channels=energy`);
        assert.equal(res.text, every.text, `max_points=${n} is not every=${stride}`);
    }
    const both = await srv.get(`/api/jobs/${job.id}/series?max_points=100&every=500&format=csv&channels=tau`);
    assert.ok(both.text === (await cliCsv(job.spec, ['--channels', 'tau', '--every', '500'])), 'every=500 wins over max_points=100');
    const few = await srv.get(`/api/jobs/${job.id}/series?max_points=100&every=3&format=csv&channels=tau`);
    assert.ok(few.text === (await cliCsv(job.spec, ['--channels', 'tau', '--every', '102'])), 'max_points=100 wins over every=3');
});

test('a bad max_points is 400 INVALID_QUERY naming the field', async () => {
    for (const bad of ['0', '1', '-5', 'abc', '1.5', '', '1e3', '1000000001']) {
        const res = await srv.get(`/api/jobs/${job.id}/series?max_points=${encodeURIComponent(bad)}`);
        assert.equal(res.status, 400, `max_points=${bad}: ${res.text}`);
        assert.equal(res.json.error.code, 'INVALID_QUERY');
        assert.equal(res.json.error.field, 'max_points');
        assert.equal(res.json.error.message, `max_points must be an integer from 2 to 1000000000 (got "${bad}")`);
    }
});

test('past --max-series-streams large reads: 503 TOO_MANY_STREAMS with Retry-After; small reads and health go on', async () => {
    const two = await startServer({ workers: 1, args: ['--max-series-streams', '2'] });
    try {
        const res = await two.post('/api/jobs?wait=60', BIG);
        assert.equal(res.status, 200, res.text);
        const url = `/api/jobs/${res.json.id}/series`;
        const a = await openPaused(two, url);
        const b = await openPaused(two, url);
        assert.equal(a.status, 200);
        assert.equal(b.status, 200);
        const third = await two.get(url);
        assert.equal(third.status, 503, third.text.slice(0, 200));
        assert.equal(third.json.error.code, 'TOO_MANY_STREAMS');
        assert.equal(third.json.error.field, '');
        assert.match(third.json.error.message, /^2 large series are being sent/);
        assert.ok(Number(third.headers['retry-after']) >= 1, JSON.stringify(third.headers));
        /* a decimated read is small: not counted */
        const small = await two.get(`${url}?max_points=1000&format=csv`);
        assert.equal(small.status, 200);
        assert.equal(small.text.split('\n').length - 2, kept(SAMPLES, Math.ceil((SAMPLES - 1) / 999)));
        const t0 = Date.now();
        assert.equal((await two.get('/api/health')).status, 200);
        assert.ok(Date.now() - t0 < 1000, `health took ${Date.now() - t0} ms`);
        /* a reader that goes away gives its place back */
        a.destroy();
        await a.done;
        const again = await waitFor(async () => {
            const r = await two.get(`${url}?format=csv`);
            return r.status === 200 ? r : null;
        }, { timeoutMs: 5000, what: () => 'a large read after one ended' });
        assert.equal(again.text.split('\n').length - 2, SAMPLES);
        b.resume();
        const rest = await b.done;
        assert.ok(rest.complete, 'the paused read did not finish once resumed');
    } finally {
        await two.stop();
    }
});

test('a job deleted while its series is being sent: the reply is cut short, the server goes on', async () => {
    const res = await srv.post('/api/jobs?wait=60', BIG);
    assert.equal(res.status, 200, res.text);
    const full = (await srv.get(`/api/jobs/${res.json.id}/series`)).text.length;
    const reader = await openPaused(srv, `/api/jobs/${res.json.id}/series`);
    assert.equal(reader.status, 200);
    const t0 = Date.now();
    const del = await srv.del(`/api/jobs/${res.json.id}`);
    assert.equal(del.status, 204, del.text);
    assert.ok(Date.now() - t0 < 2000, `the deletion took ${Date.now() - t0} ms`);
    reader.resume();
    const end = await reader.done;
    assert.equal(end.complete, false, 'the reply claims to be complete');
    assert.ok(end.bytes < full, `${end.bytes} of ${full} bytes arrived`);
    assert.equal((await srv.get(`/api/jobs/${res.json.id}/series`)).status, 404);
    assert.equal((await srv.get('/api/health')).status, 200);
    await waitFor(() => /series [a-z_]+ is gone while it was being sent/.test(srv.output()), {
        timeoutMs: 5000,
        what: () => 'the server to log the cut reply',
    });
    /* the other job's series is whole */
    const other = await srv.get(`/api/jobs/${job.id}/series?format=csv&max_points=50`);
    assert.equal(other.status, 200);
});

test('a server stopped while a series is being sent exits cleanly', async () => {
    const s = await startServer({ workers: 1 });
    const res = await s.post('/api/jobs?wait=60', BIG);
    assert.equal(res.status, 200, res.text);
    const reader = await openPaused(s, `/api/jobs/${res.json.id}/series?format=csv`);
    assert.equal(reader.status, 200);
    const stopped = await s.stop('SIGTERM', 15000);
    assert.equal(stopped.killed, undefined, 'it had to be killed');
    assert.equal(stopped.code, 0, s.output());
    reader.resume();
    const end = await reader.done;
    assert.equal(end.complete, false);
});
