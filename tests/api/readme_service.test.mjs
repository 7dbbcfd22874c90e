/*
 * readme_service.test.mjs - the README's service examples, run as written: the first ```sh block
 * of its "## The service" section, one command at a time with sh (curl, jq and build/ctcsim, as
 * a user types them in the repository folder) against a real server on a free port (the only
 * change made to the text: localhost:8080 becomes localhost:PORT). Each command must exit 0 and
 * print what its comment promises, so the examples cannot drift from the service. curl and jq
 * come with make deps; without them these tests fail and say so.
 */
import assert from 'node:assert/strict';
import { spawnSync } from 'node:child_process';
import { existsSync, mkdirSync, readFileSync, symlinkSync } from 'node:fs';
import path from 'node:path';
import test from 'node:test';

import { CLI, FINAL, ROOT, startServer, tempDir, waitFor } from './lib.mjs';

/* The section's first sh block, continuation lines joined: one string per command. */
function serviceCommands() {
    const readme = readFileSync(path.join(ROOT, 'README.md'), 'utf8');
    const section = readme.split(/^## /m).find((s) => s.startsWith('The service\n'));
    assert.ok(section, 'README.md has a "## The service" section');
    const block = section.match(/```sh\n([\s\S]*?)```/);
    assert.ok(block, 'the service section has a ```sh block');
    return block[1].replace(/\\\n/g, ' ').split('\n').filter((l) => l.trim() !== '');
}

let srv;
let dir;
const commands = serviceCommands();

/* Runs the README command whose text contains `needle` (exactly one must); returns its stdout. */
function run(needle) {
    const matching = commands.filter((c) => c.includes(needle));
    assert.equal(matching.length, 1, `one README service command contains ${needle}`);
    const cmd = matching[0].replaceAll('localhost:8080', `localhost:${srv.port}`);
    const r = spawnSync('sh', ['-c', cmd], { cwd: dir, encoding: 'utf8', timeout: 90000 });
    assert.equal(r.status, 0, `README command failed (exit ${r.status}): ${cmd}\n${r.stderr}` +
        (/not found/.test(r.stderr) ? '\n(curl and jq: make deps installs them)' : ''));
    return r.stdout;
}

test('a server on a fresh database, and a folder where build/ctcsim is the command line', async () => {
    srv = await startServer({ workers: 1 });
    dir = tempDir('ctcsim-readme-');
    mkdirSync(path.join(dir, 'build'));
    symlinkSync(CLI, path.join(dir, 'build', 'ctcsim'));
    assert.equal(commands.length, 6, `the block's commands: ${JSON.stringify(commands)}`);
});

test('GET /api/health answers {"status":"ok", ...}', () => {
    assert.equal(JSON.parse(run('/api/health')).status, 'ok');
});

test('posting the preset answers job 1, which is done within seconds', async () => {
    const job = JSON.parse(run(`-d '{"preset": "triple_pendulum_pid"}'`));
    assert.equal(job.id, 1);
    await waitFor(async () => FINAL.has((await srv.get('/api/jobs/1')).json.status),
        { timeoutMs: 30000, what: () => 'job 1 to finish' });
    assert.equal(run('| jq .status').trim(), '"done"');
});

test('its series as CSV: t, then q and e per joint, every 10th sample and the last', () => {
    const lines = run('format=csv').trim().split('\n');
    assert.equal(lines[0], 't,q[0],q[1],q[2],e[0],e[1],e[2]');
    assert.equal(lines.length, 1 + 51);
    assert.match(lines.at(-1), /^5,/);
});

test('job.json is written before it is posted, and the post holds until job 2 is done', () => {
    run('> job.json');
    assert.ok(existsSync(path.join(dir, 'job.json')));
    assert.equal(JSON.parse(readFileSync(path.join(dir, 'job.json'), 'utf8')).duration, 5);
    const job = JSON.parse(run('-d @job.json'));
    assert.equal(job.id, 2);
    assert.equal(job.status, 'done');
});

test('the server stops cleanly on SIGTERM', async () => {
    const r = await srv.stop('SIGTERM');
    assert.equal(r.code, 0);
});
