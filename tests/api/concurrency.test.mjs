/*
 * concurrency.test.mjs - 8 clients submit 200 short jobs at once: all are accepted (a client
 * told QUEUE_FULL waits Retry-After and tries again), all finish, their ids are distinct, the
 * paginated list holds exactly them, and their series equal serial `ctcsim run`s of their specs.
 */
import assert from 'node:assert/strict';
import test from 'node:test';

import { cliCsv, FINAL, listAll, mapLimit, sleep, startServer, waitFor, waitIdle } from './lib.mjs';

const NJOBS = 200;
const NCLIENTS = 8;
const PRESETS = ['triple_pendulum_pd', 'triple_pendulum_pid', 'triple_pendulum_passive', 'spatial_double_pendulum_lqr', 'n_link_pendulum'];
const DURATIONS = [0.1, 0.15, 0.2, 0.25];
/* 20 distinct specs (5 presets x 4 durations), each 10 times */
const jobOf = (i) => ({
    preset: PRESETS[i % PRESETS.length],
    name: `concurrent ${i}`,
    duration: DURATIONS[i % DURATIONS.length],
});

let srv;
const ids = new Array(NJOBS);
let retries = 0;

test('the server starts', async () => {
    srv = await startServer({ workers: 2 });
});

test(`${NCLIENTS} clients submit ${NJOBS} jobs concurrently`, async (t) => {
    const client = async (k) => {
        for (let i = k; i < NJOBS; i += NCLIENTS) {
            for (let attempt = 0; ; attempt++) {
                const res = await srv.post('/api/jobs', jobOf(i));
                /* a full queue, or this address's --max-jobs-per-client (all the clients share
                   the loopback address): a polite client waits as Retry-After says */
                const code = res.json?.error?.code;
                const later = (res.status === 503 && code === 'QUEUE_FULL') ||
                    (res.status === 429 && code === 'TOO_MANY_JOBS');
                if (later && attempt < 100) {
                    const after = Number(res.headers['retry-after']);
                    assert.ok(after >= 1, `${code} without Retry-After: ${JSON.stringify(res.headers)}`);
                    retries++;
                    await sleep(Math.min(after, 1) * 200);
                    continue;
                }
                assert.equal(res.status, 202, `job ${i}: ${res.text}`);
                assert.equal(res.headers.location, `/api/jobs/${res.json.id}`);
                ids[i] = res.json.id;
                break;
            }
        }
    };
    await Promise.all(Array.from({ length: NCLIENTS }, (_, k) => client(k)));
    assert.equal(new Set(ids).size, NJOBS, 'ids are distinct');
    assert.ok(ids.every((id) => Number.isInteger(id) && id > 0));
    if (retries) t.diagnostic(`${retries} QUEUE_FULL or TOO_MANY_JOBS answers, retried`);
});

test('all of them finish, done', async () => {
    const rows = await waitFor(
        async () => {
            const all = await listAll(srv, { limit: 200 });
            return all.every((j) => FINAL.has(j.status)) ? all : null;
        },
        { timeoutMs: 30000, intervalMs: 200 },
    );
    for (const row of rows) assert.equal(row.status, 'done', `job ${row.id}: ${row.status}`);
    const h = await waitIdle(srv);
    assert.equal(h.json.jobs.done, NJOBS);
});

test('GET /api/jobs pages through exactly the 200 jobs, newest first', async () => {
    const rows = await listAll(srv, { limit: 37 });
    assert.equal(rows.length, NJOBS);
    assert.deepEqual(rows.map((r) => r.id), [...ids].sort((a, b) => b - a));
    const byId = new Map(ids.map((id, i) => [id, i]));
    for (const row of rows) {
        assert.equal(row.name, `concurrent ${byId.get(row.id)}`);
        assert.equal(row.location, `/api/jobs/${row.id}`);
        assert.equal(row.spec, undefined, 'rows carry no spec');
    }
    /* the default page is 50 rows; the last page says null */
    const first = await srv.get('/api/jobs');
    assert.equal(first.json.jobs.length, 50);
    assert.equal(typeof first.json.next_cursor, 'number');
    const last = await srv.get(`/api/jobs?limit=200`);
    assert.equal(last.json.jobs.length, 200);
    const after = await srv.get(`/api/jobs?limit=200&cursor=${Math.min(...ids)}`);
    assert.deepEqual(after.json, { jobs: [], next_cursor: null });
    /* the status filter */
    assert.equal((await listAll(srv, { limit: 200, status: 'done' })).length, NJOBS);
    const queued = await srv.get('/api/jobs?status=queued');
    assert.deepEqual(queued.json, { jobs: [], next_cursor: null });
});

test('every series equals a serial CLI run of its spec', async () => {
    const cache = new Map(); /* spec text -> CSV */
    const got = await mapLimit(ids, 8, async (id) => {
        const job = (await srv.get(`/api/jobs/${id}`)).json;
        const csv = await srv.get(`/api/jobs/${id}/series?format=csv`);
        assert.equal(csv.status, 200, csv.text);
        return { job, csv: csv.text };
    });
    for (const { job, csv } of got) {
        const key = JSON.stringify({ ...job.spec, name: null }); /* the name does not change the run */
        if (!cache.has(key)) cache.set(key, await cliCsv(job.spec));
        assert.ok(csv === cache.get(key), `job ${job.id} (${job.name}): CSV differs from the CLI's`);
    }
    assert.equal(cache.size, PRESETS.length * DURATIONS.length);
});

test('the server stops cleanly on SIGTERM', async () => {
    const r = await srv.stop('SIGTERM');
    assert.equal(r.killed, undefined, 'it had to be killed');
    assert.equal(r.code, 0, srv.output());
});
