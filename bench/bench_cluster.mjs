/*
 * bench_cluster.mjs - many small jobs through the service: the SQLite server with 1, 2 and 3
 * workers against one PostgreSQL with one --role api process and 1, 2 and 3 --role worker
 * processes (one worker each), side by side in one run.
 *
 *   node bench/bench_cluster.mjs [SERVER [JOBS [jobs|family]]]
 *                                    (default build/ctcsim-server, 2000, jobs)
 *
 * Each configuration gets a fresh database. jobs: JOBS jobs (triple_pendulum_pid for 0.1 s:
 * about 0.2 ms of simulation each) are posted by 16 concurrent clients while the workers run;
 * the time is from the first POST to the moment health counts them all done. family: one
 * POST /api/families of JOBS members, the same job with controller.kp from 50 to 150 (issue 24's
 * 10,000-member family), timed from the POST (its 202 included: the members are validated and
 * stored first) to the moment the family's counts have none queued or running. Printed per
 * configuration:
 * jobs per second, and the per-job overhead, workers x elapsed / jobs minus the mean simulation
 * time the workers measured (wall_s): what storing, claiming and notifying cost a worker per job.
 * PostgreSQL comes from tests/pg/start.sh (a throw-away cluster on loopback, fsync off as in the
 * tests: the figures are the service's, not a durable disk's). Needs node >= 18 and PostgreSQL's
 * server (Debian's postgresql).
 */
import { spawn, spawnSync } from 'node:child_process';
import { mkdtempSync, rmSync, chmodSync } from 'node:fs';
import net from 'node:net';
import os from 'node:os';
import path from 'node:path';

const SERVER = path.resolve(process.argv[2] || 'build/ctcsim-server');
const JOBS = Number(process.argv[3] || 2000);
const MODE = process.argv[4] || 'jobs';
if (MODE !== 'jobs' && MODE !== 'family') throw new Error(`the mode is jobs or family, not ${MODE}`);
const JOB = { preset: 'triple_pendulum_pid', name: 'bench', duration: 0.1 };
const CLIENTS = 16;

const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
const procs = new Set();
process.on('exit', () => procs.forEach((p) => p.kill('SIGKILL')));

function freePort() {
    return new Promise((resolve) => {
        const s = net.createServer();
        s.listen(0, '127.0.0.1', () => {
            const { port } = s.address();
            s.close(() => resolve(port));
        });
    });
}

function start(args) {
    const p = spawn(SERVER, args, { stdio: ['ignore', 'ignore', 'pipe'] });
    p.stderr.on('data', () => {});
    procs.add(p);
    return p;
}

async function stop(p) {
    const done = new Promise((r) => p.on('exit', r));
    p.kill('SIGTERM');
    await done;
    procs.delete(p);
}

async function health(base) {
    try {
        const r = await fetch(`${base}/api/health`);
        return r.status === 200 ? await r.json() : null;
    } catch {
        return null;
    }
}

/* posts one family of JOBS members, waits until none is queued or running; {seconds,
   wallMean, accept} (accept: s until the 202) */
async function runFamily(base) {
    const family = { name: 'bench', base: JOB, axes: [{ path: 'controller.kp', linspace: [50, 150, JOBS] }] };
    const t0 = performance.now();
    const r = await fetch(`${base}/api/families`, { method: 'POST', headers: { 'content-type': 'application/json' }, body: JSON.stringify(family) });
    if (r.status !== 202) throw new Error(`POST /api/families: ${r.status} ${await r.text()}`);
    const { id } = await r.json();
    const accept = (performance.now() - t0) / 1000;
    for (;;) {
        const l = await fetch(`${base}/api/families?limit=1`);
        const f = l.status === 200 ? (await l.json()).families.find((x) => x.id === id) : null;
        if (f && f.counts.queued + f.counts.running === 0) break;
        await sleep(50);
    }
    const seconds = (performance.now() - t0) / 1000;
    /* the workers' own time per member, from the family's table */
    const table = await (await fetch(`${base}/api/families/${id}`)).json();
    const walls = table.table.rows.map((m) => m.wall_s).filter((w) => typeof w === 'number');
    if (walls.length !== JOBS) throw new Error(`${JOBS - walls.length} members did not finish`);
    return { seconds, wallMean: walls.reduce((a, w) => a + w, 0) / walls.length, accept };
}

/* posts JOBS jobs from CLIENTS clients, waits until all are done; {seconds, wallMean} */
async function run(base) {
    for (let i = 0; !(await health(base)); i++) {
        if (i > 200) throw new Error(`no server at ${base}`);
        await sleep(50);
    }
    if (MODE === 'family') return runFamily(base);
    const body = JSON.stringify(JOB);
    const t0 = performance.now();
    let next = 0;
    await Promise.all(Array.from({ length: CLIENTS }, async () => {
        while (next < JOBS) {
            next++;
            const r = await fetch(`${base}/api/jobs`, { method: 'POST', headers: { 'content-type': 'application/json' }, body });
            if (r.status !== 202) throw new Error(`POST: ${r.status} ${await r.text()}`);
            await r.arrayBuffer();
        }
    }));
    for (;;) {
        const h = await health(base);
        if (h && h.jobs.done + h.jobs.failed + h.jobs.diverged >= JOBS) break;
        await sleep(20);
    }
    const seconds = (performance.now() - t0) / 1000;
    /* the workers' own time per job, from the newest 200 rows */
    const list = await (await fetch(`${base}/api/jobs?limit=200`)).json();
    const wallMean = list.jobs.reduce((a, j) => a + j.wall_s, 0) / list.jobs.length;
    return { seconds, wallMean };
}

const common = ['--max-queue', String(JOBS + 10), '--max-jobs-per-client', String(JOBS + 10), '--web', os.tmpdir()];
const dir = mkdtempSync(path.join(os.tmpdir(), 'ctcsim-bench-'));
chmodSync(dir, 0o755);
const rows = [];
let pgUrl = null;
try {
    const pg = spawnSync('sh', ['tests/pg/start.sh', path.join(dir, 'pg')], { encoding: 'utf8' });
    if (pg.status !== 0) throw new Error(`PostgreSQL did not start: ${pg.stderr}`);
    pgUrl = pg.stdout.trim();
    for (const workers of [1, 2, 3]) {
        /* SQLite: one process with `workers` worker threads */
        const port = await freePort();
        const s = start(['--port', String(port), '--db', path.join(dir, `sqlite${workers}.db`), '--workers', String(workers), ...common]);
        const a = await run(`http://127.0.0.1:${port}`);
        await stop(s);
        rows.push({ backend: 'sqlite', workers, ...a });

        /* PostgreSQL: one API process and `workers` worker processes of one worker each */
        const db = `bench${workers}`;
        spawnSync('psql', [pgUrl, '-qc', `CREATE DATABASE ${db}`]);
        const url = pgUrl.replace(/\/ctcsim$/, `/${db}`);
        const apiPort = await freePort();
        const api = start(['--port', String(apiPort), '--db', url, '--role', 'api', ...common]);
        await sleep(300); /* the schema, made by the first process */
        const ws = Array.from({ length: workers }, () => start(['--db', url, '--role', 'worker', '--workers', '1']));
        const b = await run(`http://127.0.0.1:${apiPort}`);
        await Promise.all([...ws, api].map(stop));
        rows.push({ backend: 'postgres', workers, ...b });
    }
} finally {
    if (pgUrl) spawnSync('sh', ['tests/pg/stop.sh', path.join(dir, 'pg')]);
    rmSync(dir, { recursive: true, force: true });
}

console.log(MODE === 'family'
    ? `one family of ${JOBS} members (${JOB.preset}, ${JOB.duration} s), ${os.cpus().length} cores`
    : `${JOBS} jobs (${JOB.preset}, ${JOB.duration} s), ${CLIENTS} clients, ${os.cpus().length} cores`);
console.log(`backend   workers  jobs/s  overhead/job (ms)  simulation/job (ms)${MODE === 'family' ? '  accepted in (s)' : ''}`);
for (const r of rows) {
    const overhead = (r.workers * r.seconds) / JOBS - r.wallMean;
    console.log(`${r.backend.padEnd(9)} ${String(r.workers).padStart(7)} ${(JOBS / r.seconds).toFixed(0).padStart(7)} ${(overhead * 1000).toFixed(2).padStart(18)} ${(r.wallMean * 1000).toFixed(3).padStart(20)}${r.accept !== undefined ? r.accept.toFixed(2).padStart(17) : ''}`);
}
