/*
 * visuals.test.mjs - a URDF robot's <visual> boxes, cylinders and spheres (the bodies'
 * "visuals") drawn by the job view's animation instead of their plain links: a job from an
 * inline URDF with one of each keeps them through the import, canvas#anim counts them in
 * data-visuals, and its pixels hold the shapes' translucent fill, which the same robot without
 * visuals does not have; where a box is, in the planar view, the fill is at its centre.
 */
import assert from 'node:assert/strict';
import { after, before, test } from 'node:test';

import { launchBrowser, poll, runJob, screenshot, startWebServer, withView } from './lib.mjs';

let srv;
let browser;

before(async () => {
    srv = await startWebServer();
    browser = await launchBrowser();
});

after(async () => {
    await browser?.close();
    await srv?.stop();
});

/* two links about z, planar; link a carries a box along it and a cylinder, link b a sphere */
const urdf = (visuals) => `<robot name="shapes">
  <link name="base"/>
  <link name="a"><inertial><origin xyz="0.5 0 0"/><mass value="1"/>
    <inertia ixx="0.001" iyy="0.08" izz="0.08"/></inertial>
    ${visuals ? '<visual><origin xyz="0.5 0 0"/><geometry><box size="1 0.2 0.1"/></geometry></visual>' : ''}
    ${visuals ? '<visual><origin xyz="1 0 0"/><geometry><cylinder radius="0.08" length="0.3"/></geometry></visual>' : ''}
  </link>
  <link name="b"><inertial><origin xyz="0.4 0 0"/><mass value="1"/>
    <inertia ixx="0.001" iyy="0.05" izz="0.05"/></inertial>
    ${visuals ? '<visual><origin xyz="0.8 0 0"/><geometry><sphere radius="0.15"/></geometry></visual>' : ''}
    ${visuals ? '<visual><geometry><mesh filename="package://x/b.stl"/></geometry></visual>' : ''}
  </link>
  <joint name="ja" type="revolute"><parent link="base"/><child link="a"/><axis xyz="0 0 1"/></joint>
  <joint name="jb" type="revolute"><parent link="a"/><child link="b"/><origin xyz="1 0 0"/><axis xyz="0 0 1"/></joint>
</robot>`;

const job = (visuals) => ({
    scene: { urdf: urdf(visuals), gravity: [0, -9.81, 0], q0: [0, 0] },
    controller: { type: 'pd', kp: 100, kv: 20 },
    trajectory: { type: 'constant', value: 0 },
    duration: 0.2,
});

/* canvas#anim's pixels of the shapes' fill: ACTUAL (#0072B2) at 0.35 over the background
   #fbfbfc, within 8 per channel */
function fillPixels(page) {
    return page.evaluate(() => {
        const c = document.querySelector('canvas#anim');
        const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
        const want = [0x00, 0x72, 0xb2].map((v, i) => 0.35 * v + 0.65 * [0xfb, 0xfb, 0xfc][i]);
        let n = 0;
        for (let i = 0; i < d.length; i += 4)
            if (want.every((v, k) => Math.abs(d[i + k] - v) <= 8)) n++;
        return { n, width: c.width, height: c.height, dpr: c.width / c.clientWidth };
    });
}

test('a URDF robot\'s boxes, cylinders and spheres survive the import and are drawn', async () => {
    const shaped = await runJob(srv, job(true));
    const bodies = shaped.spec.scene.bodies;
    assert.deepEqual(bodies.map((b) => (b.visuals || []).map((v) => v.type)), [['box', 'cylinder'], ['sphere']]);
    assert.deepEqual(bodies[0].visuals[0].size, [1, 0.2, 0.1]);
    assert.deepEqual(bodies[0].visuals[0].origin, [0.5, 0, 0]);
    const plain = await runJob(srv, job(false));
    assert.equal(plain.spec.scene.bodies[0].visuals, undefined);

    let bare;
    await withView(browser, srv, `#/jobs/${plain.id}`, 'visuals-none', async (page) => {
        await page.waitForSelector('canvas#anim');
        await poll(() => page.evaluate(() => document.querySelector('canvas#anim').dataset.visuals === '0'), 'data-visuals 0');
        bare = await fillPixels(page);
    });
    await withView(browser, srv, `#/jobs/${shaped.id}`, 'visuals', async (page) => {
        await page.waitForSelector('canvas#anim');
        await poll(() => page.evaluate(() => document.querySelector('canvas#anim').dataset.visuals === '3'), 'data-visuals 3 (the mesh left out)');
        const drawn = await fillPixels(page);
        /* without visuals only the sticks' antialiased edges can match the fill's colour */
        assert.ok(bare.n < 100, `the robot without visuals has ${bare.n} fill pixels`);
        /* the box alone is 1 m by 0.2 m in a view whose reach is about 2 m: thousands of pixels */
        assert.ok(drawn.n > 1000 * drawn.dpr * drawn.dpr, `only ${drawn.n} fill pixels`);
        /* the box's centre, 0.5 m along x from the base at q = 0 (the view's centre, x right) */
        const px = await page.evaluate(() => {
            const c = document.querySelector('canvas#anim');
            return { w: c.clientWidth, h: c.clientHeight, dpr: c.width / c.clientWidth };
        });
        /* the scale fits the sticks' reach, about 2 m here; the point below is inside the box for
           any reach from 1.2 to 10 m */
        const s = (0.44 * Math.min(px.w, px.h)) / 2;
        const at = await page.evaluate(([x, y, dpr]) => {
            const g = document.querySelector('canvas#anim').getContext('2d');
            return Array.from(g.getImageData(Math.round(x * dpr), Math.round(y * dpr), 1, 1).data);
        }, [px.w / 2 + s * 0.25, px.h / 2 + s * 0.06, px.dpr]);
        const want = [0x00, 0x72, 0xb2].map((v, i) => 0.35 * v + 0.65 * [0xfb, 0xfb, 0xfc][i]);
        assert.ok(want.every((v, k) => Math.abs(at[k] - v) <= 8), `inside the box: rgb(${at.slice(0, 3)})`);
        await screenshot(page, 'visuals.png');
    });
});
