/*
 * storage.test.mjs - the service under database faults (issue 25, defects 4, 6 and 8): a write
 * lock held by another process, and a full disk.
 *
 * The lock is held by the sqlite3 command in a child process (BEGIN IMMEDIATE and a write, kept
 * open), as any other program on the machine could. With one HTTP thread, a POST that waited for
 * the lock would hold up every other request; it must answer 503 DATABASE_BUSY at once, health must
 * answer at once and say "degraded", reads must be served (WAL readers do not wait), and a job
 * whose worker meets the lock must still finish "done" once it goes. The full disk is a 16 MiB
 * tmpfs mounted for the test (root only; skipped where mount fails) and filled with a file: a
 * finished job can still be deleted, a new job is then accepted and stored, a result too large for
 * the disk ends its job "failed" with SQLite's reason, health says "full" with 503, and once room
 * comes back health says "ok". The same with --db-max-size, which needs neither root nor the
 * sqlite3 command; the others are skipped without them. A server started while the lock is held
 * waits for it (jobq_start's JOBQ_START_TRIES) and then runs the jobs it recovers.
 */
import assert from 'node:assert/strict';
import { spawn, spawnSync } from 'node:child_process';
import { closeSync, openSync, rmSync, writeSync } from 'node:fs';
import path from 'node:path';
import test from 'node:test';

import { BACKEND, FINAL, sleep, startServer, submit, tempDir, waitFor, waitJob } from './lib.mjs';

const haveSqlite = spawnSync('sqlite3', ['-version']).status === 0;
/* every test here is about SQLite's file: its write lock held by another process, its size cap
   (--db-max-size, SQLite only) and its disk; PostgreSQL's faults are tests/api/cluster.test.mjs's */
const SQLITE_ONLY = BACKEND !== 'sqlite' && "SQLite's file (lock, size cap, disk): not the PostgreSQL backend's";

/* one short job: 0.5 s of the triple pendulum */
const SMALL = { preset: 'triple_pendulum_pid', name: 'small', duration: 0.5 };

/* Times one request; resolves {res, ms}. */
async function timed(promise) {
    const t0 = Date.now();
    const res = await promise;
    return { res, ms: Date.now() - t0 };
}

/* Holds the database's write lock from a sqlite3 child process until release() (which commits a
 * write that changes nothing). Resolves once the lock is held. */
async function holdWriteLock(db) {
    const child = spawn('sqlite3', [db], { stdio: ['pipe', 'pipe', 'pipe'] });
    let out = '';
    child.stdout.on('data', (c) => (out += c));
    child.stderr.on('data', (c) => (out += c));
    const exited = new Promise((resolve) => child.on('exit', resolve));
    child.stdin.write(".timeout 5000\nBEGIN IMMEDIATE;\nUPDATE job_counts SET n = n;\nSELECT 'held';\n");
    await waitFor(() => out.includes('held') || /Error/i.test(out), { timeoutMs: 10000 });
    assert.ok(out.includes('held'), `sqlite3 could not take the lock: ${out}`);
    return {
        async release() {
            child.stdin.end('COMMIT;\n');
            await exited;
        },
    };
}

test('a write lock held by another process stalls no request and drops no job',
    { skip: SQLITE_ONLY || (!haveSqlite && 'no sqlite3 command') }, async () => {
    /* one HTTP thread: a request that waited for the lock would hold up every other one */
    const srv = await startServer({ workers: 1, args: ['--http-threads', '1'] });
    /* a job of about 0.5 s (5 s under ASan) that finishes while the lock is held */
    const job = await submit(srv, {
        preset: 'triple_pendulum_pid',
        name: 'under the lock',
        duration: 4,
        integrator: { method: 'rk4', step: 0.0001 },
    });
    await waitJob(srv, job.id, { until: (j) => j.status === 'running', intervalMs: 10 });

    const lock = await holdWriteLock(srv.db);
    const locked = Date.now();
    const [post, health] = await Promise.all([
        timed(srv.post('/api/jobs', SMALL)),
        sleep(50).then(() => timed(srv.get('/api/health'))),
    ]);
    assert.equal(post.res.status, 503, post.res.text);
    assert.equal(post.res.json.error.code, 'DATABASE_BUSY', post.res.text);
    assert.match(post.res.json.error.message, /database is locked/);
    assert.equal(post.res.headers['retry-after'], '1');
    assert.ok(post.ms < 1000, `POST took ${post.ms} ms`);
    assert.ok(health.ms < 1000, `health took ${health.ms} ms behind the POST`);

    /* health says what the POST met, at once, whichever thread answers */
    const h = await timed(srv.get('/api/health'));
    assert.ok(h.ms < 1000, `health took ${h.ms} ms`);
    assert.equal(h.res.status, 503, h.res.text);
    assert.equal(h.res.json.status, 'degraded');
    assert.equal(h.res.json.database.state, 'locked');
    assert.match(h.res.json.database.message, /database is locked/);
    assert.match(h.res.json.database.since, /^\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d\.\d{3}Z$/);
    assert.ok(h.res.json.database.failures >= 1);
    assert.equal(typeof h.res.json.jobs.running, 'number');

    /* reads are served while the writer holds its lock */
    const read = await timed(srv.get(`/api/jobs/${job.id}`));
    assert.equal(read.res.status, 200, read.res.text);
    assert.ok(read.ms < 1000, `GET took ${read.ms} ms`);

    /* held past the 5 s a connection used to wait before giving up */
    await sleep(Math.max(0, 6000 - (Date.now() - locked)));
    await lock.release();

    const done = await waitJob(srv, job.id, { timeoutMs: 60000 });
    assert.equal(done.status, 'done', JSON.stringify(done));
    assert.equal(done.message, null);
    const series = await srv.get(`/api/jobs/${job.id}/series?channels=q&format=csv`);
    assert.equal(series.status, 200, series.text);
    assert.equal(series.text.trim().split('\n').length, 1 + 4 / 0.01 + 1);

    const ok = await waitFor(async () => {
        const r = await srv.get('/api/health');
        return r.status === 200 ? r : null;
    }, { timeoutMs: 5000, what: () => 'health to be ok again' });
    assert.deepEqual(ok.json.database, { state: 'ok' });
    const after = await submit(srv, SMALL);
    assert.equal((await waitJob(srv, after.id)).status, 'done');
    await srv.stop();
});

test('a server started while another process holds the lock waits for it and recovers its jobs',
    { skip: SQLITE_ONLY || (!haveSqlite && 'no sqlite3 command') }, async () => {
    /* a queued job left in the database by a server stopped before it ran */
    const dir = tempDir();
    const first = await startServer({ dir, workers: 1 });
    const long = await submit(first, {
        ...SMALL, name: 'long', duration: 4, integrator: { method: 'rk4', step: 0.0001 },
    });
    const left = await submit(first, { ...SMALL, name: 'left queued' });
    await waitJob(first, long.id, { until: (j) => j.status === 'running', intervalMs: 10 });
    await first.stop('SIGKILL');

    /* the lock held past the store's 5 s busy timeout: the start must wait, not exit */
    const lock = await holdWriteLock(first.db);
    const released = sleep(7000).then(() => lock.release());
    const t0 = Date.now();
    const srv = await startServer({ dir, workers: 1, timeoutMs: 30000 });
    const ms = Date.now() - t0;
    await released;
    assert.ok(ms >= 6000, `the server answered after ${ms} ms, while the lock was held`);
    assert.match(srv.output(), /waiting for the lock/);
    const done = await waitJob(srv, left.id, { timeoutMs: 60000 });
    assert.equal(done.status, 'done', JSON.stringify(done));
    await srv.stop();
});

test('--db-max-size: a result past the cap fails its job, health says full, DELETE makes room',
    { skip: SQLITE_ONLY }, async () => {
    /* 256 KiB: the schema and two jobs of 96 KiB of series (501 samples) each, not a third */
    const srv = await startServer({ workers: 1, args: ['--db-max-size', '256K'] });
    const ids = [];
    for (let i = 0; i < 3; i++) {
        const job = await submit(srv, { ...SMALL, name: `capped ${i}`, duration: 5 });
        ids.push(job.id);
        await waitJob(srv, job.id);
    }
    const rows = await Promise.all(ids.map(async (id) => (await srv.get(`/api/jobs/${id}`)).json));
    assert.deepEqual(rows.map((j) => j.status), ['done', 'done', 'failed'], JSON.stringify(rows));
    assert.equal(rows[2].message, 'could not store the result: database or disk is full');

    const h = await srv.get('/api/health');
    assert.equal(h.status, 503, h.text);
    assert.equal(h.json.status, 'error');
    assert.equal(h.json.database.state, 'full');
    assert.match(h.json.database.message, /database or disk is full/);

    const del = await srv.del(`/api/jobs/${ids[0]}`);
    assert.equal(del.status, 204, del.text);
    const ok = await srv.get('/api/health');
    assert.equal(ok.status, 200, ok.text);
    assert.deepEqual(ok.json.database, { state: 'ok' });
    const next = await submit(srv, { ...SMALL, name: 'in the freed room' });
    assert.equal((await waitJob(srv, next.id)).status, 'done');
    await srv.stop();
});

/* A tmpfs of size bytes mounted on a new directory; null where mount fails (not root). */
function mountTmpfs(size) {
    const dir = tempDir('ctcsim-full-');
    const r = spawnSync('mount', ['-t', 'tmpfs', '-o', `size=${size}`, 'tmpfs', dir]);
    return r.status === 0 ? dir : null;
}

/* Fills the file system of dir with one file; returns its path. */
function fillDisk(dir) {
    const file = path.join(dir, 'filler');
    const fd = openSync(file, 'w');
    for (const size of [1 << 20, 4096, 512]) {
        const block = Buffer.alloc(size);
        try {
            for (;;) writeSync(fd, block);
        } catch (e) {
            if (e.code !== 'ENOSPC') throw e;
        }
    }
    closeSync(fd);
    return file;
}

const mnt = haveSqlite && !SQLITE_ONLY ? mountTmpfs('16m') : null;
test.after(() => {
    if (mnt) spawnSync('umount', ['-l', mnt]);
});

test('a full disk: DELETE frees room, a result too large fails its job, health tells',
    { skip: SQLITE_ONLY || (!mnt && 'cannot mount a tmpfs here (needs root) or no sqlite3 command') }, async () => {
    const srv = await startServer({ dir: mnt, workers: 1 });
    const first = await submit(srv, SMALL);
    const second = await submit(srv, { ...SMALL, name: 'kept' });
    assert.equal((await waitJob(srv, first.id)).status, 'done');
    assert.equal((await waitJob(srv, second.id)).status, 'done');
    const kept = await srv.get(`/api/jobs/${second.id}/series?format=csv`);
    assert.equal(kept.status, 200);

    /* the disk full to the last byte: a finished job can still be deleted, and its room reused */
    const filler = fillDisk(mnt);
    const del = await srv.del(`/api/jobs/${first.id}`);
    assert.equal(del.status, 204, del.text);
    const next = await submit(srv, { ...SMALL, name: 'after the delete' });
    assert.equal((await waitJob(srv, next.id)).status, 'done');

    /* about 8 MB of series (42001 samples x 24 values) on a full disk: the job ends failed */
    const big = await submit(srv, {
        preset: 'triple_pendulum_pid',
        name: 'too big',
        duration: 42,
        integrator: { method: 'rk4', step: 0.001 },
        output: { interval: 0.001 },
    });
    const failed = await waitJob(srv, big.id, { timeoutMs: 60000 });
    assert.equal(failed.status, 'failed', JSON.stringify(failed));
    assert.equal(failed.message, 'could not store the result: database or disk is full');
    assert.equal((await srv.get(`/api/jobs/${big.id}/series`)).status, 404);

    const h = await srv.get('/api/health');
    assert.equal(h.status, 503, h.text);
    assert.equal(h.json.status, 'error');
    assert.equal(h.json.database.state, 'full');
    assert.match(h.json.database.message, /database or disk is full/);
    assert.equal(h.json.jobs.failed, 1);

    /* room again: health sees it without another write, new jobs run, nothing stored was lost */
    rmSync(filler);
    const ok = await waitFor(async () => {
        const r = await srv.get('/api/health');
        return r.status === 200 ? r : null;
    }, { timeoutMs: 5000, what: () => 'health to be ok once the disk has room' });
    assert.deepEqual(ok.json.database, { state: 'ok' });
    const last = await submit(srv, { ...SMALL, name: 'with room' });
    assert.ok(FINAL.has((await waitJob(srv, last.id)).status));
    const again = await srv.get(`/api/jobs/${second.id}/series?format=csv`);
    assert.equal(again.text, kept.text);
    await srv.stop();
    const check = spawnSync('sqlite3', [path.join(mnt, 'jobs.db'), 'PRAGMA integrity_check']);
    assert.equal(check.stdout.toString().trim(), 'ok', check.stderr.toString());
});
