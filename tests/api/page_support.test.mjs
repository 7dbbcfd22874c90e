/*
 * page_support.test.mjs - what the job page needs from the API for large, running and failed
 * jobs: the series as float32 (?format=f32) equal to the JSON's numbers rounded to float32, and
 * with ?reduce=minmax the extremes of each bucket checked against a scan of the full JSON;
 * POST /api/jobs/{id}/cancel, which cancels a running or queued job and leaves a finished one
 * alone (409, never a deletion); queue_position and ?brief=1 on GET /api/jobs/{id}; a running
 * job's samples so far (?partial=1), only the new ones with ?from=; and an RK4 step cut to the
 * output interval reported as metrics.step_cut.
 */
import assert from 'node:assert/strict';
import test from 'node:test';

import { BACKEND, startServer, submit, waitFor, waitJob } from './lib.mjs';

/* on PostgreSQL each server is an API process without workers beside two worker processes
   (lib.mjs): a running job's samples so far are in a worker's memory, which the API process
   cannot read; it says so instead (the next test) */
const PG_CLUSTER = BACKEND === 'postgres' && 'the API process of the PostgreSQL cluster runs no job, so it has no live samples (checked below)';

/* runs for many minutes: only ever cancelled */
const LONG = { preset: 'n_link_pendulum', n: 64, duration: 600, integrator: { method: 'rk4', step: 0.0001 }, output: { interval: 0.1 } };
const running = (j) => j.status === 'running' && j.progress > 0;

let srv;
let small;

/* the f32 body as {head, channels: {name: [[row values]...]}} (rows of columns) */
function decode(buf) {
    const view = new DataView(buf.buffer, buf.byteOffset, buf.byteLength);
    const h = view.getUint32(0, true);
    assert.equal((4 + h) % 4, 0, 'the values start at a multiple of 4');
    const head = JSON.parse(Buffer.from(buf.subarray(4, 4 + h)).toString('utf8'));
    let at = 4 + h;
    const channels = {};
    for (const [name, width] of head.channels) {
        const rows = [];
        for (let r = 0; r < head.rows; r++) {
            const row = [];
            for (let c = 0; c < width; c++, at += 4) row.push(view.getFloat32(at, true));
            rows.push(row);
        }
        channels[name] = rows;
    }
    assert.equal(at, buf.byteLength, 'no bytes after the last channel');
    return { head, channels };
}

async function getBinary(path) {
    const res = await fetch(srv.base + path);
    return { status: res.status, type: res.headers.get('content-type'), buf: new Uint8Array(await res.arrayBuffer()) };
}

test('the server starts; a small job runs', async () => {
    srv = await startServer({ workers: 2 });
    const res = await srv.post('/api/jobs?wait=60', { preset: 'triple_pendulum_pid', duration: 2 });
    assert.equal(res.status, 200, res.text);
    small = res.json;
    assert.equal((await srv.get(`/api/jobs/${small.id}`)).json.queue_position, null, "a finished job has no queue position");
});

test('format=f32 holds the JSON numbers as float32, same rows and columns', async () => {
    const q = `channels=q,e,energy&joints=0,2&max_points=50`;
    const json = (await srv.get(`/api/jobs/${small.id}/series?${q}`)).json;
    const bin = await getBinary(`/api/jobs/${small.id}/series?${q}&format=f32`);
    assert.equal(bin.status, 200);
    assert.equal(bin.type, 'application/octet-stream');
    const { head, channels } = decode(bin.buf);
    assert.equal(head.reduce, 'stride');
    assert.equal(head.rows, json.t.length);
    assert.deepEqual(head.channels.map(([n]) => n), ['t', 'q', 'e', 'energy']);
    for (const name of ['q', 'e', 'energy']) {
        assert.equal(channels[name][0].length, json[name].length, `${name} columns`);
        json[name].forEach((col, c) =>
            col.forEach((x, r) => assert.equal(channels[name][r][c], Math.fround(x), `${name}[${c}] row ${r}`)),
        );
    }
    json.t.forEach((x, r) => assert.equal(channels.t[r][0], Math.fround(x)));
});

test('reduce=minmax: two rows per bucket, each column\'s min and max over it, at most max_points rows', async () => {
    const all = (await srv.get(`/api/jobs/${small.id}/series?channels=tau`)).json;
    const n = all.t.length;
    const bin = await getBinary(`/api/jobs/${small.id}/series?channels=tau&format=f32&reduce=minmax&max_points=20`);
    assert.equal(bin.status, 200);
    const { head, channels } = decode(bin.buf);
    assert.equal(head.reduce, 'minmax');
    assert.ok(head.rows <= 20 && head.rows % 2 === 0, `${head.rows} rows`);
    const size = Math.ceil(n / (head.rows / 2));
    for (let b = 0; b < head.rows / 2; b++) {
        const j0 = b * size, j1 = Math.min(n, j0 + size);
        assert.equal(channels.t[2 * b][0], Math.fround(all.t[j0]), `bucket ${b} starts at its first time`);
        assert.equal(channels.t[2 * b + 1][0], Math.fround(all.t[j1 - 1]), `bucket ${b} ends at its last time`);
        all.tau.forEach((col, c) => {
            const part = col.slice(j0, j1);
            assert.equal(channels.tau[2 * b][c], Math.fround(Math.min(...part)), `tau[${c}] bucket ${b} min`);
            assert.equal(channels.tau[2 * b + 1][c], Math.fround(Math.max(...part)), `tau[${c}] bucket ${b} max`);
        });
    }
});

test('bad format and reduce are 400 naming the parameter', async () => {
    for (const [query, field, message] of [
        ['format=f16', 'format', /format must be json, csv or f32 \(got "f16"\)/],
        ['format=f32&reduce=mean', 'reduce', /reduce must be stride or minmax \(got "mean"\)/],
        ['format=json&reduce=minmax', 'reduce', /reduce=minmax needs format=f32 \(got format=json\)/],
    ]) {
        const res = await srv.get(`/api/jobs/${small.id}/series?${query}`);
        assert.equal(res.status, 400, query);
        assert.equal(res.json.error.code, 'INVALID_QUERY');
        assert.equal(res.json.error.field, field);
        assert.match(res.json.error.message, message);
    }
    const res = await srv.get(`/api/jobs/${small.id}?brief=yes`);
    assert.equal(res.status, 400);
    assert.equal(res.json.error.field, 'brief');
});

test('POST /cancel leaves a finished job alone: 409 ALREADY_FINISHED, the job still there', async () => {
    const res = await srv.post(`/api/jobs/${small.id}/cancel`);
    assert.equal(res.status, 409, res.text);
    assert.equal(res.json.error.code, 'ALREADY_FINISHED');
    assert.match(res.json.error.message, new RegExp(`job ${small.id} is done: there is nothing to cancel`));
    const again = await srv.get(`/api/jobs/${small.id}`);
    assert.equal(again.status, 200);
    assert.equal(again.json.status, 'done');
});

test('queue_position counts from 1 while queued; ?brief=1 has no spec; /cancel stops queued and running jobs', async () => {
    const a = (await submit(srv, LONG)).id;
    const b = (await submit(srv, LONG)).id;
    await waitJob(srv, a, { until: running, timeoutMs: 10000 });
    await waitJob(srv, b, { until: running, timeoutMs: 10000 });
    const c = (await submit(srv, LONG)).id;
    const d = (await submit(srv, LONG)).id;
    const brief = await srv.get(`/api/jobs/${d}?brief=1`);
    assert.equal(brief.status, 200);
    assert.equal(brief.json.status, 'queued');
    assert.equal(brief.json.queue_position, 2);
    assert.ok(!('spec' in brief.json) && !('metrics' in brief.json), Object.keys(brief.json).join(','));
    assert.equal((await srv.get(`/api/jobs/${c}`)).json.queue_position, 1);
    assert.equal((await srv.get(`/api/jobs/${a}`)).json.queue_position, null, 'a running job is in no queue');

    const qc = await srv.post(`/api/jobs/${c}/cancel`);
    assert.equal(qc.status, 200, qc.text);
    assert.equal(qc.json.status, 'cancelled');
    assert.equal((await srv.get(`/api/jobs/${d}`)).json.queue_position, 1, 'd moved up');
    for (const id of [a, b, d]) {
        const res = await srv.post(`/api/jobs/${id}/cancel`);
        assert.ok(res.status === 200 || res.status === 202, `${id}: ${res.status} ${res.text}`);
    }
    for (const id of [a, b, d]) assert.equal((await waitJob(srv, id, { timeoutMs: 10000 })).status, 'cancelled');
    assert.equal((await srv.get(`/api/jobs/${a}`)).status, 200, 'a cancel never deletes');
});

test('a running job\'s series with ?partial=1: the samples so far, growing; ?from= sends only the new ones', { skip: PG_CLUSTER }, async () => {
    /* 64 links, RK4 at 1e-4 s: about 10 samples (0.1 s apart) a second of wall time */
    const id = (await submit(srv, LONG)).id;
    try {
        await waitJob(srv, id, { until: running, timeoutMs: 10000 });
        const plain = await srv.get(`/api/jobs/${id}/series`);
        assert.equal(plain.status, 409, 'without ?partial a running job has no series');
        assert.match(plain.json.error.message, /\?partial=1: the samples recorded so far/);
        const q = `channels=q,e&joints=0,63&partial=1`;
        let first;
        await waitFor(async () => {
            first = await srv.get(`/api/jobs/${id}/series?${q}`);
            return first.status === 200 && first.json.t.length >= 3;
        }, { timeoutMs: 20000, what: () => `partial series: ${first?.status} ${first?.text?.slice(0, 200)}` });
        const n = first.json.t.length;
        first.json.t.forEach((t, j) => assert.ok(Math.abs(t - 0.1 * j) < 1e-9, `t[${j}] = ${t}: every sample from 0 on`));
        assert.equal(first.json.q.length, 2, 'the joints filter applies');
        let later;
        await waitFor(async () => {
            later = await srv.get(`/api/jobs/${id}/series?${q}&from=${n}`);
            return later.status === 200 && later.json.t.length >= 1;
        }, { timeoutMs: 20000, what: () => `later samples: ${later?.status} ${later?.text?.slice(0, 200)}` });
        assert.ok(Math.abs(later.json.t[0] - first.json.t[n - 1] - 0.1) < 1e-9, `from=${n} starts after ${first.json.t[n - 1]}: ${later.json.t[0]}`);
        /* the samples sent first are final: a later read of them is the same */
        const again = await srv.get(`/api/jobs/${id}/series?${q}`);
        assert.deepEqual(again.json.q.map((c) => c.slice(0, n)), first.json.q);
        const bin = await getBinary(`/api/jobs/${id}/series?${q}&format=f32&from=1`);
        assert.equal(bin.status, 200);
        assert.equal(decode(bin.buf).channels.t[0][0], Math.fround(0.1));
        const past = await srv.get(`/api/jobs/${id}/series?${q}&from=100000`);
        assert.equal(past.status, 400);
        assert.equal(past.json.error.field, 'from');
        assert.match(past.json.error.message, /from must be at most the number of samples, \d+ \(got 100000\)/);
    } finally {
        await srv.post(`/api/jobs/${id}/cancel`);
        await waitJob(srv, id, { timeoutMs: 10000 });
    }
    const done = await srv.get(`/api/jobs/${small.id}/series?from=5`);
    assert.equal(done.status, 200);
    assert.ok(Math.abs(done.json.t[0] - 5 * small.spec.output.interval) < 1e-12, 'from works on a finished job');
    assert.equal(done.json.t.length, small.metrics.samples - 5);
});

test('a cluster\'s API process answers ?partial=1 of a job running in a worker process with 409 saying so', { skip: BACKEND !== 'postgres' && 'PostgreSQL only' }, async () => {
    const id = (await submit(srv, LONG)).id;
    try {
        await waitJob(srv, id, { until: running, timeoutMs: 10000 });
        const res = await srv.get(`/api/jobs/${id}/series?partial=1`);
        assert.equal(res.status, 409, res.text);
        assert.equal(res.json.error.code, 'NOT_FINISHED');
        assert.equal(res.json.error.message,
            `job ${id} is running in another worker process of the cluster, which alone holds the samples recorded so far; its series is here once it has finished`);
    } finally {
        await srv.post(`/api/jobs/${id}/cancel`);
        await waitJob(srv, id, { timeoutMs: 10000 });
    }
});

test('an RK4 step longer than the output interval is reported as metrics.step_cut', async () => {
    const cut = await srv.post('/api/jobs?wait=60', {
        preset: 'triple_pendulum_pid', duration: 0.2, integrator: { method: 'rk4', step: 0.05 }, output: { interval: 0.01 },
    });
    assert.equal(cut.status, 200, cut.text);
    assert.deepEqual(cut.json.metrics.step_cut, { asked: 0.05, used: 0.01 });
    const kept = await srv.post('/api/jobs?wait=60', {
        preset: 'triple_pendulum_pid', duration: 0.2, integrator: { method: 'rk4', step: 0.005 }, output: { interval: 0.01 },
    });
    assert.equal(kept.json.metrics.step_cut, null, 'a step that divides the interval is not cut');
    assert.equal(small.metrics.step_cut, null, 'adaptive methods have no step to cut');
});

test('the server stops', async () => {
    await srv.stop();
});
