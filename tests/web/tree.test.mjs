/*
 * tree.test.mjs - trees on the page: the kinematics walks the spec's parents (a planar Y and a
 * spatial two-arm torso, each against positions written out by hand for a given q), the
 * animation draws every branch from its parent (the canvas's pixels along each segment of a Y),
 * and the job form shows a parent selector per body, defaulting to the previous body and writing
 * the index it chooses into the JSON.
 */
import assert from 'node:assert/strict';
import { after, before, test } from 'node:test';

import { animImage, launchBrowser, pollValue, runJob, screenshot, startWebServer, withView } from './lib.mjs';

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

const REV_Z = { type: 'revolute', axis: [0, 0, 1] };
/* a 1 m rod hanging along -y, on its parent's tip (or on the origin) */
const rod = (name, parent, first = false) => ({
    name, ...(parent === undefined ? {} : { parent }), mass: 1, shape: { type: 'rod', end: [0, -1, 0] },
    joint: { ...REV_Z, location: first ? [0, 0, 0] : [0, -1, 0] },
});
/* the Y: an arm, then two double pendulums on its tip (the right one's first link names the arm;
   the others take the default, the previous body) */
const Y = [rod('arm', undefined, true), rod('l1'), rod('l2'), rod('r1', 'arm'), rod('r2')];
const QY = [0.3, 0.6, 0.2, -0.7, -0.3];

/* The Y's joints and segment ends by hand: rod k hangs at the absolute angle th_k, the sum of its
   ancestors' angles and its own, from its parent's tip. */
function yByHand(q) {
    const th = [q[0], q[0] + q[1], q[0] + q[1] + q[2], q[0] + q[3], q[0] + q[3] + q[4]];
    const parent = [-1, 0, 1, 0, 3];
    const origin = [], tip = [];
    for (let k = 0; k < 5; k++) {
        origin[k] = parent[k] < 0 ? [0, 0] : tip[parent[k]];
        tip[k] = [origin[k][0] + Math.sin(th[k]), origin[k][1] - Math.cos(th[k])];
    }
    return { parent, origin, tip };
}

test("the kinematics hangs each branch of a Y from its parent's tip, as written out by hand", async () => {
    await withView(browser, srv, '#/jobs', 'tree-kinematics-y', async (page) => {
        const r = await page.evaluate(async ({ bodies, q }) => {
            const kin = await import('/kinematics.js');
            const layout = kin.chainLayout(bodies, null);
            const pose = kin.chainPose(layout, (i) => q[i]);
            return { parents: kin.chainParents(bodies), pose: pose.map((b) => ({ origin: b.origin, ends: b.ends })) };
        }, { bodies: Y, q: QY });
        const want = yByHand(QY);
        assert.deepEqual(r.parents, want.parent);
        let gap = 0;
        const d = (a, b) => Math.hypot(a[0] - b[0], a[1] - b[1]);
        for (let k = 0; k < 5; k++) {
            gap = Math.max(gap, d(r.pose[k].origin, want.origin[k]));
            /* the arm's two segments end at its tip (both children's joints), a leaf's at its own */
            assert.equal(r.pose[k].ends.length, k === 0 ? 2 : 1, `body ${k}'s segments`);
            for (const e of r.pose[k].ends) gap = Math.max(gap, d(e, want.tip[k]), Math.abs(e[2]));
        }
        assert.ok(gap < 1e-12, `the Y's poses are ${gap} m from the closed form`);
        /* the same parents given by index, and the normalised form, give the same pose */
        const byIndex = await page.evaluate(async ({ bodies, q }) => {
            const kin = await import('/kinematics.js');
            const b = bodies.map((x, k) => ({ ...x, parent: [-1, 0, 1, 0, 3][k] }));
            return kin.chainPose(kin.chainLayout(b, null), (i) => q[i]).map((p) => p.ends);
        }, { bodies: Y, q: QY });
        assert.deepEqual(byIndex, r.pose.map((p) => p.ends));
    });
});

test('the kinematics of a spatial two-arm torso matches rotations written out by hand', async () => {
    /* a waist about z, then a torso; two arms on its shoulders (+-0.2, 0, 0.5) about the torso's x
       axis, each a 0.4 m rod along -z; the left names the torso, the right its index */
    const L = 0.4, S = [0.2, 0, 0.5];
    const bodies = [
        { name: 'torso', mass: 10, shape: { type: 'box', size: [0.3, 0.2, 0.5], centre: [0, 0, 0.25] }, joint: REV_Z },
        { name: 'left', parent: 'torso', mass: 1, shape: { type: 'rod', end: [0, 0, -L] }, joint: { type: 'revolute', axis: [1, 0, 0], location: S } },
        { name: 'right', parent: 0, mass: 1, shape: { type: 'rod', end: [0, 0, -L] }, joint: { type: 'revolute', axis: [1, 0, 0], location: [-S[0], S[1], S[2]] } },
    ];
    const q = [0.8, 0.5, -1.1];
    let r;
    await withView(browser, srv, '#/jobs', 'tree-kinematics-torso', async (page) => {
        r = await page.evaluate(async ({ bodies: b, q: qq }) => {
            const kin = await import('/kinematics.js');
            return kin.chainPose(kin.chainLayout(b, null), (i) => qq[i]).map((p) => ({ origin: p.origin, ends: p.ends }));
        }, { bodies, q });
    });
    /* Rz(a) v, and an arm's tip in the torso's frame: shoulder + Rx(b) (0, 0, -L) */
    const rz = (a, v) => [Math.cos(a) * v[0] - Math.sin(a) * v[1], Math.sin(a) * v[0] + Math.cos(a) * v[1], v[2]];
    const armTip = (sx, b) => [sx, S[1] + L * Math.sin(b), S[2] - L * Math.cos(b)];
    const want = {
        shoulders: [rz(q[0], S), rz(q[0], [-S[0], S[1], S[2]])],
        tips: [rz(q[0], armTip(S[0], q[1])), rz(q[0], armTip(-S[0], q[2]))],
    };
    const d = (a, b) => Math.hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);
    let gap = d(r[0].origin, [0, 0, 0]);
    gap = Math.max(gap, d(r[0].ends[0], want.shoulders[0]), d(r[0].ends[1], want.shoulders[1]));
    for (let k = 1; k <= 2; k++) {
        gap = Math.max(gap, d(r[k].origin, want.shoulders[k - 1]), d(r[k].ends[0], want.tips[k - 1]));
    }
    assert.equal(r[0].ends.length, 2, "the torso is drawn to both shoulders");
    assert.ok(gap < 1e-12, `the torso's poses are ${gap} m from the closed form`);
});

test('the animation draws every branch of a Y from its parent: pixels along each segment', async () => {
    await withView(browser, srv, '#/jobs', 'tree-animation', async (page) => {
        const r = await page.evaluate(async ({ bodies, q }) => {
            const { createAnimation } = await import('/animate.js');
            const { createTimeline } = await import('/timeline.js');
            const host = document.createElement('div');
            host.style.width = '400px';
            document.body.prepend(host);
            const series = { t: [0, 1], q: q.map((x) => [x, x]) };
            const spec = { scene: { gravity: [0, -9.81, 0], bodies } };
            createAnimation(host, { spec, form: 'planar', series, timeline: createTimeline(1) });
            const canvas = host.querySelector('canvas#anim');
            const g = canvas.getContext('2d');
            const dpr = canvas.width / canvas.clientWidth;
            /* the colour at a point of the canvas, in CSS pixels, for the checks below */
            window.__px = (x, y) => Array.from(g.getImageData(Math.round(x * dpr), Math.round(y * dpr), 1, 1).data);
            return { w: canvas.clientWidth, h: canvas.clientHeight, label: canvas.getAttribute('aria-label') };
        }, { bodies: Y, q: QY });
        assert.match(r.label, /animation of the tree/);
        /* the drawing's scale: the largest reach, 0.44 of the smaller side, origin at the centre,
           x right and y up (animate.js) */
        const want = yByHand(QY);
        const reach = Math.max(...want.tip.map((p) => Math.hypot(p[0], p[1])));
        const s = (0.44 * Math.min(r.w, r.h)) / reach;
        const toXY = (p) => [r.w / 2 + s * p[0], r.h / 2 - s * p[1]];
        const blue = [0x00, 0x72, 0xb2];
        const misses = [];
        for (let k = 0; k < 5; k++) {
            for (const f of [0.35, 0.65]) { /* off the joints' white discs */
                const o = want.origin[k], t = want.tip[k];
                const [x, y] = toXY([o[0] + f * (t[0] - o[0]), o[1] + f * (t[1] - o[1])]);
                const c = await page.evaluate(([xx, yy]) => window.__px(xx, yy), [x, y]);
                if (Math.max(...blue.map((v, i) => Math.abs(v - c[i]))) > 12) misses.push(`body ${k} at ${f}: rgb(${c.slice(0, 3)})`);
            }
        }
        assert.deepEqual(misses, [], 'segments not drawn where the Y has them');
        /* where a chain would put r1 (from l2's tip) nothing is drawn */
        const chainR1 = [want.tip[2][0] + 0.5 * Math.sin(QY[0] + QY[1] + QY[2] + QY[3]), want.tip[2][1] - 0.5 * Math.cos(QY[0] + QY[1] + QY[2] + QY[3])];
        const c = await page.evaluate(([xx, yy]) => window.__px(xx, yy), toXY(chainR1));
        assert.ok(Math.abs(c[2] - 0xb2) > 12 || Math.abs(c[0]) > 12, `r1 drawn as in a chain: rgb(${c.slice(0, 3)})`);
        await screenshot(page, 'tree-y.png');
    });
});

test('the job form has a parent selector per body, the previous body by default, writing the index chosen', async () => {
    await withView(browser, srv, '#/submit?preset=triple_pendulum_pd', 'tree-form', async (page) => {
        const field = (n) => page.evaluate((name) => document.querySelector(`#view [name="${name}"]`)?.value ?? null, n);
        await pollValue(() => field('scene.bodies[2].parent'), (v) => v !== null, 'scene.bodies[2].parent select');
        assert.deepEqual(await Promise.all([0, 1, 2].map((k) => field(`scene.bodies[${k}].parent`))), ['-1', '0', '1']);
        const options = await page.evaluate(() => [...document.querySelectorAll('#view [name="scene.bodies[2].parent"] option')]
            .map((o) => [o.value, o.textContent]));
        assert.deepEqual(options.map((o) => o[0]), ['-1', '0', '1'], 'the ground and the bodies before body 2');
        await page.locator('#view [name="scene.bodies[2].parent"]').selectOption('0');
        const doc = () => page.evaluate(() => JSON.parse(document.querySelector('textarea#job-json').value));
        await pollValue(doc, (d) => d.scene.bodies[2].parent === 0, 'scene.bodies[2].parent = 0 in the JSON');
        assert.equal((await doc()).scene.bodies[1].parent, undefined, 'the other bodies keep their default');
        /* the reverse: a parent given by name in the JSON shows as that body */
        const d = await doc();
        d.scene.bodies[2].parent = 'ground';
        await page.locator('textarea#job-json').fill(JSON.stringify(d, null, 2));
        await pollValue(() => field('scene.bodies[2].parent'), (v) => v === '-1', 'the select after "ground" in the JSON');
        await screenshot(page, 'tree-form.png');
    });
});

test('the job view of the y_pendulum_pd preset animates a tree', async () => {
    const job = await runJob(srv, { preset: 'y_pendulum_pd', duration: 0.5 });
    await withView(browser, srv, `#/jobs/${job.id}`, 'tree-job', async (page) => {
        await page.waitForSelector('canvas#anim');
        assert.match(await page.getAttribute('canvas#anim', 'aria-label'), /animation of the tree/);
        assert.equal(await page.getAttribute('canvas#anim', 'data-mode'), 'planar');
        const img = await animImage(page);
        assert.notEqual(img.image, img.blank, 'the canvas is blank');
        await screenshot(page, 'tree-job.png');
    });
});
