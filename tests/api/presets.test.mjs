/*
 * presets.test.mjs - every preset through the service: listed, printed, submitted, run, and its
 * series identical to the command line's for the job's normalised spec; series selection by
 * channels, joints and every.
 */
import assert from 'node:assert/strict';
import { readFileSync } from 'node:fs';
import path from 'node:path';
import test from 'node:test';

import { cliCsv, parseCsv, runCli, startServer, submit, waitJob, idOf, ROOT } from './lib.mjs';

const DURATION = 0.3;
const KNOWN = [
    'triple_pendulum_pd', 'triple_pendulum_pid', 'triple_pendulum_poles', 'triple_pendulum_lqr',
    'triple_pendulum_passive', 'spatial_double_pendulum_pd', 'spatial_double_pendulum_pid',
    'spatial_double_pendulum_poles', 'spatial_double_pendulum_lqr', 'n_link_pendulum',
    'five_bar_pd', 'five_bar_pid', 'five_bar_poles', 'five_bar_lqr', 'four_bar_passive',
    'arm_four_bar_pd', 'rssr_passive', 'y_pendulum_pd', 'y_four_bar_pd', 'spatial_hand_pd',
    'two_arm_torso_pd', 'ur5_min_jerk', 'iiwa14_min_jerk', 'triple_pendulum_pid_1khz',
    'triple_pendulum_pid_200hz', 'triple_pendulum_pid_50hz', 'triple_pendulum_pid_limited', 'panda_min_jerk',
    'two_link_min_jerk', 'two_link_lab_payload', 'puma560_min_jerk',
];
/* bodies of each preset's chain (n_link_pendulum with n = 4) */
const TREE_BODIES = { y_pendulum_pd: 5, y_four_bar_pd: 6, spatial_hand_pd: 10, two_arm_torso_pd: 7,
    panda_min_jerk: 9 };
const BODIES = (name) =>
    TREE_BODIES[name] ?? (name === 'n_link_pendulum' ? 4 : name.startsWith('five_bar') ? 5 : name.startsWith('spatial') || name.startsWith('two_link') ? 2 :
        name === 'arm_four_bar_pd' ? 4 : name === 'ur5_min_jerk' || name === 'puma560_min_jerk' ? 6 : name === 'iiwa14_min_jerk' ? 7 : 3);
const PASSIVE = new Set(['triple_pendulum_passive', 'four_bar_passive', 'rssr_passive']);

let srv;
let presets = [];
const jobs = new Map(); /* preset name -> finished job (GET /api/jobs/{id}) */

const requestOf = (name) =>
    name === 'n_link_pendulum' ? { preset: name, n: 4, duration: DURATION } : { preset: name, duration: DURATION };

test('the server starts', async () => {
    srv = await startServer({ workers: 2 });
});

test('GET /api/presets lists every preset with a summary and its params', async () => {
    const res = await srv.get('/api/presets');
    assert.equal(res.status, 200);
    assert.match(res.headers['content-type'], /^application\/json/);
    presets = res.json.presets;
    assert.ok(Array.isArray(presets));
    assert.deepEqual(presets.map((p) => p.name), KNOWN);
    for (const p of presets) {
        assert.equal(typeof p.summary, 'string');
        assert.ok(p.summary.length > 0, p.name);
        assert.deepEqual(p.params, p.name === 'n_link_pendulum' ? ['n'] : [], p.name);
    }
    /* the command line lists the same, in the same order */
    const cli = await runCli(['presets']);
    assert.equal(cli.code, 0);
    assert.deepEqual(cli.stdout.trim().split('\n').map((l) => l.split(/\s+/)[0]), KNOWN);
});

test('the job schema names every preset, and no other', () => {
    const schema = JSON.parse(readFileSync(path.join(ROOT, 'api', 'job.schema.json'), 'utf8'));
    /* the "preset" property's enum, wherever the schema keeps it */
    const find = (node) => {
        if (node === null || typeof node !== 'object') return null;
        if (Array.isArray(node.properties?.preset?.enum)) return node.properties.preset.enum;
        for (const v of Object.values(node)) {
            const got = find(v);
            if (got) return got;
        }
        return null;
    };
    const names = find(schema);
    assert.ok(names, 'no enum of preset names in api/job.schema.json');
    assert.deepEqual([...names].sort(), [...KNOWN].sort());
});

test('GET /api/presets/{name} is the document `ctcsim preset NAME` prints', async () => {
    for (const [name, query, args] of [
        ['triple_pendulum_pid', '', []],
        ['spatial_double_pendulum_lqr', '', []],
        ['n_link_pendulum', '', []],
        ['n_link_pendulum', '?n=16', ['n=16']],
    ]) {
        const res = await srv.get(`/api/presets/${name}${query}`);
        assert.equal(res.status, 200, `${name}${query}: ${res.text}`);
        assert.match(res.headers['content-type'], /^application\/json/);
        const cli = await runCli(['preset', name, ...args]);
        assert.equal(cli.code, 0, cli.stderr);
        assert.deepEqual(res.json, JSON.parse(cli.stdout), `${name}${query}`);
    }
    const res = await srv.get('/api/presets/n_link_pendulum?n=16');
    assert.equal(res.json.scene.bodies.length, 16);
});

test('every preset is accepted (202, Location, queued row) and runs to done', async () => {
    const ids = new Map();
    for (const p of presets) {
        const res = await srv.post('/api/jobs', requestOf(p.name));
        assert.equal(res.status, 202, `${p.name}: ${res.text}`);
        const row = res.json;
        assert.equal(res.headers.location, `/api/jobs/${row.id}`);
        assert.equal(idOf(res), row.id);
        assert.equal(row.location, `/api/jobs/${row.id}`);
        assert.ok(Number.isInteger(row.id) && row.id > 0);
        assert.equal(row.preset, p.name);
        assert.ok(['queued', 'running', 'done'].includes(row.status), row.status);
        assert.match(row.created, /^\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d\.\d{3}Z$/);
        assert.equal(row.scene.bodies, BODIES(p.name), p.name);
        ids.set(p.name, row.id);
    }
    assert.equal(new Set(ids.values()).size, presets.length, 'distinct ids');
    for (const [name, id] of ids) {
        const job = await waitJob(srv, id);
        assert.equal(job.status, 'done', `${name}: ${job.message}`);
        assert.equal(job.progress, 1);
        assert.match(job.started, /Z$/);
        assert.match(job.finished, /Z$/);
        assert.ok(Date.parse(job.created) <= Date.parse(job.started));
        assert.ok(Date.parse(job.started) <= Date.parse(job.finished));
        assert.equal(job.metrics.status, 'done');
        assert.equal(job.metrics.t_end, DURATION);
        assert.equal(typeof job.wall_s, 'number');
        assert.equal(job.message, null);
        assert.equal(job.spec.duration, DURATION);
        assert.equal(job.preset, name);
        if (PASSIVE.has(name)) assert.equal(job.e_max, null);
        else assert.equal(job.e_max, Math.max(...job.metrics.e_max));
        jobs.set(name, job);
    }
});

test('POST /api/validate gives the same normalised spec as the stored job', async () => {
    for (const p of presets) {
        const res = await srv.post('/api/validate', requestOf(p.name));
        assert.equal(res.status, 200, res.text);
        assert.equal(res.json.valid, true);
        assert.deepEqual(res.json.spec, jobs.get(p.name).spec, p.name);
    }
});

test('series CSV is byte-identical to `ctcsim run` of the normalised spec', async () => {
    for (const [name, job] of jobs) {
        const res = await srv.get(`/api/jobs/${job.id}/series?format=csv`);
        assert.equal(res.status, 200, res.text);
        assert.match(res.headers['content-type'], /^text\/csv/);
        const cli = await cliCsv(job.spec);
        assert.ok(res.text === cli, `${name}: the service's CSV differs from the CLI's`);
    }
});

test('series JSON has t and every channel with duration/interval + 1 samples', async () => {
    for (const [name, job] of jobs) {
        const res = await srv.get(`/api/jobs/${job.id}/series`);
        assert.equal(res.status, 200, res.text);
        assert.match(res.headers['content-type'], /^application\/json/);
        const s = res.json;
        const n = Math.round(job.spec.duration / job.spec.output.interval) + 1;
        assert.equal(n, 31);
        assert.equal(s.t.length, n, name);
        assert.equal(s.t[0], 0);
        assert.equal(s.t[n - 1], DURATION);
        assert.equal(job.metrics.samples, n);
        assert.deepEqual(Object.keys(s), ['t', ...job.spec.output.channels], name);
        const nq = job.metrics.nq;
        const nv = job.metrics.nv;
        const nind = job.metrics.nind; /* the controller's channels: every coordinate, or a loop's independent ones */
        assert.equal(nv, job.scene.coordinates);
        assert.equal(nind, job.spec.scene.loop ? job.metrics.coordinates.length : nv, name);
        for (const ch of job.spec.output.channels) {
            const width = ch === 'energy' || ch === 'loop' ? 2 : ch === 'q' ? nq : ch === 'qdot' ? nv : nind;
            assert.equal(s[ch].length, width, `${name} ${ch} columns`);
            for (const col of s[ch]) assert.equal(col.length, n, `${name} ${ch} samples`);
        }
        /* the same numbers as the CSV */
        const csv = parseCsv((await srv.get(`/api/jobs/${job.id}/series?format=csv`)).text);
        assert.equal(csv.rows.length, n);
        const iq1 = csv.header.indexOf('q[1]');
        for (let j = 0; j < n; j++) {
            assert.equal(Number(csv.rows[j][0]), s.t[j]);
            assert.equal(Number(csv.rows[j][iq1]), s.q[1][j]);
        }
    }
});

test('channels, joints and every select columns and samples; names keep indices', async () => {
    const job = jobs.get('triple_pendulum_pid');
    const full = parseCsv(await cliCsv(job.spec));
    const res = await srv.get(`/api/jobs/${job.id}/series?format=csv&channels=q,tau&joints=0,2&every=7`);
    assert.equal(res.status, 200, res.text);
    const got = parseCsv(res.text);
    assert.deepEqual(got.header, ['t', 'q[0]', 'q[2]', 'tau[0]', 'tau[2]']);
    /* samples 0, 7, 14, 21, 28 and the last, 30 */
    const kept = [0, 7, 14, 21, 28, 30];
    assert.equal(got.rows.length, kept.length);
    got.rows.forEach((row, k) => {
        got.header.forEach((col, c) => {
            assert.equal(row[c], full.rows[kept[k]][full.header.indexOf(col)], `${col} at sample ${kept[k]}`);
        });
    });
    /* the CLI's own --channels/--every give the same rows, before the joints filter */
    const cli = parseCsv(await cliCsv(job.spec, ['--channels', 'q,tau', '--every', '7']));
    assert.equal(cli.rows.length, kept.length);
    got.header.forEach((col, c) => {
        const ci = cli.header.indexOf(col);
        cli.rows.forEach((row, k) => assert.equal(got.rows[k][c], row[ci]));
    });

    /* the JSON series with the same selection */
    const js = await srv.get(`/api/jobs/${job.id}/series?format=json&channels=q,tau&joints=0,2&every=7`);
    assert.equal(js.status, 200, js.text);
    assert.deepEqual(Object.keys(js.json), ['t', 'q', 'tau']);
    assert.deepEqual(js.json.t, kept.map((j) => Number(full.rows[j][0])));
    assert.equal(js.json.q.length, 2);
    assert.deepEqual(js.json.q[1], kept.map((j) => Number(full.rows[j][full.header.indexOf('q[2]')])));
    assert.deepEqual(js.json.tau[0], kept.map((j) => Number(full.rows[j][full.header.indexOf('tau[0]')])));

    /* one joint, one channel; energy is not filtered by joints */
    const one = parseCsv((await srv.get(`/api/jobs/${job.id}/series?format=csv&channels=e,energy&joints=1`)).text);
    assert.deepEqual(one.header, ['t', 'e[1]', 'energy[kinetic]', 'energy[potential]']);
    assert.equal(one.rows.length, 31);
    /* every larger than the series: the first and the last sample */
    const two = await srv.get(`/api/jobs/${job.id}/series?channels=w&every=1000`);
    assert.deepEqual(two.json.t, [0, DURATION]);
    assert.equal(two.json.w.length, 3);
});

test('the server stops cleanly on SIGTERM', async () => {
    const r = await srv.stop('SIGTERM');
    assert.equal(r.killed, undefined, 'it had to be killed');
    assert.equal(r.code, 0, srv.output());
});
