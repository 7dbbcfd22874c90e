/*
 * search.test.mjs - finding runs again: a preset job named after what its request changed
 * (server/job_name.h), tags kept in the normalised job and checked (400 naming the entry and
 * the reason), GET /api/jobs?q=&tag= against a filter of the whole list done here (the oracle),
 * and the list's final and RMS errors against each job's own metrics.
 */
import assert from 'node:assert/strict';
import { after, before, test } from 'node:test';

import { listAll, startServer } from './lib.mjs';


let srv;
const jobs = {};

async function run(job) {
    const res = await srv.post('/api/jobs?wait=60', job);
    assert.equal(res.status, 200, `${JSON.stringify(job)}: ${res.status} ${res.text}`);
    return res.json;
}

before(async () => {
    srv = await startServer({ workers: 2 });
    jobs.kp = await run({ preset: 'triple_pendulum_pid', controller: { kp: 400 }, duration: 0.5, tags: ['sweep', 'kp 400'] });
    jobs.plain = await run({ preset: 'triple_pendulum_pid', duration: 0.5 });
    jobs.lqr = await run({ preset: 'triple_pendulum_lqr', duration: 0.5, tags: ['Sweep'] });
    jobs.mine = await run({ preset: 'triple_pendulum_pd', name: 'my run', duration: 0.5, tags: ['sweep'] });
});

after(async () => {
    await srv?.stop();
});

test('a job edited from a preset is named after the edit, a named one keeps its name', () => {
    assert.equal(jobs.kp.name, 'triple_pendulum_pid, kp = 400, duration = 0.5');
    assert.equal(jobs.kp.spec.name, jobs.kp.name, 'the normalised job carries the name');
    assert.equal(jobs.kp.preset, 'triple_pendulum_pid');
    assert.equal(jobs.mine.name, 'my run');
});

test('the same edit posted as the whole document is named alike', async () => {
    /* the page's form: the preset's document, one gain changed, sent with "preset" */
    const doc = (await srv.get('/api/presets/triple_pendulum_pid')).json;
    doc.controller.kp = 400;
    doc.duration = 0.5;
    const res = await srv.post('/api/validate', { preset: 'triple_pendulum_pid', ...doc });
    assert.equal(res.status, 200, res.text);
    assert.equal(res.json.spec.name, 'triple_pendulum_pid, kp = 400, duration = 0.5');
});

test('tags are kept in the normalised job and listed with the row', async () => {
    assert.deepEqual(jobs.kp.spec.tags, ['sweep', 'kp 400']);
    assert.deepEqual(jobs.kp.tags, ['sweep', 'kp 400']);
    assert.deepEqual(jobs.plain.tags, [], 'no tags: an empty list');
    assert.equal('tags' in jobs.plain.spec, false, 'none given, none in the normalised job');
    const row = (await listAll(srv)).find((j) => j.id === jobs.kp.id);
    assert.deepEqual(row.tags, ['sweep', 'kp 400']);
});

test('bad tags are refused with the entry and the reason', async () => {
    const cases = [
        [{ tags: 'sweep' }, 'tags', 'must be an array of strings (got a string)'],
        [{ tags: ['a', 1] }, 'tags[1]', 'must be a string (got a number)'],
        [{ tags: [''] }, 'tags[0]', 'must be 1 to 40 bytes long (got 0)'],
        [{ tags: ['x'.repeat(41)] }, 'tags[0]', 'must be 1 to 40 bytes long (got 41)'],
        [{ tags: ['a', 'a'] }, 'tags[1]', 'repeats tag "a"'],
        [{ tags: Array.from({ length: 17 }, (_, i) => `t${i}`) }, 'tags', 'must have at most 16 tags (got 17)'],
    ];
    for (const [extra, field, message] of cases) {
        const res = await srv.post('/api/jobs', { preset: 'triple_pendulum_pd', ...extra });
        assert.equal(res.status, 400, JSON.stringify(extra));
        assert.deepEqual(res.json.error, { code: 'INVALID_FIELD', field, message });
    }
});

test('?q= and ?tag= find what a filter of the whole list finds', async () => {
    const all = await listAll(srv);
    const has = (s, q) => typeof s === 'string' && s.toLowerCase().includes(q.toLowerCase());
    const oracle = (q, tag) =>
        all.filter((j) => (!q || has(j.name, q) || has(j.preset, q) || has(j.controller, q) || j.tags.some((t) => has(t, q))) &&
            (!tag || j.tags.includes(tag))).map((j) => j.id);
    for (const [q, tag] of [['sweep', null], ['PID', null], ['lqr', null], ['kp = 400', null], [null, 'sweep'],
        [null, 'Sweep'], ['pid', 'sweep'], ['nothing', null], ['%', null]]) {
        const params = new URLSearchParams();
        if (q) params.set('q', q);
        if (tag) params.set('tag', tag);
        const res = await srv.get(`/api/jobs?${params}`);
        assert.equal(res.status, 200, res.text);
        assert.deepEqual(res.json.jobs.map((j) => j.id), oracle(q, tag), `q=${q} tag=${tag}`);
    }
    assert.deepEqual(oracle('sweep', null).sort(), [jobs.kp.id, jobs.lqr.id, jobs.mine.id].sort(), 'the oracle itself');
});

test('a bad q or tag is a 400 naming it', async () => {
    let res = await srv.get(`/api/jobs?q=${'x'.repeat(201)}`);
    assert.equal(res.status, 400);
    assert.deepEqual(res.json.error, { code: 'INVALID_QUERY', field: 'q', message: 'q must be at most 200 bytes long (got 201)' });
    res = await srv.get('/api/jobs?tag=');
    assert.equal(res.status, 400);
    assert.deepEqual(res.json.error, { code: 'INVALID_QUERY', field: 'tag', message: 'tag must be 1 to 40 bytes long (got 0)' });
});

test('the list shows the final and RMS errors of each job, from its metrics', async () => {
    const rows = await listAll(srv);
    for (const j of Object.values(jobs)) {
        const row = rows.find((r) => r.id === j.id);
        const m = j.metrics;
        const final = Math.max(...m.e_final.map(Math.abs));
        const rms = Math.sqrt(m.e_rms.reduce((a, v) => a + v * v, 0) / m.e_rms.length);
        assert.ok(Math.abs(row.e_final - final) <= 1e-12 * Math.max(1, final), `${j.name}: e_final ${row.e_final}, want ${final}`);
        assert.ok(Math.abs(row.e_rms - rms) <= 1e-12 * Math.max(1, rms), `${j.name}: e_rms ${row.e_rms}, want ${rms}`);
        assert.ok(row.e_final < row.e_max, `${j.name}: the final error is below the initial one`);
    }
});
