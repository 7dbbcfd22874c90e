/*
 * trees.test.mjs - bodies that name their parent, through the service: a parent given by index,
 * by name or as "ground" is stored and answered as an index (the normalised spec of `ctcsim
 * validate` too), and a parent that is not a body before its child is 400 INVALID_FIELD at
 * scene.bodies[k].parent with the job format's message (job_json.h, tests/unit/test_job_json.c).
 */
import assert from 'node:assert/strict';
import test from 'node:test';

import { runCli, startServer } from './lib.mjs';

const REV = { type: 'revolute', axis: [0, 0, 1] };
/* a 1 m, 1 kg rod named name hanging along -y from its parent's tip (or from the origin) */
const rod = (name, extra = {}, first = false) => ({
    name, mass: 1, shape: { type: 'rod', end: [0, -1, 0] },
    joint: { ...REV, location: first ? [0, 0, 0] : [0, -1, 0] }, ...extra,
});
const job = (bodies) => ({ scene: { bodies }, controller: { type: 'none' }, duration: 0.1 });

let srv;

test('the server starts', async () => {
    srv = await startServer({ workers: 1 });
});

test('parents by name, index or "ground" are answered as indices, as `ctcsim validate` writes them', async () => {
    const given = job([rod('upper', { parent: 'ground' }, true), rod('middle', { parent: 'upper' }), rod('lower', { parent: 1 }),
        rod('tip')]);
    const res = await srv.post('/api/validate', given);
    assert.equal(res.status, 200, res.text);
    assert.deepEqual(res.json.spec.scene.bodies.map((b) => b.parent), [-1, 0, 1, 2]);
    const cli = await runCli(['validate', '-'], { input: JSON.stringify(given) });
    assert.equal(cli.code, 0, cli.stderr);
    assert.deepEqual(JSON.parse(cli.stdout), res.json.spec);

    /* the stored job's spec */
    const run = await srv.post('/api/jobs?wait=30', given);
    assert.equal(run.status, 200, run.text);
    assert.equal(run.json.status, 'done', run.json.message);
    assert.deepEqual(run.json.spec.scene.bodies.map((b) => b.parent), [-1, 0, 1, 2]);
});

test('a parent that is not a body before its child is 400 at its field, through /api/jobs and /api/validate', async () => {
    const bodies = () => [rod('arm', {}, true), rod('palm'), rod('finger')];
    const cases = [
        [{ parent: 'hand' }, 'scene.bodies[2].parent', '"hand" names no body (give a body\'s "name" or index, or "ground")'],
        [{ parent: 'finger' }, 'scene.bodies[2].parent', '"finger" must name a body before body 2 (it names body 2)'],
        [{ parent: 3 }, 'scene.bodies[2].parent',
            'must be -1 (the ground) or the index of a body before body 2: a whole number from -1 to 1 (got 3)'],
        [{ parent: null }, 'scene.bodies[2].parent', 'must be a body\'s index or name, or "ground" (got null)'],
        [{ name: 'palm' }, null, null],
    ];
    for (const [extra, field, message] of cases) {
        const b = bodies();
        Object.assign(b[2], extra);
        if (message === null) { /* two bodies named "palm": fine while no parent names it */
            const res = await srv.post('/api/validate', job(b));
            assert.equal(res.status, 200, res.text);
            continue;
        }
        for (const path of ['/api/jobs', '/api/validate']) {
            const res = await srv.post(path, job(b));
            assert.equal(res.status, 400, `${path} ${JSON.stringify(extra)}: ${res.text}`);
            assert.equal(res.json.error.code, 'INVALID_FIELD', res.text);
            assert.equal(res.json.error.field, field, res.text);
            assert.equal(res.json.error.message, message);
        }
    }
    /* a name used as a parent must be unique */
    const twins = [rod('arm', {}, true), rod('arm'), rod('finger', { parent: 'arm' })];
    const res = await srv.post('/api/jobs', job(twins));
    assert.equal(res.status, 400, res.text);
    assert.equal(res.json.error.field, 'scene.bodies[2].parent');
    assert.equal(res.json.error.message, '"arm" is the name of bodies 0 and 1: a name used to refer to a body must be unique');
});

test('the server stops cleanly on SIGTERM', async () => {
    const r = await srv.stop('SIGTERM');
    assert.equal(r.code, 0, srv.output());
});
