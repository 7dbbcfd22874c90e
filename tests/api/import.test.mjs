/*
 * import.test.mjs - robots given to POST /api/jobs as a URDF document ("scene.urdf", inline XML)
 * or a Denavit-Hartenberg table ("scene.dh"): accepted, run, and stored with the converted
 * bodies (the stored spec never depends on the document); malformed input answered 400 naming the
 * element and its line, with nothing stored. `ctcsim validate` of the same job is the reference
 * for the normalised spec.
 */
import assert from 'node:assert/strict';
import test from 'node:test';

import { listAll, runCli, startServer, submit, waitJob } from './lib.mjs';

const URDF = `<?xml version="1.0"?>
<robot name="two_link_arm">
  <link name="base"/>
  <link name="upper">
    <inertial><origin xyz="0.5 0 0" rpy="0 0 0.3"/><mass value="1"/>
      <inertia ixx="1e-4" iyy="0.0833" izz="0.0833"/></inertial>
  </link>
  <link name="tool"><inertial><mass value="0.2"/><inertia ixx="1e-4" iyy="1e-4" izz="1e-4"/></inertial></link>
  <link name="fore">
    <inertial><origin xyz="0.5 0 0"/><mass value="1"/>
      <inertia ixx="1e-4" iyy="0.0833" izz="0.0833"/></inertial>
  </link>
  <joint name="shoulder" type="continuous">
    <parent link="base"/><child link="upper"/><axis xyz="0 0 1"/>
    <dynamics damping="0.1"/>
  </joint>
  <joint name="elbow" type="revolute">
    <parent link="upper"/><child link="fore"/><origin xyz="1 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-2" upper="2" effort="30" velocity="3"/>
  </joint>
  <joint name="tool_mount" type="fixed">
    <parent link="fore"/><child link="tool"/><origin xyz="1 0 0"/>
  </joint>
</robot>
`;

const TAIL = {
    controller: { type: 'pd', zeta: 1, tau: 0.1 },
    trajectory: { type: 'min_jerk', from: 0, to: 0.2, start: 0, end: 0.2 },
    duration: 0.3,
    output: { interval: 0.05 },
};

const DH = {
    convention: 'modified',
    rows: [
        { a: 0, alpha: 0, d: 0.3, theta: 0.1, mass: 2, com: [0, 0, 0.1], inertia: [0.02, 0.02, 0.002] },
        { a: 0.05, alpha: -1.5707963267948966, d: 0, mass: 1, com: [0.2, 0, 0], inertia: [0.001, 0.01, 0.01] },
        { type: 'prismatic', a: 0.4, alpha: 1.5707963267948966, d: 0.1, mass: 0.5, com: [0, 0, -0.05], inertia: [0.001, 0.001, 0.0002] },
    ],
};

test('a job with an inline URDF runs and is stored with the converted bodies', async () => {
    const srv = await startServer();
    try {
        const job = { name: 'urdf arm', scene: { urdf: URDF }, ...TAIL };
        const row = await submit(srv, job);
        const done = await waitJob(srv, row.id);
        assert.equal(done.status, 'done', JSON.stringify(done));
        const got = await srv.get(`/api/jobs/${row.id}`);
        const scene = got.json.spec.scene;
        assert.equal(scene.urdf, undefined);
        assert.deepEqual(scene.bodies.map((b) => b.name), ['upper', 'fore']);
        /* the tool is merged into the forearm: 1.2 kg, centre of mass (1 * 0.5 + 0.2 * 1) / 1.2 */
        assert.equal(scene.bodies[1].mass, 1.2);
        assert.ok(Math.abs(scene.bodies[1].com[0] - 0.7 / 1.2) < 1e-15, `${scene.bodies[1].com}`);
        assert.deepEqual(scene.bodies[0].joint.dynamics, { damping: 0.1 });
        assert.deepEqual(scene.bodies[1].joint.limit, { lower: -2, upper: 2, effort: 30, velocity: 3 });
        assert.deepEqual(scene.gravity, [0, 0, -9.81]);
        /* the stored spec is the command line's normalised job, and is itself a valid job */
        const cli = await runCli(['validate', '-'], { input: JSON.stringify(job) });
        assert.equal(cli.code, 0, cli.stderr);
        assert.deepEqual(got.json.spec, JSON.parse(cli.stdout));
        const again = await runCli(['validate', '-'], { input: JSON.stringify(got.json.spec) });
        assert.equal(again.code, 0, again.stderr);
    } finally {
        await srv.stop();
    }
});

test('a job with a DH table runs and is stored with its bodies', async () => {
    const srv = await startServer();
    try {
        const row = await submit(srv, { scene: { dh: DH }, ...TAIL });
        const done = await waitJob(srv, row.id);
        assert.equal(done.status, 'done', JSON.stringify(done));
        const got = await srv.get(`/api/jobs/${row.id}`);
        const scene = got.json.spec.scene;
        assert.equal(scene.dh, undefined);
        assert.deepEqual(scene.bodies.map((b) => [b.name, b.joint.type]),
            [['link1', 'revolute'], ['link2', 'revolute'], ['link3', 'prismatic']]);
    } finally {
        await srv.stop();
    }
});

test('malformed robots are answered 400 naming the element and its line, and nothing is stored', async () => {
    const srv = await startServer();
    try {
        const cases = [
            [URDF.replace('</link>\n  <link name="tool">', '\n  <link name="tool">'), 'scene.urdf',
                /^line \d+: not well-formed XML: /],
            [URDF.replace('type="continuous"', 'type="floating"'), 'scene.urdf',
                /^line 13: <joint name="shoulder">: type "floating" is not supported/],
            [URDF.replace('<mass value="0.2"/>', '<mass value="-0.2"/>'), 'scene.urdf',
                /^line 8: <mass> in <link name="tool">: value must not be negative \(got -0.2 kg\)$/],
            [URDF.replace('<child link="tool"/>', '<child link="fore"/>'), 'scene.urdf',
                /^line 21: <joint name="tool_mount">: link "fore" has two parents: joint "elbow" \(line 17\) is its parent already$/],
        ];
        for (const [urdf, field, message] of cases) {
            const res = await srv.post('/api/jobs', { scene: { urdf }, ...TAIL });
            assert.equal(res.status, 400, res.text);
            assert.equal(res.json.error.code, 'INVALID_FIELD');
            assert.equal(res.json.error.field, field);
            assert.match(res.json.error.message, message);
        }
        const bad = await srv.post('/api/jobs', { scene: { dh: { ...DH, convention: 'craig' } }, ...TAIL });
        assert.equal(bad.status, 400, bad.text);
        assert.equal(bad.json.error.field, 'scene.dh.convention');
        assert.equal((await listAll(srv)).length, 0);
    } finally {
        await srv.stop();
    }
});
