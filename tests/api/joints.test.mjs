/*
 * joints.test.mjs - the page's table of joint kinds (web/joints.js) against the library's
 * (src/model/joint.c), as the job format shows it through `ctcsim validate`.
 *
 * The page keeps nq and nv per joint type statically (jobform.js, kinematics.js and series.js
 * import them). Here the parser is the reference: the joint types it accepts are the ones its
 * error for an unknown type lists, and a type's nq and nv are the lengths of the normalised q0
 * and v0 of a two-body job (a revolute joint, then the type under test, so that a fixed joint
 * still leaves a coordinate that moves) less the revolute joint's one.
 */
import assert from 'node:assert/strict';
import path from 'node:path';
import test from 'node:test';
import { pathToFileURL } from 'node:url';

import { ROOT, runCli } from './lib.mjs';

const { JOINTS, JOINT_NQ, JOINT_NV } = await import(pathToFileURL(path.join(ROOT, 'web', 'joints.js')).href);

const body = (joint) => ({ mass: 1, com: [0, -0.5, 0], inertia: [0.1, 0.1, 0.1], joint });

/* `ctcsim validate` of a job whose second joint is joint; resolves to { code, stdout, stderr } */
function validate(joint) {
    const doc = {
        scene: {
            gravity: [0, -9.81, 0],
            bodies: [body({ type: 'revolute', axis: [0, 0, 1] }), body({ location: [0, -1, 0], ...joint })],
        },
        controller: { type: 'none' },
        duration: 1,
    };
    return runCli(['validate', '-'], { input: JSON.stringify(doc) });
}

test("the page knows exactly the joint types the parser accepts", async () => {
    const r = await validate({ type: 'no such joint' });
    assert.equal(r.code, 2, r.stderr);
    const m = /scene\.bodies\[1\]\.joint\.type: must be one of (.*) \(got "no such joint"\)/.exec(r.stderr);
    assert.ok(m, `unexpected message: ${r.stderr}`);
    const accepted = [...m[1].matchAll(/"([^"]+)"/g)].map((x) => x[1]);
    assert.ok(accepted.length >= 5, `too few types in ${m[1]}`);
    assert.deepEqual(Object.keys(JOINTS).sort(), accepted.sort());
});

test("the page's nq and nv of each joint type are the parser's", async () => {
    for (const [type, { nq, nv }] of Object.entries(JOINTS)) {
        assert.equal(JOINT_NQ[type], nq, type);
        assert.equal(JOINT_NV[type], nv, type);
        /* a kind that takes an axis gets one (any axis a planar or spatial chain accepts) */
        let r = await validate({ type });
        if (r.code === 2 && /joint\.axis: is required/.test(r.stderr)) r = await validate({ type, axis: [0, 0, 1] });
        assert.equal(r.code, 0, `${type}: ${r.stderr}`);
        const scene = JSON.parse(r.stdout).scene;
        assert.equal(scene.q0.length - 1, nq, `${type}: q0 ${JSON.stringify(scene.q0)}`);
        assert.equal(scene.v0.length - 1, nv, `${type}: v0 ${JSON.stringify(scene.v0)}`);
    }
});
