/*
 * soak.mjs - ctcsim-server under load and faults at once, and a count of the jobs it loses
 * (issue 25's soak; run it with bench/soak.sh, which bench/README.md describes).
 *
 * One server on loopback with a database in a temporary directory. For SOAK_SECONDS:
 *   - SOAK_CLIENTS submitters POST small, medium and long jobs (presets; one in five with
 *     ?wait=10),
 *     pausing while SOAK_MAX_PENDING accepted jobs are not yet final, so that the queue can drain;
 *   - SOAK_READERS readers GET /api/health, a job, a finished job's series (decimated), the list;
 *   - one canceller DELETEs about three times a second a random job of the SOAK_CANCEL_SHARE
 *     (0.25) of them picked for it at submission (a queued one is cancelled, a running one asked
 *     to stop, a finished one deleted); the others are left alone, so that a job a fault strands
 *     is not hidden by a delete;
 *   - every SOAK_KILL_EVERY seconds the server is SIGKILLed and started again on the same
 *     database and port, except in the last half interval: a restart re-queues what a fault left
 *     stranded, and the run should end with faults no restart hides;
 *   - every SOAK_LOCK_EVERY seconds (first at a quarter of that, so that with the defaults a lock
 *     falls between two kills and the last one after the last kill) the sqlite3 command holds the database
 *     write-locked (BEGIN EXCLUSIVE) for SOAK_LOCK_SECONDS from another process (8 s by default:
 *     longer than the server's busy timeout, 5 s).
 * Then it waits up to SOAK_DRAIN seconds for every accepted job to be final (done, failed,
 * diverged, cancelled) or deleted by the canceller (it stops waiting sooner when the server has had
 * no busy worker and nothing queued for 10 s), and reports:
 *   - jobs accepted (a 200 or 202 with an id), and how they ended; failures with their reasons;
 *   - lost: accepted, never deleted, and after the drain missing from GET /api/jobs, still
 *     queued or running, or with another status than the final one a client once read (a DELETE
 *     cut off by a kill may have deleted its job: such a job counts as deleted). The exit status
 *     is 1 when any is lost or the server exited by itself, 2 on a setup error, 0 otherwise;
 *   - jobs the database holds that no client was told of (a POST whose answer a SIGKILL cut
 *     off), and how many of those are still queued or running;
 *   - latency of GET /api/health and of POST /api/jobs without ?wait: p50, p99, max, over the
 *     requests that were answered (refused connections while the server restarts are counted
 *     apart, as are requests that took more than SOAK_REQUEST_TIMEOUT seconds);
 *   - peak RSS: the largest VmHWM (/proc/PID/status, read every 0.5 s and before each kill) over
 *     the server's incarnations.
 * SOAK_JSON=FILE also writes the figures as one JSON object. The directory is removed at exit
 * unless SOAK_KEEP=1 (the database and each incarnation's output stay there).
 *
 * usage: node bench/soak.mjs [SERVER]   (default $CTCSIM_SERVER or build/ctcsim-server)
 * Needs Node 18 or later and the sqlite3 command; no npm packages.
 */
import { spawn } from 'node:child_process';
import { mkdtempSync, readFileSync, rmSync, writeFileSync, existsSync } from 'node:fs';
import net from 'node:net';
import os from 'node:os';
import path from 'node:path';

const env = (name, fallback) => {
    const v = process.env[name];
    if (v === undefined || v === '') return fallback;
    const x = Number(v);
    if (!Number.isFinite(x) || x < 0) {
        console.error(`soak: ${name} must be a number >= 0 (got "${v}")`);
        process.exit(2);
    }
    return x;
};

const cfg = {
    server: path.resolve(process.argv[2] || process.env.CTCSIM_SERVER || 'build/ctcsim-server'),
    seconds: env('SOAK_SECONDS', 120),
    killEvery: env('SOAK_KILL_EVERY', 20),
    lockEvery: env('SOAK_LOCK_EVERY', 20),
    lockSeconds: env('SOAK_LOCK_SECONDS', 8),
    clients: env('SOAK_CLIENTS', 4),
    readers: env('SOAK_READERS', 4),
    workers: env('SOAK_WORKERS', 2),
    maxPending: env('SOAK_MAX_PENDING', 24),
    cancelShare: env('SOAK_CANCEL_SHARE', 0.25),
    drain: env('SOAK_DRAIN', 120),
    requestTimeout: env('SOAK_REQUEST_TIMEOUT', 30),
};

/* the jobs submitted, equally often: small (tens of ms), medium (about 0.3 to 1 s on one core)
   and long (about 2 s), so that jobs are running and queued when a lock or a kill comes */
const JOBS = [
    { kind: 'small', body: { preset: 'triple_pendulum_pd', duration: 2 } },
    { kind: 'small', body: { preset: 'spatial_double_pendulum_lqr', duration: 2 } },
    { kind: 'small', body: { preset: 'five_bar_pd', duration: 3 } },
    {
        kind: 'medium',
        body: { preset: 'n_link_pendulum', n: 128, duration: 3, integrator: { method: 'rk4', step: 0.001 } },
    },
    {
        kind: 'medium',
        body: { preset: 'n_link_pendulum', n: 256, duration: 3, integrator: { method: 'rk4', step: 0.001 } },
    },
    {
        kind: 'long',
        body: { preset: 'n_link_pendulum', n: 256, duration: 8, integrator: { method: 'rk4', step: 0.001 } },
    },
];
const FINAL = new Set(['done', 'failed', 'diverged', 'cancelled']);

const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
const pick = (a) => a[Math.floor(Math.random() * a.length)];

function freePort() {
    return new Promise((resolve, reject) => {
        const s = net.createServer();
        s.on('error', reject);
        s.listen(0, '127.0.0.1', () => {
            const { port } = s.address();
            s.close(() => resolve(port));
        });
    });
}

/* ---- the server's incarnations ---- */

const dir = mkdtempSync(path.join(os.tmpdir(), 'ctcsim-soak-'));
const db = path.join(dir, 'soak.db');
const port = await freePort();
const base = `http://127.0.0.1:${port}`;
const incarnations = []; /* {pid, hwmKiB, startMs, exit} */
let server = null; /* the live child, or null while it restarts */

function readHwm(inc) {
    try {
        const m = /VmHWM:\s+(\d+) kB/.exec(readFileSync(`/proc/${inc.pid}/status`, 'utf8'));
        if (m) inc.hwmKiB = Math.max(inc.hwmKiB, Number(m[1]));
    } catch {
        /* gone */
    }
}

/* Starts the server as a supervisor would (systemd's Restart=on-failure): a start that exits
 * (the database locked past the busy timeout while it recovers jobs: exit 3) is counted with its
 * last line and tried again a second later, for up to 60 s. */
const failedStarts = new Map(); /* "exit 3: ...database is locked" -> count */
async function startServer() {
    const t0 = Date.now();
    for (;;) {
        const inc = await startOnce();
        if (!inc.exit) return inc;
        const line = inc.out.trim().split('\n').pop() || '';
        count(failedStarts, `exit ${inc.exit.code ?? inc.exit.signal}: ${line.replace(/\/tmp\/\S+/g, 'DB')}`);
        if (Date.now() - t0 > 60000) throw new Error(`the server did not start within 60 s:\n${inc.out}`);
        await sleep(1000);
    }
}

/* one start: resolves the incarnation once it answers health, or once it exits */
async function startOnce() {
    const n = incarnations.length;
    const proc = spawn(
        cfg.server,
        ['--bind', '127.0.0.1', '--port', String(port), '--db', db, '--workers', String(cfg.workers)],
        { stdio: ['ignore', 'pipe', 'pipe'] },
    );
    const inc = { pid: proc.pid, hwmKiB: 0, startMs: 0, exit: null, proc, out: '' };
    const keep = (c) => {
        inc.out += c.toString('utf8');
        if (inc.out.length > 1 << 16) inc.out = inc.out.slice(-(1 << 16));
    };
    proc.stdout.on('data', keep);
    proc.stderr.on('data', keep);
    inc.exited = new Promise((resolve) =>
        proc.on('close', (code, signal) => {
            inc.exit = { code, signal };
            writeFileSync(path.join(dir, `server-${n}.log`), inc.out);
            resolve(inc.exit);
        }),
    );
    incarnations.push(inc);
    const t0 = Date.now();
    for (;;) {
        if (inc.exit) {
            await inc.exited; /* its output is complete */
            return inc;
        }
        try {
            const r = await fetch(`${base}/api/health`, { signal: AbortSignal.timeout(5000) });
            await r.text();
            if (r.status === 200 || r.status === 503) break;
        } catch {
            /* not listening yet */
        }
        if (Date.now() - t0 > 60000) throw new Error(`the server did not answer within 60 s:\n${inc.out}`);
        await sleep(50);
    }
    inc.startMs = Date.now() - t0;
    server = inc;
    return inc;
}

/* ---- requests and their figures ---- */

const lat = { health: [], post: [] }; /* ms of answered requests */
const refused = { health: 0, post: 0, other: 0 }; /* no answer: connection refused or reset */
const timedOut = { health: 0, post: 0, other: 0 };
const postRefusals = new Map(); /* "503 QUEUE_FULL" -> count */
const count = (m, k) => m.set(k, (m.get(k) || 0) + 1);

/* One request; resolves {status, json} or null when no answer came (counted under kind). */
async function call(kind, method, urlPath, body) {
    const init = { method, signal: AbortSignal.timeout(cfg.requestTimeout * 1000) };
    if (body !== undefined) {
        init.body = JSON.stringify(body);
        init.headers = { 'content-type': 'application/json' };
    }
    const t0 = performance.now();
    try {
        const r = await fetch(base + urlPath, init);
        const text = await r.text();
        const ms = performance.now() - t0;
        if (lat[kind]) lat[kind].push(ms);
        let json;
        try {
            json = JSON.parse(text);
        } catch {
            json = undefined;
        }
        return { status: r.status, json };
    } catch (e) {
        const slot = kind in refused ? kind : 'other';
        if (e.name === 'TimeoutError' || e.name === 'AbortError') timedOut[slot]++;
        else refused[slot]++;
        return null;
    }
}

/* ---- what the clients know of the jobs ---- */

const jobs = new Map(); /* id -> {kind, status, deleted, cancel, target, deleteUnanswered} */
let pending = 0; /* accepted, not final, not deleted */

function setStatus(id, status) {
    const j = jobs.get(id);
    if (!j || j.deleted) return;
    const wasFinal = FINAL.has(j.status);
    j.status = status;
    if (!wasFinal && FINAL.has(status)) pending--;
}

function markDeleted(id) {
    const j = jobs.get(id);
    if (!j || j.deleted) return;
    if (!FINAL.has(j.status)) pending--;
    j.deleted = true;
}

let running = true;

async function submitter() {
    while (running) {
        if (pending >= cfg.maxPending) {
            await sleep(100);
            continue;
        }
        const job = pick(JOBS);
        const wait = Math.random() < 0.2;
        const r = await call(wait ? 'other' : 'post', 'POST', wait ? '/api/jobs?wait=10' : '/api/jobs', job.body);
        if (r && (r.status === 200 || r.status === 202) && r.json && Number.isInteger(r.json.id)) {
            if (!jobs.has(r.json.id)) {
                jobs.set(r.json.id, {
                    kind: job.kind,
                    status: 'queued',
                    deleted: false,
                    cancel: false,
                    target: Math.random() < cfg.cancelShare,
                });
                pending++;
            }
            setStatus(r.json.id, r.json.status);
        } else if (r) {
            count(postRefusals, `${r.status} ${r.json?.error?.code ?? ''}`.trim());
            if (r.status === 503) await sleep(200);
        } else {
            await sleep(100);
        }
        await sleep(20 + Math.random() * 80);
    }
}

function randomJob(filter) {
    const ids = [...jobs.keys()].filter((id) => filter(jobs.get(id)));
    return ids.length ? pick(ids) : null;
}

async function reader() {
    while (running) {
        const what = Math.random();
        if (what < 0.4) {
            await call('health', 'GET', '/api/health');
        } else if (what < 0.7) {
            const id = randomJob((j) => !j.deleted && !FINAL.has(j.status)) ?? randomJob((j) => !j.deleted);
            if (id !== null) {
                const r = await call('other', 'GET', `/api/jobs/${id}`);
                if (r && r.status === 200 && r.json) setStatus(id, r.json.status);
            }
        } else if (what < 0.9) {
            const id = randomJob((j) => !j.deleted && j.status === 'done');
            if (id !== null) await call('other', 'GET', `/api/jobs/${id}/series?every=20&channels=q`);
        } else {
            await call('other', 'GET', '/api/jobs?limit=20');
        }
        await sleep(20 + Math.random() * 60);
    }
}

const deletes = new Map(); /* "200" -> count */
async function canceller() {
    while (running) {
        await sleep(150 + Math.random() * 300);
        const id = randomJob((j) => j.target && !j.deleted);
        if (id === null) continue;
        const r = await call('other', 'DELETE', `/api/jobs/${id}`);
        if (!r) {
            jobs.get(id).deleteUnanswered = true;
            continue;
        }
        count(deletes, String(r.status));
        if (r.status === 204) markDeleted(id);
        else if (r.status === 200 || r.status === 202) {
            jobs.get(id).cancel = true;
            if (r.json?.status) setStatus(id, r.json.status);
        }
    }
}

/* ---- the faults ---- */

let kills = 0;
const restartMs = [];
async function killer() {
    /* no kill in the last half interval: a restart re-queues the jobs a fault left stranded, so
       the faults of the final stretch (a lock) would otherwise go unseen */
    const killsEnd = Date.now() + (cfg.seconds - cfg.killEvery / 2) * 1000;
    let next = Date.now() + cfg.killEvery * 1000;
    while (running && cfg.killEvery > 0) {
        await sleep(100);
        if (Date.now() < next || !running) continue;
        if (Date.now() > killsEnd) break;
        const inc = server;
        readHwm(inc);
        server = null;
        inc.proc.kill('SIGKILL');
        await inc.exited;
        kills++;
        const t0 = Date.now();
        await startServer();
        restartMs.push(Date.now() - t0);
        next += cfg.killEvery * 1000; /* on a fixed clock, whatever the restart took */
    }
}

const locks = { held: 0, failed: 0, errors: [] };
async function lockOnce(n) {
    const marker = path.join(dir, `locked-${n}`);
    const script =
        `.timeout 10000\nBEGIN EXCLUSIVE;\n.system touch '${marker}'\n` +
        `.system sleep ${cfg.lockSeconds}\nCOMMIT;\n`;
    const proc = spawn('sqlite3', ['-bail', db], { stdio: ['pipe', 'ignore', 'pipe'] });
    let err = '';
    proc.stderr.on('data', (c) => (err += c.toString('utf8')));
    const done = new Promise((resolve) => proc.on('close', (code) => resolve(code)));
    proc.on('error', (e) => (err += String(e)));
    proc.stdin.end(script);
    const code = await done;
    if (code === 0 && existsSync(marker)) locks.held++;
    else {
        locks.failed++;
        locks.errors.push(err.trim() || `exit ${code}`);
    }
}

async function locker() {
    if (cfg.lockEvery <= 0) return;
    let next = Date.now() + (cfg.lockEvery * 1000) / 4;
    let n = 0;
    while (running) {
        await sleep(100);
        if (Date.now() < next || !running) continue;
        await lockOnce(n++);
        next += cfg.lockEvery * 1000;
    }
}

/* samples VmHWM, and restarts a server that exited without being killed (counted as a crash) */
let crashes = 0;
async function sampler() {
    while (running) {
        if (server && server.exit) {
            crashes++;
            server = null;
            await startServer();
        }
        if (server) readHwm(server);
        await sleep(500);
    }
}

/* ---- the end: drain, then count ---- */

function percentile(xs, p) {
    if (!xs.length) return null;
    const s = [...xs].sort((a, b) => a - b);
    return s[Math.min(s.length - 1, Math.ceil((p / 100) * s.length) - 1)];
}

function latencySummary(xs) {
    const f = (x) => (x === null ? null : Math.round(x * 10) / 10);
    return { n: xs.length, p50: f(percentile(xs, 50)), p99: f(percentile(xs, 99)), max: f(percentile(xs, 100)) };
}

/* every job the database holds, through the list (newest first) */
async function listAll() {
    const all = new Map();
    let cursor = null;
    for (;;) {
        const r = await call('other', 'GET', `/api/jobs?limit=200${cursor ? `&cursor=${cursor}` : ''}`);
        if (!r || r.status !== 200) return null;
        for (const row of r.json.jobs) all.set(row.id, row.status);
        if (r.json.next_cursor === null || r.json.next_cursor === undefined) return all;
        cursor = r.json.next_cursor;
    }
}

/* Polls the open jobs until each is final or gone, or the deadline passes, or the server has
 * been idle (no busy worker, nothing queued: GET /api/health) for 10 s with jobs still open:
 * nothing will move them then. */
async function drain() {
    const deadline = Date.now() + cfg.drain * 1000;
    let idleSince = null;
    for (;;) {
        let left = 0;
        for (const [id, j] of jobs) {
            if (j.deleted || FINAL.has(j.status)) continue;
            const r = await call('other', 'GET', `/api/jobs/${id}`);
            if (r && r.status === 200) setStatus(id, r.json.status);
            if (!FINAL.has(j.status)) left++;
        }
        if (left === 0 || Date.now() > deadline) return;
        const h = await call('other', 'GET', '/api/health');
        const idle = h && h.json && h.json.busy === 0 && h.json.queued === 0;
        idleSince = idle ? (idleSince ?? Date.now()) : null;
        if (idle && Date.now() - idleSince > 10000) return;
        await sleep(500);
    }
}

/* The last word, from the list of every stored job: each accepted job not deleted must be there
 * and final, and a job once seen final must still have that status. A job whose DELETE got no
 * answer (cut off by a kill) may be gone: it counts as deleted. */
function sweep(stored) {
    const missing = [];
    const stuck = [];
    const changed = [];
    for (const [id, j] of jobs) {
        if (j.deleted) continue;
        const st = stored.get(id);
        if (st === undefined) {
            if (j.deleteUnanswered) markDeleted(id);
            else missing.push(id);
            continue;
        }
        if (!FINAL.has(st)) stuck.push(id);
        else if (FINAL.has(j.status) && j.status !== st) changed.push(`${id} ${j.status}->${st}`);
        else setStatus(id, st);
    }
    return { missing, stuck, changed };
}

function reasonKey(message) {
    return (message || 'no message').replace(/-?\d+(\.\d+)?(e[-+]?\d+)?/gi, '#').slice(0, 120);
}

async function main() {
    if (!existsSync(cfg.server)) {
        console.error(`soak: no server at ${cfg.server} (make build/ctcsim-server, or give its path)`);
        process.exit(2);
    }
    const t0 = Date.now();
    await startServer();
    /* a task that fails (the server would not start again) ends the load at once */
    let taskError = null;
    const guard = (p) =>
        p.catch((e) => {
            taskError = taskError || e;
            running = false;
        });
    const tasks = [killer(), locker(), sampler(), canceller()];
    for (let i = 0; i < cfg.clients; i++) tasks.push(submitter());
    for (let i = 0; i < cfg.readers; i++) tasks.push(reader());
    const guarded = tasks.map(guard);
    while (running && Date.now() - t0 < cfg.seconds * 1000) await sleep(100);
    running = false;
    await Promise.all(guarded);
    if (taskError) throw taskError;
    const loadSeconds = (Date.now() - t0) / 1000;

    const drained0 = Date.now();
    await drain();
    const drainSeconds = (Date.now() - drained0) / 1000;
    const stored = await listAll();
    if (!stored) throw new Error('GET /api/jobs failed after the drain');
    const { missing, stuck, changed } = sweep(stored);
    const lost = missing.length + stuck.length + changed.length;

    /* how the accepted jobs ended, and why the failed ones failed */
    const ended = {};
    const reasons = new Map();
    for (const [id, j] of jobs) {
        const k = j.deleted
            ? 'deleted'
            : missing.includes(id)
              ? 'missing'
              : stuck.includes(id)
                ? 'stuck'
                : j.status;
        ended[k] = (ended[k] || 0) + 1;
        if (!j.deleted && (j.status === 'failed' || j.status === 'diverged')) {
            const r = await call('other', 'GET', `/api/jobs/${id}`);
            count(reasons, `${j.status}: ${reasonKey(r?.json?.message)}`);
        }
    }
    let unacknowledged = 0;
    let unacknowledgedOpen = 0;
    for (const [id, status] of stored) {
        if (jobs.has(id)) continue;
        unacknowledged++;
        if (!FINAL.has(status)) unacknowledgedOpen++;
    }
    const health = await call('other', 'GET', '/api/health');
    readHwm(server);
    const last = server;
    last.proc.kill('SIGTERM');
    const lastExit = await Promise.race([last.exited, sleep(30000).then(() => null)]);
    if (!lastExit) last.proc.kill('SIGKILL');

    const hwm = incarnations.filter((i) => i.hwmKiB > 0).map((i) => i.hwmKiB);
    const figures = {
        server: cfg.server,
        settings: cfg,
        load_s: Math.round(loadSeconds),
        drain_s: Math.round(drainSeconds),
        kills,
        crashes,
        failed_starts: Object.fromEntries(failedStarts),
        restart_ms: restartMs,
        locks,
        jobs: {
            accepted: jobs.size,
            ended,
            lost,
            missing,
            stuck,
            changed,
            failed_reasons: Object.fromEntries(reasons),
            unacknowledged,
            unacknowledged_open: unacknowledgedOpen,
        },
        post_refused: Object.fromEntries(postRefusals),
        deletes: Object.fromEntries(deletes),
        no_answer: { refused, timed_out: timedOut },
        latency_ms: { health: latencySummary(lat.health), post: latencySummary(lat.post) },
        peak_rss_mib: Math.round(Math.max(...hwm) / 102.4) / 10,
        rss_by_incarnation_mib: hwm.map((k) => Math.round(k / 102.4) / 10),
        final_health: health?.json ?? null,
        last_exit: lastExit,
    };

    const L = figures.latency_ms;
    const out = [];
    out.push(`soak: ${figures.load_s} s of load on ${cfg.workers} workers, ${kills} SIGKILLs and restarts ` +
        `(restart ${Math.max(0, ...restartMs)} ms at most), ${locks.held} database locks of ${cfg.lockSeconds} s` +
        (locks.failed ? ` (${locks.failed} not taken: ${locks.errors[0]})` : ''));
    for (const [k, v] of failedStarts) out.push(`failed starts: ${v} x ${k}`);
    if (crashes) out.push(`CRASHES: the server exited by itself ${crashes} times (logs in ${dir})`);
    out.push(`jobs: ${jobs.size} accepted; ` + Object.entries(ended).map(([k, v]) => `${v} ${k}`).join(', ') +
        `; drained in ${figures.drain_s} s`);
    out.push(`lost: ${lost} (missing ${missing.length}, still queued or running ${stuck.length}, ` +
        `final status changed ${changed.length})` +
        (lost ? `: ${[...missing, ...stuck, ...changed].slice(0, 20).join(', ')}` : ''));
    for (const [k, v] of reasons) out.push(`  ${v} x ${k}`);
    out.push(`stored but never acknowledged (a POST cut by SIGKILL): ${unacknowledged}, ` +
        `of which still queued or running: ${unacknowledgedOpen}`);
    out.push(`POST refused: ${JSON.stringify(figures.post_refused)}; DELETE answers: ${JSON.stringify(figures.deletes)}`);
    out.push(`no answer: refused/reset ${JSON.stringify(refused)}, over ${cfg.requestTimeout} s ${JSON.stringify(timedOut)}`);
    out.push(`latency ms: health p50 ${L.health.p50} p99 ${L.health.p99} max ${L.health.max} (n ${L.health.n}); ` +
        `POST p50 ${L.post.p50} p99 ${L.post.p99} max ${L.post.max} (n ${L.post.n})`);
    out.push(`peak RSS: ${figures.peak_rss_mib} MiB (VmHWM over ${hwm.length} incarnations: ` +
        `${figures.rss_by_incarnation_mib.join(', ')} MiB)`);
    console.log(out.join('\n'));
    if (process.env.SOAK_JSON) writeFileSync(process.env.SOAK_JSON, JSON.stringify(figures, null, 2) + '\n');
    return lost === 0 && crashes === 0 ? 0 : 1;
}

let status = 2;
try {
    status = await main();
} catch (e) {
    console.error(`soak: ${e.stack || e}`);
} finally {
    running = false;
    for (const inc of incarnations) if (!inc.exit) inc.proc.kill('SIGKILL');
    if (process.env.SOAK_KEEP === '1' || status !== 0) console.error(`soak: kept ${dir}`);
    else rmSync(dir, { recursive: true, force: true });
}
process.exit(status);
