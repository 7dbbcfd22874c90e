/*
 * families.test.mjs - studies: POST /api/families, the list, the table as JSON and CSV, the
 * members as ordinary jobs, DELETE (cancel, then delete), a restart in the middle of a family,
 * a family of 10,000 tiny members (accept time and memory), fair turns for single jobs posted
 * during it (their waiting time), bad axes, the --max-family limit, and `ctcsim sweep` printing
 * the server's table.
 *
 * Oracles: the command line (the same family run by `ctcsim sweep` gives the same table but for
 * the timing columns), the members' own job rows (GET /api/jobs/{id}), and wall-clock bounds.
 */
import assert from 'node:assert/strict';
import { readFileSync, writeFileSync } from 'node:fs';
import path from 'node:path';
import test from 'node:test';

import { FINAL, parseCsv, runCli, startServer, tempDir, waitFor, waitJob } from './lib.mjs';


const TINY = { preset: 'triple_pendulum_pd', duration: 0.01 };
/* a quarter of a second or so of work (100000 RK4 steps of the triple pendulum) */
const MEDIUM = { preset: 'triple_pendulum_pd', duration: 4, integrator: { method: 'rk4', step: 0.00004 } };
/* runs for minutes: only ever cancelled */
const LONG = { preset: 'triple_pendulum_pd', duration: 60, integrator: { method: 'rk4', step: 0.00001 } };

const SWEEP = {
    name: 'gains and tolerances',
    base: { preset: 'triple_pendulum_pd', duration: 0.5 },
    axes: [
        { path: 'controller.kp', values: [50, 200] },
        { path: 'integrator.rtol', logspace: [1e-4, 1e-8, 3] },
    ],
};

let srv;
let sweepId;

async function family(s, id) {
    const res = await s.get(`/api/families/${id}`);
    assert.equal(res.status, 200, res.text);
    return res.json;
}

const finished = (f) => f.counts.queued + f.counts.running === 0;

async function waitFamily(s, id, timeoutMs = 60000) {
    let last;
    return waitFor(
        async () => {
            last = await family(s, id);
            return finished(last) ? last : null;
        },
        { timeoutMs, intervalMs: 100, what: () => `family ${id}: ${JSON.stringify(last?.counts)}` },
    );
}

/* the CSV without the timing columns, which differ between two runs */
function untimed(text) {
    const { header, rows } = parseCsv(text);
    const keep = header.map((h, i) => (h === 'wall_s' || h === 'us_per_eval' ? -1 : i)).filter((i) => i >= 0);
    return [keep.map((i) => header[i]), ...rows.map((r) => keep.map((i) => r[i]))].map((r) => r.join(',')).join('\n');
}

test('the server starts', async () => {
    srv = await startServer({ workers: 2 });
});

test('POST /api/families: 202 with the id and the member count; the members run', async () => {
    const res = await srv.post('/api/families', SWEEP);
    assert.equal(res.status, 202, res.text);
    assert.equal(res.json.members, 6);
    assert.equal(res.json.name, 'gains and tolerances');
    sweepId = res.json.id;
    assert.equal(res.headers.location, `/api/families/${sweepId}`);
    assert.equal(res.json.location, `/api/families/${sweepId}`);
    const f = await waitFamily(srv, sweepId);
    assert.deepEqual(f.counts, { queued: 0, running: 0, done: 6, failed: 0, diverged: 0, cancelled: 0 });
    assert.deepEqual(f.axes, ['controller.kp', 'integrator.rtol']);
    assert.deepEqual(f.spec, SWEEP);
});

test('the table: one row per member with its axis values and metrics; members are jobs', async () => {
    const f = await family(srv, sweepId);
    assert.deepEqual(f.table.columns, ['member', 'replica', 'controller.kp', 'integrator.rtol', 'status',
        'e_final', 'e_rms', 'e_max', 'tau_peak', 'energy_drift', 'us_per_eval', 'steps', 'wall_s']);
    assert.equal(f.table.rows.length, 6);
    const rtol = [1e-4, 1e-6, 1e-8];
    for (const [i, row] of f.table.rows.entries()) {
        assert.equal(row.member, i);
        assert.deepEqual(row.values, [i < 3 ? 50 : 200, rtol[i % 3]]);
        assert.equal(row.status, 'done');
        const job = (await srv.get(`/api/jobs/${row.job}`)).json;
        assert.equal(job.family, sweepId);
        assert.equal(job.spec.controller.kp, row.values[0]);
        assert.equal(job.spec.integrator.rtol, row.values[1]);
        /* the row's figures are the job's metrics reduced over its coordinates */
        const m = job.metrics;
        assert.equal(row.e_max, Math.max(...m.e_max.map(Math.abs)));
        assert.equal(row.e_final, Math.max(...m.e_final.map(Math.abs)));
        assert.equal(row.tau_peak, Math.max(...m.tau_peak.map(Math.abs)));
        assert.equal(row.steps, m.steps);
        assert.equal(row.wall_s, m.wall_s);
        assert.ok(row.us_per_eval > 0);
    }
    /* a tighter tolerance takes more steps */
    assert.ok(f.table.rows[2].steps > f.table.rows[0].steps);
    /* a single job has no family */
    const single = await srv.post('/api/jobs', TINY);
    assert.equal((await srv.get(`/api/jobs/${single.json.id}`)).json.family, null);
});

test('the table as CSV (?format=csv and Accept: text/csv) equals `ctcsim sweep --csv` but for timings', async () => {
    const csv = await srv.get(`/api/families/${sweepId}?format=csv`);
    assert.equal(csv.status, 200);
    assert.match(csv.headers['content-type'], /^text\/csv/);
    const accepted = await srv.get(`/api/families/${sweepId}`, { headers: { accept: 'text/csv' } });
    assert.equal(accepted.text, csv.text);
    assert.equal(csv.text.split('\n')[0], 'member,replica,controller.kp,integrator.rtol,status,e_final,e_rms,e_max,tau_peak,energy_drift,us_per_eval,steps,wall_s');
    const file = path.join(tempDir('ctcsim-sweep-'), 'family.json');
    writeFileSync(file, JSON.stringify(SWEEP));
    const cli = await runCli(['sweep', file, '--csv', '--quiet', '--threads', '2']);
    assert.equal(cli.code, 0, cli.stderr);
    assert.equal(untimed(cli.stdout), untimed(csv.text));
    /* the aligned text has the same cells */
    const text = await runCli(['sweep', file, '--quiet', '--threads', '1']);
    assert.equal(text.code, 0, text.stderr);
    const cells = text.stdout.trim().split('\n').map((l) => l.trim().split(/ +/));
    assert.deepEqual(cells[0], csv.text.split('\n')[0].split(','));
    assert.equal(cells.length, 7);
    const bad = await srv.get(`/api/families/${sweepId}?format=xml`);
    assert.equal(bad.status, 400);
    assert.deepEqual(bad.json.error, { code: 'INVALID_QUERY', field: 'format', message: 'format must be json or csv (got "xml")' });
});

test('GET /api/families lists families newest first with their counts', async () => {
    const other = await srv.post('/api/families', { base: TINY, axes: [{ path: 'controller.kv', values: [10, 20] }] });
    assert.equal(other.status, 202, other.text);
    await waitFamily(srv, other.json.id);
    const res = await srv.get('/api/families?limit=1');
    assert.equal(res.status, 200, res.text);
    assert.equal(res.json.families.length, 1);
    assert.equal(res.json.families[0].id, other.json.id);
    assert.equal(res.json.families[0].counts.done, 2);
    assert.equal(res.json.next_cursor, other.json.id);
    const next = await srv.get(`/api/families?limit=5&cursor=${res.json.next_cursor}`);
    assert.deepEqual(next.json.families.map((f) => f.id), [sweepId]);
    assert.equal(next.json.next_cursor, null);
    assert.equal((await srv.get('/api/families/999')).status, 404);
    assert.equal((await srv.get('/api/families/x')).json.error.code, 'INVALID_ID');
});

test('bad axes: 400 naming the axis, the value and the member\'s error', async () => {
    const cases = [
        [{ base: TINY, axes: [{ path: 'integrator.rtol', values: [1e-6, -1] }] },
            { code: 'INVALID_FIELD', field: 'axes[0]', message: 'axis integrator.rtol = -1 (member 1): integrator: rtol must be in (0, 1) (got -1)' }],
        [{ base: TINY, axes: [{ path: 'controller.kq', values: [1] }] },
            { code: 'UNKNOWN_FIELD', field: 'axes[0]', message: 'axis controller.kq = 1 (member 0): controller.kq: unknown key "kq" (did you mean "kp"?)' }],
        [{ base: TINY, axes: [{ path: 'controller.kp', logspace: [0, 1, 3] }] },
            { code: 'INVALID_FIELD', field: 'axes[0].logspace[0]', message: 'must be > 0 on a logarithmic axis (got 0)' }],
        [{ base: TINY, axes: [{ path: 'controller.kp' }] },
            { code: 'MISSING_FIELD', field: 'axes[0]', message: 'an axis needs exactly one of "values", "linspace", "logspace" and "random" (got 0)' }],
        [{ axes: [] }, { code: 'MISSING_FIELD', field: 'base', message: 'is required: a job, or {"preset": NAME, ...} with overrides' }],
    ];
    for (const [body, error] of cases) {
        const res = await srv.post('/api/families', body);
        assert.equal(res.status, 400, res.text);
        assert.deepEqual(res.json.error, error);
    }
    const listed = (await srv.get('/api/families')).json.families.length;
    assert.equal(listed, 2, 'nothing refused was stored');
});

test('GET /api/jobs/{id}?wait holds the answer until a family\'s member finishes, as for a single job', async () => {
    const res = await srv.post('/api/families', { base: { ...MEDIUM, duration: 8 }, axes: [{ path: 'controller.kp', values: [60, 70, 80, 90] }] });
    assert.equal(res.status, 202, res.text);
    const members = (await family(srv, res.json.id)).table.rows.map((r) => r.job);
    const single = (await srv.post('/api/jobs', { ...MEDIUM, duration: 8 })).json.id;
    /* the last member waits behind the others (half a second each, two workers) */
    const ids = [members[3], single];
    for (const id of ids) {
        const before = (await srv.get(`/api/jobs/${id}?brief=1`)).json;
        assert.ok(!FINAL.has(before.status), `job ${id} finished before the wait: ${before.status}`);
    }
    const t0 = Date.now();
    const got = await Promise.all(ids.map((id) => srv.get(`/api/jobs/${id}?wait=60&brief=1`)));
    for (const [i, r] of got.entries()) {
        assert.equal(r.status, 200, r.text);
        assert.equal(r.json.status, 'done', `job ${ids[i]} answered after ${Date.now() - t0} ms unfinished`);
        assert.equal(r.json.spec, undefined, 'brief=1 still applies');
    }
    /* a finished job answers at once; a bad wait is refused */
    const t1 = Date.now();
    assert.equal((await srv.get(`/api/jobs/${members[0]}?wait=60`)).json.status, 'done');
    assert.ok(Date.now() - t1 < 2000);
    const bad = await srv.get(`/api/jobs/${members[0]}?wait=0`);
    assert.equal(bad.status, 400, bad.text);
    assert.equal(bad.json.error.field, 'wait');
    await waitFamily(srv, res.json.id);
});

test('DELETE cancels the queued and running members (202), a second DELETE deletes them (204)', async () => {
    const res = await srv.post('/api/families', { base: LONG, axes: [{ path: 'controller.kp', linspace: [50, 100, 5] }] });
    assert.equal(res.status, 202, res.text);
    const id = res.json.id;
    await waitFor(async () => (await family(srv, id)).counts.running === 2, { timeoutMs: 20000 });
    const t0 = Date.now();
    const del = await srv.del(`/api/families/${id}`);
    assert.equal(del.status, 202, del.text);
    assert.equal(del.json.counts.cancelled, 3);
    const f = await waitFamily(srv, id, 10000);
    assert.ok(Date.now() - t0 < 5000, 'the running members stopped within a step');
    assert.equal(f.counts.cancelled, 5);
    assert.ok(f.table.rows.every((r) => r.status === 'cancelled'));
    const jobs = f.table.rows.map((r) => r.job);
    const gone = await srv.del(`/api/families/${id}`);
    assert.equal(gone.status, 204, gone.text);
    assert.equal((await srv.get(`/api/families/${id}`)).status, 404);
    for (const j of jobs) assert.equal((await srv.get(`/api/jobs/${j}`)).status, 404);
    assert.equal((await srv.del(`/api/families/${id}`)).status, 404);
});

test('a restart in the middle of a family: its members finish after it', async () => {
    const res = await srv.post('/api/families', { base: MEDIUM, axes: [{ path: 'controller.kp', linspace: [50, 150, 8] }] });
    assert.equal(res.status, 202, res.text);
    const id = res.json.id;
    await waitFor(async () => (await family(srv, id)).counts.done >= 1, { timeoutMs: 30000 });
    const before = await family(srv, id);
    assert.ok(before.counts.queued > 0, `still queued: ${JSON.stringify(before.counts)}`);
    const stopped = await srv.stop('SIGTERM');
    assert.equal(stopped.code, 0);
    srv = await startServer({ dir: srv.dir, workers: 2 });
    const f = await waitFamily(srv, id, 60000);
    assert.equal(f.counts.done, 8, JSON.stringify(f.counts));
    assert.ok(f.table.rows.every((r) => r.status === 'done' && r.steps === 100000));
});

/* The server's resident memory in kB. */
function rssOf(s) {
    return Number(/VmRSS:\s+(\d+) kB/.exec(readFileSync(`/proc/${s.proc.pid}/status`, 'utf8'))[1]);
}

/* A server whose memory measures what it holds: under AddressSanitizer (make check-asan) freed
 * memory waits in a quarantine of up to 256 MB before reuse, which would count every allocation
 * the expansion ever made; a 1 MB quarantine keeps the measure to what is held (as in
 * series.test.mjs). Other builds ignore ASAN_OPTIONS. */
async function startMeasured() {
    const saved = process.env.ASAN_OPTIONS;
    process.env.ASAN_OPTIONS = `${saved ? `${saved}:` : ''}quarantine_size_mb=1`;
    try {
        return await startServer({ workers: 2 });
    } finally {
        if (saved === undefined) delete process.env.ASAN_OPTIONS;
        else process.env.ASAN_OPTIONS = saved;
    }
}

test('10,000 tiny members: accepted in seconds, sane memory; single jobs wait for about one job', async (t) => {
    const lean = await startMeasured();
    t.after(() => lean.stop());
    const before = rssOf(lean);
    const t0 = Date.now();
    const res = await lean.post('/api/families', { name: 'big', base: TINY, axes: [{ path: 'controller.kp', linspace: [50, 150, 10000] }] });
    const acceptMs = Date.now() - t0;
    assert.equal(res.status, 202, res.text);
    assert.equal(res.json.members, 10000);
    assert.ok(acceptMs < 60000, `accepted in ${acceptMs} ms`);
    /* the members' specs are about 20 MB of text while they are expanded and stored */
    const grew = rssOf(lean) - before;
    assert.ok(grew < 256 * 1024, `the server grew by ${grew} kB`);
    const id = res.json.id;

    /* single jobs posted while the family runs start within about a job's time, not the
       family's: each waits for the members in hand and at most one more per family */
    const waits = [];
    for (let i = 0; i < 3; i++) {
        const single = await lean.post('/api/jobs', TINY);
        assert.equal(single.status, 202, single.text);
        const job = await waitJob(lean, single.json.id, { timeoutMs: 30000 });
        assert.equal(job.status, 'done');
        waits.push(Date.parse(job.started) - Date.parse(job.created));
    }
    const f = await family(lean, id);
    assert.ok(f.counts.queued > 1000, `the family still had ${f.counts.queued} members queued`);
    for (const w of waits) assert.ok(w < 2000, `a single job waited ${w} ms: ${waits}`);
    console.log(`# accepted 10000 members in ${acceptMs} ms, the server grew by ${grew} kB; single jobs waited ${waits.join(', ')} ms with ${f.counts.queued} members queued`);

    const del = await lean.del(`/api/families/${id}`);
    assert.ok(del.status === 200 || del.status === 202, del.text);
    await waitFamily(lean, id, 30000);
    assert.equal((await lean.del(`/api/families/${id}`)).status, 204);
});

test('--max-family: a larger family is refused with 413 before anything is stored', async () => {
    const small = await startServer({ workers: 1, args: ['--max-family', '5'] });
    const res = await small.post('/api/families', { base: TINY, replicas: 2, axes: [{ path: 'controller.kp', values: [1, 2, 3] }] });
    assert.equal(res.status, 413, res.text);
    assert.deepEqual(res.json.error, {
        code: 'FAMILY_TOO_LARGE',
        field: 'axes',
        message: 'the family has 6 members, more than this server takes (--max-family 5)',
    });
    assert.equal((await small.get('/api/families')).json.families.length, 0);
    assert.equal((await small.get('/api/health')).json.jobs.queued, 0);
    const ok = await small.post('/api/families', { base: TINY, replicas: 5 });
    assert.equal(ok.status, 202, ok.text);
    await waitFamily(small, ok.json.id);
    await small.stop();
});

test('the server stops cleanly', async () => {
    const r = await srv.stop('SIGTERM');
    assert.equal(r.code, 0, srv.output());
    assert.ok(FINAL.has('done'));
});
