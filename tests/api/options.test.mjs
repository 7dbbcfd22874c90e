/*
 * options.test.mjs - ctcsim-server's options and their environment variables: every option that
 * `--help` lists names its variable, the server reads each one (a bad value is refused at start
 * with exit 2 and a message naming the variable), a good CTCSIM_HTTP_THREADS starts it, and the
 * README documents every option with its variable.
 */
import assert from 'node:assert/strict';
import { spawn, spawnSync } from 'node:child_process';
import { readFileSync } from 'node:fs';
import path from 'node:path';
import test from 'node:test';

import { ROOT, SERVER, freePort, request, sleep, tempDir } from './lib.mjs';

/* the environment without any CTCSIM_* setting, plus extra */
function envWith(extra) {
    const env = { ...process.env };
    for (const k of Object.keys(env)) if (k.startsWith('CTCSIM')) delete env[k];
    return { ...env, ...extra };
}

/* [{flag, env}] of --help: "  --flag ARG  help" then "  (default ...; VARIABLE)" */
function options() {
    const r = spawnSync(SERVER, ['--help'], { encoding: 'utf8', env: envWith({}) });
    assert.equal(r.status, 0, r.stderr);
    const lines = r.stdout.split('\n');
    const out = [];
    for (let i = 0; i < lines.length; i++) {
        const m = /^ {2}(--[a-z-]+) [A-Z]+ /.exec(lines[i]);
        if (!m) continue;
        const d = /\(default .*?(?:; (CTCSIM_[A-Z_]+))?\)$/.exec(lines[i + 1] || '');
        assert.ok(d, `--help: no default line after ${m[1]}: "${lines[i + 1]}"`);
        out.push({ flag: m[1], env: d[1] });
    }
    return out;
}

/* options whose value "many" is not valid (numbers and addresses; the text ones take anything) */
const CHECKED = new Set(['--bind', '--port', '--workers', '--job-threads', '--max-queue', '--max-body',
    '--job-time-limit', '--http-threads', '--idle-timeout', '--max-connections', '--max-connections-per-ip']);

test('every option of --help has its environment variable, --http-threads too', () => {
    const opts = options();
    assert.ok(opts.length >= 12, `only ${opts.length} options in --help`);
    for (const o of opts) assert.ok(o.env, `${o.flag} has no environment variable in --help`);
    assert.deepEqual(opts.find((o) => o.flag === '--http-threads'), { flag: '--http-threads', env: 'CTCSIM_HTTP_THREADS' });
});

test('--help names both stores: SQLite for one process, PostgreSQL for --role api/worker', () => {
    const r = spawnSync(SERVER, ['--help'], { encoding: 'utf8', env: envWith({}) });
    assert.equal(r.status, 0, r.stderr);
    const intro = r.stdout.split('\n\n')[1].replace(/\s+/g, ' ');
    assert.match(intro, /SQLite/);
    assert.match(intro, /PostgreSQL/);
    assert.match(intro, /--db/);
    assert.match(intro, /--role/);
    const dbMax = r.stdout.split('\n').find((l) => l.startsWith('  --db-max-size '));
    assert.match(dbMax, /SQLite only/);
});

test('the server reads each variable: a bad value stops it with exit 2, naming the variable', () => {
    const opts = options().filter((o) => CHECKED.has(o.flag));
    assert.equal(opts.length, CHECKED.size);
    for (const o of opts) {
        const r = spawnSync(SERVER, ['--db', path.join(tempDir(), 'jobs.db')], {
            encoding: 'utf8', env: envWith({ [o.env]: 'many' }), timeout: 10000,
        });
        assert.equal(r.status, 2, `${o.env}=many: exit ${r.status}, ${r.stderr}`);
        assert.match(r.stderr, new RegExp(`^ctcsim-server: ${o.env} must be .*\\(got "many"\\)\\n$`), o.env);
    }
    const r = spawnSync(SERVER, [], { encoding: 'utf8', env: envWith({ CTCSIM_HTTP_THREADS: '0' }), timeout: 10000 });
    assert.equal(r.stderr, 'ctcsim-server: CTCSIM_HTTP_THREADS must be an integer from 1 to 1024 (got "0")\n');
});

test('CTCSIM_HTTP_THREADS=1 serves requests', async () => {
    const port = await freePort();
    const proc = spawn(SERVER, ['--port', String(port), '--db', path.join(tempDir(), 'jobs.db'), '--workers', '1'], {
        stdio: ['ignore', 'pipe', 'pipe'], env: envWith({ CTCSIM_HTTP_THREADS: '1' }),
    });
    let out = '';
    proc.stdout.on('data', (c) => (out += c));
    proc.stderr.on('data', (c) => (out += c));
    const exited = new Promise((resolve) => proc.on('exit', (code) => resolve(code)));
    try {
        let health = null;
        for (let i = 0; i < 200 && !health; i++) {
            try {
                const h = await request(`http://127.0.0.1:${port}`, 'GET', '/api/health');
                if (h.status === 200) health = h;
            } catch {
                await sleep(50);
            }
        }
        assert.ok(health, `no 200 from /api/health: ${out}`);
        assert.equal(health.json.status, 'ok');
    } finally {
        proc.kill('SIGTERM');
    }
    assert.equal(await exited, 0, out);
});

test('the README documents every option with its variable', () => {
    const readme = readFileSync(path.join(ROOT, 'README.md'), 'utf8').replace(/\s+/g, ' ');
    for (const o of options()) {
        assert.ok(readme.includes(`\`${o.flag}\` (\`${o.env}\``), `README.md: no "\`${o.flag}\` (\`${o.env}\`"`);
    }
});
