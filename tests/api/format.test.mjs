/*
 * format.test.mjs - the page's job form defaults (web/jobform.js) against the parser and the
 * schema (api/job.schema.json).
 *
 * Choosing a type in the form fills the object with that type's defaults (CONTROLLERS,
 * TRAJECTORIES, DISTURBANCES, INTEGRATORS). The form offers exactly the types the schema has;
 * and wherever a key it fills is one the parser would default, it fills the parser's default
 * (found with `ctcsim validate`: the job with the key left out, normalised) and the schema's.
 * Keys the parser requires ("is required" when left out) are the page's own choice. The parser's
 * own tables are checked against the schema by tests/unit/test_job_format.c.
 */
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';
import test from 'node:test';
import { pathToFileURL } from 'node:url';

import { ROOT, runCli } from './lib.mjs';

const form = await import(pathToFileURL(path.join(ROOT, 'web', 'jobform.js')).href);
const schema = JSON.parse(fs.readFileSync(path.join(ROOT, 'api', 'job.schema.json'), 'utf8'));

/* the alternatives of a $defs entry, flattened through $ref and oneOf (an object with properties
 * is one, whatever its $ref adds) */
function alternatives(node) {
    if (node.properties) return [node];
    if (node.$ref) return alternatives(node.$ref.slice(2).split('/').reduce((o, k) => o[k], schema));
    return (node.oneOf || []).flatMap(alternatives);
}
/* the type names an alternative stands for (its const or enum of typeKey) */
const typesOf = (alt, typeKey) => {
    const t = alt.properties[typeKey] || {};
    return t.const !== undefined ? [t.const] : t.enum || [];
};

const SECTIONS = [
    { key: 'controller', table: form.CONTROLLERS, typeKey: 'type', def: 'controller' },
    { key: 'trajectory', table: form.TRAJECTORIES, typeKey: 'type', def: 'trajectory_item' },
    { key: 'disturbance', table: form.DISTURBANCES, typeKey: 'type', def: 'disturbance_item' },
    { key: 'integrator', table: form.INTEGRATORS, typeKey: 'method', def: 'integrator' },
];

const base = JSON.parse((await runCli(['preset', 'triple_pendulum_pd'])).stdout);

for (const s of SECTIONS) {
    const alts = alternatives(schema.$defs[s.def]);

    test(`the form offers the schema's ${s.key} types`, () => {
        const schemaTypes = alts.flatMap((a) => typesOf(a, s.typeKey)).sort();
        assert.deepEqual(Object.keys(s.table).sort(), schemaTypes);
    });

    test(`the form's ${s.key} defaults are the parser's and the schema's`, async () => {
        let compared = 0;
        for (const [type, values] of Object.entries(s.table)) {
            const alt = alts.find((a) => typesOf(a, s.typeKey).includes(type));
            for (const [k, v] of Object.entries(values)) {
                const obj = { [s.typeKey]: type, ...structuredClone(values) };
                delete obj[k];
                const doc = { ...structuredClone(base), [s.key]: obj };
                const r = await runCli(['validate', '-'], { input: JSON.stringify(doc) });
                if (r.code === 2 && r.stderr.includes(`${s.key}.${k}: is required`)) continue;
                assert.equal(r.code, 0, `${s.key} ${type} without ${k}: ${r.stderr}`);
                const parsed = JSON.parse(r.stdout)[s.key][k];
                assert.deepEqual(v, parsed, `${s.key} ${type}: the form fills ${k} = ${JSON.stringify(v)}, the parser's default is ${JSON.stringify(parsed)}`);
                const schemaDefault = alt.properties[k]?.default;
                assert.deepEqual(v, schemaDefault, `${s.key} ${type}: the form fills ${k} = ${JSON.stringify(v)}, the schema's default is ${JSON.stringify(schemaDefault)}`);
                compared++;
            }
        }
        if (s.key === 'controller') assert.equal(compared, 0, 'every controller gain is required');
        else assert.ok(compared > 0, `no ${s.key} default compared`);
    });
}

/* The page reads a body's parent as the parser does (web/kinematics.js chainParents, which the
 * form's parent selectors show): the previous body when none is given, and an index, a name or
 * "ground" as the index the normalised job writes. */
test("the page's parents are the parser's: the default and every way of naming one", async () => {
    const kin = await import(pathToFileURL(path.join(ROOT, 'web', 'kinematics.js')).href);
    const chain = JSON.parse((await runCli(['preset', 'n_link_pendulum', 'n=5'])).stdout);
    const named = structuredClone(chain);
    named.scene.bodies.forEach((b, k) => { b.name = `link${k}`; });
    named.scene.bodies[0].parent = 'ground';
    named.scene.bodies[2].parent = 'link1';
    named.scene.bodies[3].parent = 2;
    named.scene.bodies[4].parent = 3.0;
    for (const doc of [chain, named]) {
        const r = await runCli(['validate', '-'], { input: JSON.stringify(doc) });
        assert.equal(r.code, 0, r.stderr);
        const parsed = JSON.parse(r.stdout).scene.bodies.map((b) => b.parent);
        assert.deepEqual(parsed, [-1, 0, 1, 2, 3]);
        assert.deepEqual(kin.chainParents(doc.scene.bodies), parsed, 'the page reads other parents than the parser');
    }
    /* the schema lists the key, with no default: the parser's depends on the body's place */
    const body = schema.$defs.body.properties.parent;
    assert.ok(body && body.oneOf, 'the schema has scene.bodies[].parent');
    assert.equal(body.default, undefined);
});
