/*
 * visuals.test.mjs - a URDF's <visual> boxes, cylinders and spheres through POST /api/jobs
 * ("scene.urdf"): kept in the stored job's bodies in each body's frame (a fixed link's on the
 * body it is merged into, turned by its joint's rpy), meshes left out, the stored spec equal to
 * `ctcsim validate`'s and itself a valid job; `ctcsim import` notes the meshes it left out; a
 * bad shape is a 400 naming the element and its line.
 */
import assert from 'node:assert/strict';
import { rmSync, writeFileSync } from 'node:fs';
import path from 'node:path';
import test from 'node:test';

import { runCli, startServer, submit, tempDir, waitJob } from './lib.mjs';

/* a arm on a revolute joint; a fixed tool turned a quarter turn about z at a's tip */
const URDF = `<?xml version="1.0"?>
<robot name="dressed">
  <link name="base"/>
  <link name="arm">
    <inertial><origin xyz="0.5 0 0"/><mass value="1"/><inertia ixx="1e-3" iyy="0.08" izz="0.08"/></inertial>
    <visual><origin xyz="0.5 0 0"/><geometry><box size="1 0.1 0.1"/></geometry></visual>
    <visual><geometry><mesh filename="package://x/arm.dae"/></geometry></visual>
  </link>
  <link name="tool">
    <inertial><mass value="0.2"/><inertia ixx="1e-4" iyy="1e-4" izz="1e-4"/></inertial>
    <visual><origin xyz="0.1 0 0"/><geometry><cylinder radius="0.02" length="0.2"/></geometry></visual>
    <visual><geometry><sphere radius="0.05"/></geometry></visual>
  </link>
  <joint name="shoulder" type="revolute"><parent link="base"/><child link="arm"/><axis xyz="0 0 1"/></joint>
  <joint name="mount" type="fixed"><parent link="arm"/><child link="tool"/>
    <origin xyz="1 0 0" rpy="0 0 1.5707963267948966"/></joint>
</robot>
`;

const TAIL = { controller: { type: 'none' }, duration: 0.1 };
const near = (a, b, what) => a.forEach((x, i) => assert.ok(Math.abs(x - b[i]) < 1e-15, `${what}: ${a} against ${b}`));

test('visual shapes survive the import into the stored job, meshes left out', async () => {
    const srv = await startServer();
    try {
        const job = { scene: { urdf: URDF }, ...TAIL };
        const row = await submit(srv, job);
        assert.equal((await waitJob(srv, row.id)).status, 'done');
        const spec = (await srv.get(`/api/jobs/${row.id}`)).json.spec;
        assert.equal(spec.scene.bodies.length, 1, 'the tool is merged into the arm');
        const v = spec.scene.bodies[0].visuals;
        assert.deepEqual(v.map((x) => x.type), ['box', 'cylinder', 'sphere'], 'the mesh is left out');
        assert.deepEqual(v[0].size, [1, 0.1, 0.1]);
        near(v[0].origin, [0.5, 0, 0], 'box origin');
        /* the tool's frame: 1 m along x, turned a quarter turn about z: its x is the arm's y */
        near(v[1].origin, [1, 0.1, 0], 'cylinder origin');
        near(v[1].rotation.flat(), [0, -1, 0, 1, 0, 0, 0, 0, 1], 'cylinder rotation');
        assert.equal(v[1].radius, 0.02);
        assert.equal(v[1].length, 0.2);
        near(v[2].origin, [1, 0, 0], 'sphere origin');
        assert.equal(v[2].rotation, undefined);
        /* the command line's normalised job, and a valid job itself */
        const cli = await runCli(['validate', '-'], { input: JSON.stringify(job) });
        assert.equal(cli.code, 0, cli.stderr);
        assert.deepEqual(spec, JSON.parse(cli.stdout));
        const again = await runCli(['validate', '-'], { input: JSON.stringify(spec) });
        assert.equal(again.code, 0, again.stderr);
        /* a bad shape: 400 with its element and line */
        const bad = await srv.post('/api/jobs', { scene: { urdf: URDF.replace('radius="0.05"', 'radius="-1"') }, ...TAIL });
        assert.equal(bad.status, 400, bad.text);
        assert.equal(bad.json.error.field, 'scene.urdf');
        assert.equal(bad.json.error.message, 'line 12: <sphere> in <link name="tool">: radius must be positive');
    } finally {
        await srv.stop();
    }
});

test('ctcsim import notes the meshes it left out', async () => {
    const dir = tempDir();
    const file = path.join(dir, 'dressed.urdf');
    writeFileSync(file, URDF);
    const out = await runCli(['import', file]);
    rmSync(dir, { recursive: true, force: true });
    assert.equal(out.code, 0, out.stderr);
    assert.match(out.stderr, /note: 1 <visual> mesh left out \(the animation draws boxes, cylinders and spheres\)/);
    assert.equal(JSON.parse(out.stdout).scene.bodies[0].visuals.length, 3);
});
