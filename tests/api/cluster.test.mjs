/*
 * The PostgreSQL cluster's faults: one `--role api` process and worker processes (lib.mjs, with
 * CTCSIM_TEST_PG), each killed or cut off while jobs run. A worker killed with SIGKILL during a
 * job: the job's lease expires and another worker runs it again, to the byte-identical series of
 * the command line. The API process killed with SIGKILL: the workers go on, and a new API process
 * answers for every job. PostgreSQL restarted during a batch: every accepted job finishes done,
 * once (one done row each, counted in the database), and the workers, whose connections were
 * lost, reconnect and take new jobs (the API process answers 503 while the database is down). A worker whose connection the database ends
 * (pg_terminate_backend) reconnects and claims again. Skipped on SQLite, whose file is not shared
 * between processes.
 */
import assert from 'node:assert/strict';
import { spawnSync } from 'node:child_process';
import test from 'node:test';

import { BACKEND, cliCsv, pgDatabase, sleep, startServer, submit, tempDir, waitFor, waitJob } from './lib.mjs';

const SKIP = BACKEND !== 'postgres' && 'needs PostgreSQL (tests/api/run.sh runs it with CTCSIM_TEST_PG)';

/* about 1-3 s of one worker's time: 300000 steps of the triple pendulum */
const MEDIUM = { preset: 'triple_pendulum_pid', name: 'medium', duration: 12, integrator: { method: 'rk4', step: 0.00004 }, output: { interval: 0.05 } };
const SMALL = { preset: 'triple_pendulum_pid', name: 'small', duration: 0.5 };

/* one query's rows as text (psql -At), on a server's database */
function sql(srv, query) {
    const r = spawnSync('psql', [srv.db, '-qAtc', query], { encoding: 'utf8' });
    if (r.status !== 0) throw new Error(`psql: ${r.stderr}`);
    return r.stdout.trim();
}

/* the process id in a claim's token (host:pid:connection:claim), or null */
function workerPid(srv, id) {
    const token = sql(srv, `SELECT coalesce(worker, '') FROM jobs WHERE id = ${id}`);
    const m = /^[^:]*:([0-9]+):/.exec(token);
    return m ? Number(m[1]) : null;
}

test('a worker killed with SIGKILL mid-job: the job runs again elsewhere, same series', { skip: SKIP }, async () => {
    const srv = await startServer({ workers: 2 });
    try {
        const id = (await submit(srv, MEDIUM)).id;
        await waitJob(srv, id, { until: (j) => j.status === 'running' && j.progress > 0, timeoutMs: 20000 });
        const pid = workerPid(srv, id);
        const victim = srv.workers.find((w) => w.proc.pid === pid);
        assert.ok(victim, `job ${id} is held by process ${pid}, not one of the workers`);
        await victim.kill();
        const done = await waitJob(srv, id, { timeoutMs: 60000 });
        assert.equal(done.status, 'done', JSON.stringify(done));
        const other = workerPid(srv, id) ?? -1;
        assert.notEqual(other, pid, 'the job finished under the killed worker');
        const res = await srv.get(`/api/jobs/${id}/series?format=csv`);
        assert.equal(res.status, 200);
        assert.equal(res.text, await cliCsv(MEDIUM), 'the series differs from the CLI run');
        assert.equal(sql(srv, `SELECT count(*) FROM series WHERE job_id = ${id} AND channel = 't'`), '1');
    } finally {
        await srv.stop();
    }
});

test('health on PostgreSQL counts the whole database: workers this process\'s, busy and jobs every one\'s', { skip: SKIP }, async () => {
    const srv = await startServer({ workers: 2 });
    /* a second API process on the same database, without workers */
    const other = await startServer({ dir: srv.dir, workers: 1, args: [] });
    await Promise.all(other.workers.map((w) => w.stop()));
    other.workers = [];
    try {
        const id = (await submit(srv, MEDIUM)).id;
        await waitJob(srv, id, { until: (j) => j.status === 'running', timeoutMs: 20000 });
        for (const s of [srv, other]) {
            const h = (await s.get('/api/health')).json;
            assert.equal(h.workers, 0, `an API process has no workers: ${JSON.stringify(h)}`);
            assert.equal(h.busy, 1, `the job running in a worker process: ${JSON.stringify(h)}`);
            assert.equal(h.jobs.running, 1, JSON.stringify(h));
        }
        await srv.del(`/api/jobs/${id}`);
    } finally {
        await other.stop();
        await srv.stop();
    }
});

test('--max-queue holds across API processes: concurrent POSTs to two of them queue at most the bound', { skip: SKIP }, async () => {
    const BOUND = 3;
    const args = ['--max-queue', String(BOUND)];
    const first = await startServer({ workers: 2, args });
    const second = await startServer({ dir: first.dir, workers: 1, args });
    /* no workers: what is accepted stays queued */
    for (const srv of [first, second]) {
        await Promise.all(srv.workers.map((w) => w.stop()));
        srv.workers = [];
    }
    try {
        for (let round = 0; round < 3; round++) {
            const posts = [];
            for (let i = 0; i < 16; i++) posts.push((i % 2 ? second : first).post('/api/jobs', SMALL));
            const answers = await Promise.all(posts);
            const accepted = answers.filter((r) => r.status === 202);
            const full = answers.filter((r) => r.status === 503 && r.json?.error?.code === 'QUEUE_FULL');
            assert.equal(accepted.length + full.length, answers.length, answers.map((r) => r.text).join('\n'));
            assert.equal(accepted.length, BOUND, `round ${round}: ${accepted.length} accepted`);
            assert.equal(sql(first, "SELECT count(*) FROM jobs WHERE status = 'queued'"), String(BOUND));
            for (const r of accepted) assert.ok([200, 202].includes((await first.del(`/api/jobs/${r.json.id}`)).status));
            for (const r of accepted) assert.equal((await first.del(`/api/jobs/${r.json.id}`)).status, 204);
        }
    } finally {
        await second.stop();
        await first.stop();
    }
});

test('the API process killed with SIGKILL: the workers go on, a new API process answers', { skip: SKIP }, async () => {
    const first = await startServer({ workers: 2 });
    const ids = [];
    for (let i = 0; i < 6; i++) ids.push((await submit(first, { ...SMALL, name: `small ${i}` })).id);
    const workers = first.workers;
    first.workers = []; /* killed alone: its worker processes stay */
    await first.kill();
    /* an API process on the same database, without workers of its own */
    const second = await startServer({ dir: first.dir, workers: 1, args: [] });
    try {
        for (const id of ids) {
            const job = await waitJob(second, id, { timeoutMs: 30000 });
            assert.equal(job.status, 'done', JSON.stringify(job));
        }
        /* ?wait through the new process, answered by a notification */
        const res = await second.post('/api/jobs?wait=30', SMALL);
        assert.equal(res.status, 200, res.text);
        assert.equal(res.json.status, 'done');
    } finally {
        await Promise.all(workers.map((w) => w.stop()));
        await second.stop();
    }
});

test('PostgreSQL restarted during a batch: every job finishes once, the workers reconnect', { skip: SKIP || (!process.env.CTCSIM_TEST_PG_DIR && 'CTCSIM_TEST_PG_DIR is not set') }, async () => {
    const srv = await startServer({ workers: 2 });
    try {
        const ids = [];
        for (let i = 0; i < 12; i++) ids.push((await submit(srv, { ...MEDIUM, duration: 1, name: `batch ${i}` })).id);
        await waitFor(async () => (await srv.get('/api/health')).json?.busy > 0, { timeoutMs: 20000 });
        const r = spawnSync('sh', ['tests/pg/restart.sh', process.env.CTCSIM_TEST_PG_DIR], { encoding: 'utf8' });
        assert.equal(r.status, 0, r.stderr);
        /* while the database restarts the API answers 503 (DATABASE_IO_ERROR): asked again */
        for (const id of ids) {
            const job = await waitFor(async () => {
                const res = await srv.get(`/api/jobs/${id}`);
                if (res.status === 503) return null;
                assert.equal(res.status, 200, res.text);
                return ['done', 'failed', 'diverged', 'cancelled'].includes(res.json.status) ? res.json : null;
            }, { timeoutMs: 90000, intervalMs: 200, what: () => `job ${id} to finish` });
            assert.equal(job.status, 'done', JSON.stringify(job));
        }
        /* one done row each, one t series each: nothing lost, nothing stored twice */
        assert.equal(sql(srv, `SELECT count(*) FROM jobs WHERE status = 'done' AND id IN (${ids})`), String(ids.length));
        assert.equal(sql(srv, `SELECT count(*) FROM series WHERE channel = 't' AND job_id IN (${ids})`), String(ids.length));
        const res = await srv.get(`/api/jobs/${ids[ids.length - 1]}/series?format=csv`);
        assert.equal(res.text, await cliCsv({ ...MEDIUM, duration: 1, name: `batch ${ids.length - 1}` }));
        /* the workers lost their connections and claim again */
        const after = await srv.post('/api/jobs?wait=30', SMALL);
        assert.equal(after.status, 200, after.text);
    } finally {
        await srv.stop();
    }
});

test('a worker whose connection the database ends reconnects and claims again', { skip: SKIP }, async () => {
    const srv = await startServer({ workers: 1 });
    try {
        assert.equal((await srv.post('/api/jobs?wait=30', SMALL)).json.status, 'done');
        /* every ctcsim connection to this database but psql's own */
        const name = sql(srv, 'SELECT current_database()');
        const ended = sql(srv, `SELECT count(*) FROM (SELECT pg_terminate_backend(pid) FROM pg_stat_activity WHERE datname = '${name}' AND application_name = 'ctcsim') AS t`);
        assert.ok(Number(ended) >= 2, `ended ${ended} connections`);
        await sleep(200);
        const res = await srv.post('/api/jobs?wait=30', SMALL);
        /* the API process's own connections reconnect at their next call; the first answer may
           be 503 while they do, a retry works */
        const again = res.status === 200 ? res : await srv.post('/api/jobs?wait=30', SMALL);
        assert.equal(again.status, 200, again.text);
        assert.equal(again.json.status, 'done');
        /* run by the one worker there is, the one whose connection was ended */
        assert.equal(srv.workers.length, 1);
        assert.equal(srv.workers[0].exited, null);
        assert.equal(workerPid(srv, again.json.id), srv.workers[0].proc.pid);
    } finally {
        await srv.stop();
    }
});

/* the schema of version 2 as that version of store_pg.c created it (migrations 0 -> 1 -> 2),
   without its trigger's notifications, which no process listens to here */
const V2_SCHEMA = `
CREATE TABLE schema_version (version INTEGER NOT NULL);
INSERT INTO schema_version VALUES (2);
CREATE TABLE jobs (
  id BIGINT GENERATED ALWAYS AS IDENTITY PRIMARY KEY, name TEXT NOT NULL, preset TEXT,
  status TEXT NOT NULL DEFAULT 'queued' CHECK (status IN ('queued', 'running', 'done', 'failed', 'diverged', 'cancelled')),
  progress DOUBLE PRECISION NOT NULL DEFAULT 0, created DOUBLE PRECISION NOT NULL,
  started DOUBLE PRECISION NOT NULL DEFAULT 0, finished DOUBLE PRECISION NOT NULL DEFAULT 0,
  nbodies INTEGER NOT NULL, nv INTEGER NOT NULL, controller TEXT NOT NULL, spec TEXT NOT NULL,
  metrics TEXT, message TEXT, e_max DOUBLE PRECISION, wall_s DOUBLE PRECISION, worker TEXT,
  lease_until DOUBLE PRECISION, cancel_requested BOOLEAN NOT NULL DEFAULT false);
CREATE INDEX jobs_by_status ON jobs (status);
CREATE INDEX jobs_active ON jobs (id) WHERE status IN ('queued', 'running');
CREATE TABLE series (
  job_id BIGINT NOT NULL REFERENCES jobs (id) ON DELETE CASCADE, channel TEXT NOT NULL,
  width INTEGER NOT NULL CHECK (width > 0), nsamples INTEGER NOT NULL CHECK (nsamples >= 0),
  data BYTEA NOT NULL, PRIMARY KEY (job_id, channel));
CREATE TABLE job_counts (status TEXT PRIMARY KEY, n BIGINT NOT NULL CHECK (n >= 0));
INSERT INTO job_counts (status, n) VALUES ('queued', 0), ('running', 0), ('done', 0), ('failed', 0), ('diverged', 0), ('cancelled', 0);
CREATE FUNCTION ctcsim_job_change() RETURNS trigger LANGUAGE plpgsql AS $$ BEGIN
  IF TG_OP = 'INSERT' THEN UPDATE job_counts SET n = n + 1 WHERE status = NEW.status;
  ELSIF TG_OP = 'DELETE' THEN UPDATE job_counts SET n = n - 1 WHERE status = OLD.status;
  ELSIF OLD.status <> NEW.status THEN
    UPDATE job_counts SET n = n + CASE WHEN status = NEW.status THEN 1 ELSE -1 END WHERE status IN (OLD.status, NEW.status);
  END IF; RETURN NULL; END $$;
CREATE TRIGGER job_change AFTER INSERT OR DELETE OR UPDATE OF status ON jobs FOR EACH ROW EXECUTE FUNCTION ctcsim_job_change();
INSERT INTO jobs (name, preset, status, created, finished, nbodies, nv, controller, spec, metrics, e_max, wall_s)
  VALUES ('finished before', 'triple_pendulum_pid', 'done', 1700000000, 1700000001, 3, 3, 'pid',
          '{"name":"finished before","tags":["old"]}', '{"e_final":[0.5,-2,1],"e_rms":[3,4,0]}', 2, 0.5);
INSERT INTO jobs (name, preset, status, created, nbodies, nv, controller, spec)
  VALUES ('queued before', 'triple_pendulum_pid', 'queued', 1700000002, 3, 3, 'pid',
          '{"preset":"triple_pendulum_pid","name":"queued before","duration":0.2}');
`;

test('a version 2 database is migrated to families and keeps every job; its queued job runs', { skip: SKIP }, async () => {
    const dir = tempDir();
    const db = pgDatabase(dir);
    const r = spawnSync('psql', [db, '-qv', 'ON_ERROR_STOP=1'], { input: V2_SCHEMA, encoding: 'utf8' });
    assert.equal(r.status, 0, r.stderr);
    const srv = await startServer({ dir, workers: 1 });
    try {
        assert.equal(sql(srv, 'SELECT version FROM schema_version'), '4');
        assert.equal(sql(srv, "SELECT count(*) FROM pg_indexes WHERE indexname = 'jobs_by_family_status'"), '1');
        const old = (await srv.get('/api/jobs/1')).json;
        assert.equal(old.status, 'done');
        assert.equal(old.name, 'finished before');
        assert.equal(old.family ?? null, null, 'a job stored before families has none');
        const listed = (await srv.get('/api/jobs?q=OLD')).json.jobs;
        assert.deepEqual(listed.map((j) => j.id), [1], 'the old job is found by its tag');
        /* the summaries from its metrics: max |e_final| = 2, sqrt((9 + 16 + 0) / 3) */
        assert.equal(listed[0].e_final, 2);
        assert.ok(Math.abs(listed[0].e_rms - Math.sqrt(25 / 3)) < 1e-12, String(listed[0].e_rms));
        const queued = await waitJob(srv, 2, { timeoutMs: 30000 });
        assert.equal(queued.status, 'done', JSON.stringify(queued));
        const fam = await srv.post('/api/families', { base: { preset: 'triple_pendulum_pd', duration: 0.01 }, axes: [{ path: 'controller.kp', values: [50, 60] }] });
        assert.equal(fam.status, 202, fam.text);
        assert.equal(fam.json.first_job, 3, 'the members follow the jobs kept');
        assert.equal(sql(srv, 'SELECT count(*) FROM jobs'), '4');
    } finally {
        await srv.stop();
    }
});
