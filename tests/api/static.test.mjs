/*
 * static.test.mjs - static files from the web root (a temporary one made here): index.html for
 * "/", content types by extension, 404 JSON errors for files that do not exist, and symbolic
 * links that leave the root refused. Also GET /api/openapi.yaml.
 */
import assert from 'node:assert/strict';
import { existsSync } from 'node:fs';
import { mkdir, readFile, symlink, writeFile } from 'node:fs/promises';
import path from 'node:path';
import test from 'node:test';

import { ROOT, startServer, tempDir } from './lib.mjs';

const SECRET = 'secret outside the web root 7f3a9c';
const INDEX = '<!doctype html>\n<title>ctcsim test page</title>\n<p>hello</p>\n';

let srv;

test('the server starts with a temporary web root holding links that leave it', async () => {
    const web = tempDir('ctcsim-webroot-');
    const outside = tempDir('ctcsim-outside-');
    await writeFile(path.join(web, 'index.html'), INDEX);
    await writeFile(path.join(web, 'style.css'), 'body { color: black; }\n');
    await writeFile(path.join(web, 'app.js'), 'console.log(1);\n');
    await writeFile(path.join(web, 'data.json'), '{"a": 1}\n');
    await mkdir(path.join(web, 'sub'));
    await writeFile(path.join(web, 'sub', 'page.html'), '<p>sub</p>\n');
    await writeFile(path.join(outside, 'secret.txt'), SECRET);
    await symlink(path.join(outside, 'secret.txt'), path.join(web, 'secret.txt'));
    await symlink(outside, path.join(web, 'outside'));
    await symlink('../' + path.basename(outside) + '/secret.txt', path.join(web, 'relative.txt'));
    if (existsSync('/etc/hostname')) await symlink('/etc/hostname', path.join(web, 'hostname'));
    await symlink('/etc', path.join(web, 'etc'));
    srv = await startServer({ workers: 1, web });
});

test('GET / is index.html as text/html', async () => {
    const res = await srv.get('/');
    assert.equal(res.status, 200);
    assert.match(res.headers['content-type'], /^text\/html/);
    assert.equal(res.text, INDEX);
    const again = await srv.get('/index.html');
    assert.equal(again.status, 200);
    assert.equal(again.text, INDEX);
});

test('content types follow the extension; files below a folder are served', async () => {
    for (const [p, type] of [
        ['/style.css', /^text\/css/],
        ['/app.js', /^(application|text)\/javascript/],
        ['/data.json', /^application\/json/],
        ['/sub/page.html', /^text\/html/],
    ]) {
        const res = await srv.get(p);
        assert.equal(res.status, 200, `${p}: ${res.text}`);
        assert.match(res.headers['content-type'] || '', type, p);
    }
});

test('a file that does not exist is a 404 JSON error', async () => {
    for (const p of ['/nope.html', '/sub/nope.css', '/nope/']) {
        const res = await srv.get(p);
        assert.equal(res.status, 404, `${p}: ${res.text}`);
        assert.match(res.headers['content-type'] || '', /^application\/json/);
        assert.equal(res.json.error.code, 'NOT_FOUND');
        assert.equal(typeof res.json.error.message, 'string');
        assert.equal(typeof res.json.error.field, 'string');
    }
});

test('symbolic links that leave the web root are refused (404)', async () => {
    const paths = ['/secret.txt', '/outside/secret.txt', '/relative.txt', '/etc/passwd', '/etc/hostname'];
    if (existsSync('/etc/hostname')) paths.push('/hostname');
    const hostname = existsSync('/etc/hostname') ? (await readFile('/etc/hostname', 'utf8')).trim() : null;
    for (const p of paths) {
        const res = await srv.raw('GET', p);
        assert.equal(res.status, 404, `${p}: ${res.status} ${res.text.slice(0, 200)}`);
        assert.ok(!res.text.includes(SECRET), `${p} leaks the file outside the root`);
        assert.doesNotMatch(res.text, /root:.*:0:0:/, `${p} leaks /etc/passwd`);
        if (hostname && p.endsWith('hostname')) {
            assert.ok(!(res.json === undefined && res.text.trim() === hostname), `${p} leaks /etc/hostname`);
        }
    }
});

test('GET /api/openapi.yaml is api/openapi.yaml as application/yaml', async () => {
    const res = await srv.get('/api/openapi.yaml');
    assert.equal(res.status, 200, res.text);
    assert.match(res.headers['content-type'] || '', /^application\/yaml/);
    assert.equal(res.text, await readFile(path.join(ROOT, 'api', 'openapi.yaml'), 'utf8'));
    assert.match(res.text, /^openapi: 3\.0\.3$/m);
});

test('openapi.yaml says the scope of health\'s counters on SQLite and on PostgreSQL', async () => {
    const text = await readFile(path.join(ROOT, 'api', 'openapi.yaml'), 'utf8');
    const health = /^ {4}Health:\n([\s\S]*?)\n {4}[A-Z]/m.exec(text)[1].replace(/\s+/g, ' ');
    assert.match(health, /On SQLite .* this process's/);
    assert.match(health, /On PostgreSQL .* `busy`, `queued` and `jobs` are database-wide/);
    for (const field of ['busy', 'queued', 'jobs']) {
        const desc = new RegExp(` ${field}: .*?description: >- (.*?)(?: [a-z]+: type:|$)`).exec(health)[1];
        assert.match(desc, /SQLite/, `${field}'s description names no store`);
        assert.match(desc, /PostgreSQL/, `${field}'s description names no store`);
    }
});

test('the server stops cleanly on SIGTERM', async () => {
    const r = await srv.stop('SIGTERM');
    assert.equal(r.killed, undefined, 'it had to be killed');
    assert.equal(r.code, 0, srv.output());
});
