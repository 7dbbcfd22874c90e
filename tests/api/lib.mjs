/*
 * lib.mjs - what the black-box API tests share: a ctcsim-server process on a free port with its
 * own temporary database, requests (fetch, and raw node:http for what fetch would rewrite), job
 * polling, and the `ctcsim` command line as the reference the service must agree with.
 *
 * The binaries come from the environment: CTCSIM_SERVER (default build/ctcsim-server) and CTCSIM
 * (default build/ctcsim). With CTCSIM_TEST_PG set to the URL of a PostgreSQL database (one that
 * tests/pg/start.sh started), every server's database is a PostgreSQL database of its own, made
 * for its directory, and a server is a cluster: one `--role api` process and
 * CTCSIM_TEST_PG_WORKERS (default 2) `--role worker` processes sharing the --workers between them
 * (BACKEND says which; a test that is about SQLite itself skips on PostgreSQL, saying why). Each test file starts its own servers; every server and temporary
 * directory made here is killed and removed when the process exits, whatever happened
 * (CTCSIM_API_KEEP=1 keeps the directories for a post-mortem). Only Node 18 APIs are used, and no
 * npm packages.
 */
import { spawn, spawnSync } from 'node:child_process';
import { mkdtempSync, rmSync, statSync } from 'node:fs';
import { mkdir, writeFile } from 'node:fs/promises';
import http from 'node:http';
import net from 'node:net';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

export const ROOT = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '..', '..');
export const SERVER = path.resolve(ROOT, process.env.CTCSIM_SERVER || 'build/ctcsim-server');
export const CLI = path.resolve(ROOT, process.env.CTCSIM || 'build/ctcsim');

/* the server's command-line flags, in one place */
const FLAG = {
    port: '--port',
    db: '--db',
    workers: '--workers',
    web: '--web',
    api: '--api',
};

/* the backend under test: 'sqlite', or 'postgres' with CTCSIM_TEST_PG (see above) */
const PG = process.env.CTCSIM_TEST_PG || '';
export const BACKEND = PG ? 'postgres' : 'sqlite';
const PG_WORKERS = Number(process.env.CTCSIM_TEST_PG_WORKERS || 2);
/* the lease of the tests' worker processes: short, so that a killed worker's job comes back soon */
export const PG_LEASE = 2;

/* The PostgreSQL database of a test directory (made on first use): the URL of CTCSIM_TEST_PG with
 * the database name ctcsim_<directory's name>, so a server restarted on the same dir finds its
 * jobs again. */
export function pgDatabase(dir) {
    const name = `ctcsim_${path.basename(dir).toLowerCase().replace(/[^a-z0-9]/g, '_')}`;
    const r = spawnSync('psql', [PG, '-qAtc', `SELECT 1 FROM pg_database WHERE datname = '${name}'`], { encoding: 'utf8' });
    if (r.status !== 0) throw new Error(`psql ${PG}: ${r.stderr}`);
    if (r.stdout.trim() !== '1') {
        const c = spawnSync('psql', [PG, '-qc', `CREATE DATABASE ${name}`], { encoding: 'utf8' });
        if (c.status !== 0 && !/already exists/.test(c.stderr)) throw new Error(`psql: ${c.stderr}`);
    }
    return PG.replace(/\/[^/?]*(\?|$)/, `/${name}$1`);
}

export const FINAL = new Set(['done', 'failed', 'diverged', 'cancelled']);

/* ---- clean-up at exit ---- */

const live = new Set(); /* child processes still running */
const dirs = [];        /* temporary directories to remove */

process.on('exit', () => {
    for (const child of live) {
        try {
            child.kill('SIGKILL');
        } catch {
            /* already gone */
        }
    }
    if (process.env.CTCSIM_API_KEEP) {
        if (dirs.length) console.error(`# kept: ${dirs.join(' ')}`);
        return;
    }
    for (const d of dirs) rmSync(d, { recursive: true, force: true });
});

/* A new temporary directory, removed at exit. */
export function tempDir(prefix = 'ctcsim-api-') {
    const d = mkdtempSync(path.join(os.tmpdir(), prefix));
    dirs.push(d);
    return d;
}

export const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

/* A TCP port that was free a moment ago: bind port 0, read it, close. */
export function freePort() {
    return new Promise((resolve, reject) => {
        const s = net.createServer();
        s.unref();
        s.on('error', reject);
        s.listen(0, '127.0.0.1', () => {
            const { port } = s.address();
            s.close(() => resolve(port));
        });
    });
}

/* Polls fn() every intervalMs until it returns a truthy value (returned) or timeoutMs passes
 * (throws, with what(last value) as the message when given). */
export async function waitFor(fn, { timeoutMs = 10000, intervalMs = 50, what } = {}) {
    const end = Date.now() + timeoutMs;
    let last;
    for (;;) {
        last = await fn();
        if (last) return last;
        if (Date.now() > end) {
            throw new Error(`timed out after ${timeoutMs} ms: ${what ? what(last) : 'condition'}`);
        }
        await sleep(intervalMs);
    }
}

/* Waits until /api/health shows no busy worker and no queued job, and returns it. A worker frees
 * its slot just after it stores its job's final status, so a job may read final a moment before
 * its worker stops counting as busy. */
export function waitIdle(srv, { timeoutMs = 5000 } = {}) {
    return waitFor(
        async () => {
            const r = await srv.get('/api/health');
            return r.json.busy === 0 && r.json.queued === 0 ? r : null;
        },
        { timeoutMs, what: () => 'the workers to be idle' },
    );
}

/* ---- requests ---- */

function parseBody(text) {
    try {
        return JSON.parse(text);
    } catch {
        return undefined;
    }
}

/* One request with fetch. opts: json (sent as application/json), body (sent as it is), headers,
 * signal (an AbortSignal, e.g. AbortSignal.timeout(ms), to bound the wait). Resolves {status, headers (lower-case names), text, json (undefined if not JSON)}. */
export async function request(base, method, urlPath, opts = {}) {
    const headers = { ...(opts.headers || {}) };
    const init = { method, headers };
    if (opts.signal) init.signal = opts.signal;
    if (opts.json !== undefined) {
        init.body = JSON.stringify(opts.json);
        if (!Object.keys(headers).some((h) => h.toLowerCase() === 'content-type')) {
            headers['content-type'] = 'application/json';
        }
    } else if (opts.body !== undefined) {
        init.body = opts.body;
    }
    const res = await fetch(base + urlPath, init);
    const text = await res.text();
    return {
        status: res.status,
        headers: Object.fromEntries(res.headers),
        text,
        json: parseBody(text),
    };
}

/* One request with node:http, the path sent byte for byte (fetch would resolve "..", "%2e%2e")
 * and no header added but Host and, with a body, Content-Length. Resolves as request(). */
export function rawRequest(port, method, rawPath, opts = {}) {
    return new Promise((resolve, reject) => {
        let answered = false;
        const req = http.request(
            { host: '127.0.0.1', port, method, path: rawPath, headers: opts.headers || {}, agent: false },
            (res) => {
                answered = true;
                const chunks = [];
                res.on('data', (c) => chunks.push(c));
                res.on('error', reject);
                res.on('end', () => {
                    const text = Buffer.concat(chunks).toString('utf8');
                    resolve({ status: res.statusCode, headers: res.headers, text, json: parseBody(text) });
                });
            },
        );
        /* a server may answer (413) and close before the whole body is written */
        req.on('error', (e) => {
            if (!answered) reject(e);
        });
        if (opts.body !== undefined) req.end(opts.body);
        else req.end();
    });
}

/* A client holding one keep-alive connection (node:http), to see whether requests on an idle
 * connection are answered while other requests are in flight. get(path) resolves {status, ms};
 * close() drops the connection. */
export function keepAliveClient(port) {
    const agent = new http.Agent({ keepAlive: true, maxSockets: 1 });
    return {
        get(urlPath) {
            return new Promise((resolve, reject) => {
                const t0 = Date.now();
                http.get({ host: '127.0.0.1', port, path: urlPath, agent }, (res) => {
                    res.resume();
                    res.on('end', () => resolve({ status: res.statusCode, ms: Date.now() - t0 }));
                }).on('error', reject);
            });
        },
        close() {
            agent.destroy();
        },
    };
}

/* ---- the server ---- */

export class Server {
    constructor(proc, port, dir, db) {
        this.proc = proc;
        this.port = port;
        this.base = `http://127.0.0.1:${port}`;
        this.dir = dir;
        this.db = db;
        this.out = '';
        this.exited = null; /* {code, signal} once it exits */
        this.exit = new Promise((resolve) => {
            proc.on('exit', (code, signal) => {
                live.delete(proc);
                this.exited = { code, signal };
                resolve(this.exited);
            });
        });
        const keep = (chunk) => {
            this.out += chunk.toString('utf8');
            if (this.out.length > 65536) this.out = this.out.slice(-65536);
        };
        proc.stdout.on('data', keep);
        proc.stderr.on('data', keep);
    }

    /* what the server printed, last 64 KiB */
    output() {
        return this.out + (this.workers || []).map((w, i) => `\n--- worker process ${i} ---\n${w.out}`).join('');
    }

    request(method, urlPath, opts) {
        return request(this.base, method, urlPath, opts);
    }

    get(urlPath, opts) {
        return request(this.base, 'GET', urlPath, opts);
    }

    post(urlPath, json, headers) {
        return request(this.base, 'POST', urlPath, { json, headers });
    }

    del(urlPath, headers) {
        return request(this.base, 'DELETE', urlPath, { headers });
    }

    raw(method, rawPath, opts) {
        return rawRequest(this.port, method, rawPath, opts);
    }

    /* Sends signal and waits for the exit, SIGKILL after timeoutMs. Resolves {code, signal, ms}. */
    async stop(signal = 'SIGTERM', timeoutMs = 10000) {
        /* a cluster's worker processes first, then the API process's answer */
        await Promise.all((this.workers || []).map((w) => w.stop(signal, timeoutMs)));
        const t0 = Date.now();
        if (!this.exited) this.proc.kill(signal);
        let timer;
        const late = new Promise((resolve) => {
            timer = setTimeout(() => resolve(null), timeoutMs);
        });
        let r = await Promise.race([this.exit, late]);
        clearTimeout(timer);
        if (!r) {
            this.proc.kill('SIGKILL');
            r = await this.exit;
            return { ...r, ms: Date.now() - t0, killed: true };
        }
        return { ...r, ms: Date.now() - t0 };
    }

    kill() {
        return this.stop('SIGKILL');
    }
}

/* The repository's web root, or a stand-in with an index.html while web/ does not exist yet. */
let defaultWeb;
async function webRoot() {
    if (defaultWeb) return defaultWeb;
    const repoWeb = path.join(ROOT, 'web');
    try {
        if (statSync(path.join(repoWeb, 'index.html')).isFile()) return (defaultWeb = repoWeb);
    } catch {
        /* not there yet */
    }
    const d = tempDir('ctcsim-web-');
    await writeFile(path.join(d, 'index.html'), '<!doctype html><title>ctcsim</title>\n');
    return (defaultWeb = d);
}

/* The environment without the server's CTCSIM_* settings (the flags given here must be all). */
function serverEnv() {
    const env = { ...process.env };
    for (const k of Object.keys(env)) if (k.startsWith('CTCSIM')) delete env[k];
    return env;
}

/* Starts ctcsim-server and waits until GET /api/health answers 200 (timeoutMs). opts: dir (the
 * directory of the database, to restart on the same one; default a new temporary one), workers
 * (2), web, api (the repository's api/), args (more flags). Throws with the server's output when
 * it exits or does not become healthy. */
export async function startServer(opts = {}) {
    const dir = opts.dir || tempDir();
    await mkdir(dir, { recursive: true });
    const db = PG ? pgDatabase(dir) : path.join(dir, 'jobs.db');
    const cluster = PG && PG_WORKERS > 0;
    const web = opts.web || (await webRoot());
    const api = opts.api || path.join(ROOT, 'api');
    const timeoutMs = opts.timeoutMs || 10000;
    for (let attempt = 0; ; attempt++) {
        const port = await freePort();
        const args = [
            FLAG.port, String(port),
            FLAG.db, db,
            FLAG.workers, String(opts.workers || 2),
            FLAG.web, web,
            FLAG.api, api,
            ...(cluster ? ['--role', 'api'] : []),
            ...(PG ? ['--lease', String(PG_LEASE)] : []),
            ...(opts.args || []),
        ];
        const proc = spawn(SERVER, args, { stdio: ['ignore', 'pipe', 'pipe'], env: serverEnv() });
        live.add(proc);
        const srv = new Server(proc, port, dir, db);
        /* a cluster: the --workers shared among PG_WORKERS worker processes */
        srv.workers = [];
        const total = opts.workers || 2;
        for (let i = 0; cluster && i < PG_WORKERS; i++) {
            const n = Math.floor(total / PG_WORKERS) + (i < total % PG_WORKERS ? 1 : 0);
            if (n === 0) continue;
            const wargs = [FLAG.db, db, FLAG.workers, String(n), '--role', 'worker', '--lease', String(PG_LEASE), ...(opts.args || [])];
            const wp = spawn(SERVER, wargs, { stdio: ['ignore', 'pipe', 'pipe'], env: serverEnv() });
            live.add(wp);
            srv.workers.push(new Server(wp, 0, dir, db));
        }
        const spawnError = new Promise((resolve) => proc.on('error', resolve));
        const t0 = Date.now();
        let why = null;
        for (;;) {
            const failed = await Promise.race([spawnError, sleep(50).then(() => null)]);
            if (failed) {
                why = `cannot start ${SERVER}: ${failed.message}`;
                break;
            }
            if (srv.exited) {
                why = `server exited (code ${srv.exited.code}, signal ${srv.exited.signal})`;
                break;
            }
            try {
                const h = await srv.get('/api/health');
                if (h.status === 200) return srv;
            } catch {
                /* not listening yet */
            }
            if (Date.now() - t0 > timeoutMs) {
                why = `no 200 from GET /api/health within ${timeoutMs} ms`;
                await srv.kill();
                break;
            }
        }
        /* another process may have taken the port between freePort and the bind */
        if (attempt < 2 && /in use/i.test(srv.output())) continue;
        throw new Error(`${why}\n  ${SERVER} ${args.join(' ')}\n--- server output ---\n${srv.output()}`);
    }
}

/* ---- jobs ---- */

/* The id in a 202's Location header ("/api/jobs/ID"). */
export function idOf(res) {
    const m = /^\/api\/jobs\/([0-9]+)$/.exec(res.headers.location || '');
    return m ? Number(m[1]) : res.json?.id;
}

/* Submits a job (POST /api/jobs); throws unless 202. Resolves the row. */
export async function submit(srv, job, headers) {
    const res = await srv.post('/api/jobs', job, headers);
    if (res.status !== 202) {
        throw new Error(`POST /api/jobs ${JSON.stringify(job)}: ${res.status} ${res.text}`);
    }
    return res.json;
}

/* Polls GET /api/jobs/{id} until until(job) holds (default: a final status). Resolves the job. */
export async function waitJob(srv, id, { until = (j) => FINAL.has(j.status), timeoutMs = 30000, intervalMs = 50 } = {}) {
    let last;
    return waitFor(
        async () => {
            const res = await srv.get(`/api/jobs/${id}`);
            if (res.status !== 200) throw new Error(`GET /api/jobs/${id}: ${res.status} ${res.text}`);
            last = res.json;
            return until(last) ? last : null;
        },
        { timeoutMs, intervalMs, what: () => `job ${id}: ${JSON.stringify(last && { status: last.status, progress: last.progress, message: last.message })}` },
    );
}

/* All rows of GET /api/jobs, following next_cursor with pages of `limit`. */
export async function listAll(srv, { limit = 50, status } = {}) {
    const rows = [];
    let cursor = null;
    for (let page = 0; page < 10000; page++) {
        let q = `?limit=${limit}`;
        if (cursor !== null) q += `&cursor=${cursor}`;
        if (status) q += `&status=${status}`;
        const res = await srv.get(`/api/jobs${q}`);
        if (res.status !== 200) throw new Error(`GET /api/jobs${q}: ${res.status} ${res.text}`);
        rows.push(...res.json.jobs);
        cursor = res.json.next_cursor;
        if (cursor === null || cursor === undefined) return rows;
    }
    throw new Error('GET /api/jobs: next_cursor never ends');
}

/* ---- the command line ---- */

/* Runs `ctcsim ARGS...`. Resolves {code, stdout, stderr}. */
export function runCli(args, { input } = {}) {
    return new Promise((resolve, reject) => {
        const child = spawn(CLI, args, { stdio: ['pipe', 'pipe', 'pipe'] });
        live.add(child);
        const out = [];
        const err = [];
        child.stdout.on('data', (c) => out.push(c));
        child.stderr.on('data', (c) => err.push(c));
        child.on('error', reject);
        child.stdin.on('error', () => {}); /* it may exit before reading its input */
        child.on('close', (code) => {
            live.delete(child);
            resolve({ code, stdout: Buffer.concat(out).toString('utf8'), stderr: Buffer.concat(err).toString('utf8') });
        });
        child.stdin.end(input === undefined ? '' : input);
    });
}

let cliDir;
let cliCount = 0;

/* The CSV `ctcsim run FILE --quiet ARGS...` writes for a job document (written to a temporary
 * file first). Throws unless the run exits 0. */
export async function cliCsv(spec, args = []) {
    cliDir ??= tempDir('ctcsim-cli-');
    const file = path.join(cliDir, `job${++cliCount}.json`);
    await writeFile(file, typeof spec === 'string' ? spec : JSON.stringify(spec));
    const r = await runCli(['run', file, '--quiet', ...args]);
    if (r.code !== 0) throw new Error(`ctcsim run ${file}: exit ${r.code}: ${r.stderr}`);
    return r.stdout;
}

/* Runs async fn over items, at most n at a time; resolves the results in order. */
export async function mapLimit(items, n, fn) {
    const results = new Array(items.length);
    let next = 0;
    const worker = async () => {
        while (next < items.length) {
            const i = next++;
            results[i] = await fn(items[i], i);
        }
    };
    await Promise.all(Array.from({ length: Math.min(n, items.length) }, worker));
    return results;
}

/* Parses CSV text into {header: [...], rows: [[...strings]]}. */
export function parseCsv(text) {
    const lines = text.split('\n');
    if (lines[lines.length - 1] === '') lines.pop();
    return { header: lines[0].split(','), rows: lines.slice(1).map((l) => l.split(',')) };
}
