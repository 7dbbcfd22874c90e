/*
 * loop.test.mjs - closed chains in the page: the five-bar's job view plots its loop residuals,
 * draws one e, tau and w line per independent coordinate labelled with its joint and q_d only
 * for the driven joints, animates the chain between its two ground pivots, lists the loop's
 * metrics; a run that stopped as singular says so in its status; a passive four-bar (every joint
 * dependent) has no torque plot; a four-bar closed on an arm (a loop closed on a body) draws its
 * pivot on the arm, where the tip's closing point is at every sample; so does a loop on a tree
 * (y_four_bar_pd: the four-bar on the arm beside a double pendulum).
 */
import assert from 'node:assert/strict';
import { after, before, test } from 'node:test';

import { animImage, launchBrowser, plots, screenshot, startWebServer, text, withView } from './lib.mjs';

let srv;
let browser;
let five; /* five-bar PD, 1 s */
let singular; /* five-bar driven out of reach: stops as singular (job status failed) */
let four; /* passive four-bar, 1 s */
let arm; /* four-bar on an arm, PD, 2 s */
let yfour; /* a loop on a tree: the four-bar on the arm beside a double pendulum, PD, 2 s */

before(async () => {
    srv = await startWebServer();
    browser = await launchBrowser();
    const post = async (job) => {
        const res = await srv.post('/api/jobs?wait=60', job);
        if (res.status !== 200) throw new Error(`POST ${JSON.stringify(job)}: ${res.status} ${res.text.slice(0, 300)}`);
        return res.json;
    };
    five = await post({ preset: 'five_bar_pd', duration: 1 });
    singular = await post({
        preset: 'five_bar_pd', duration: 3, scene: { loop: { cond_max: 100 } },
        trajectory: [{ type: 'constant', value: 1.5 }, { type: 'constant', value: 0.785 }, { type: 'constant', value: -2.356 }],
    });
    four = await post({ preset: 'four_bar_passive', duration: 1 });
    arm = await post({ preset: 'arm_four_bar_pd', duration: 2 });
    yfour = await post({ preset: 'y_four_bar_pd', duration: 2 });
});

after(async () => {
    await browser?.close();
    await srv?.stop();
});

/* the legend labels of the plot of a channel */
function labels(page, channel) {
    return page.evaluate((ch) =>
        [...document.querySelectorAll(`div.plot[data-channel="${ch}"] .u-legend .u-series .u-label`)].map((l) => l.textContent.trim()),
    channel);
}

test('the five-bar: loop residuals, one e per independent coordinate with its joint, q_d for the driven joints', async () => {
    assert.equal(five.status, 'done', five.message);
    await withView(browser, srv, `#/jobs/${five.id}`, 'loop-five-bar', async (page) => {
        const by = Object.fromEntries((await plots(page)).map((p) => [p.channel, p]));
        for (const ch of ['q', 'e', 'tau', 'w', 'energy', 'loop']) {
            assert.ok(by[ch]?.uplot, `no drawn div.plot[data-channel="${ch}"]`);
        }
        assert.equal(by.q.series, 5 + 3, 'q: five coordinates, desired for the three driven ones');
        for (const ch of ['e', 'tau', 'w']) assert.equal(by[ch].series, 3, `${ch} data-series`);
        assert.equal(by.loop.series, 2, 'loop: position and velocity residuals');
        assert.deepEqual((await labels(page, 'e')).slice(1), ['e[0] (joint 0)', 'e[1] (joint 1)', 'e[2] (joint 2)']);
        /* the torques carry the channel's name, as in the CSV, the API and the README */
        assert.deepEqual((await labels(page, 'tau')).slice(1), ['tau[0] (joint 0)', 'tau[1] (joint 1)', 'tau[2] (joint 2)']);
        const tauTitle = await page.evaluate(() => document.querySelector('div.plot[data-channel="tau"]')?.closest('figure')?.querySelector('figcaption')?.textContent);
        assert.equal(tauTitle, 'Driving torques tau');
        assert.deepEqual((await labels(page, 'loop')).slice(1), ['position residual', 'velocity residual']);
        const qLabels = await labels(page, 'q');
        assert.ok(qLabels.includes('q_d[2]') && !qLabels.includes('q_d[3]'), `q legend: ${qLabels}`);

        /* toggles per coordinate of q; the metrics name the loop */
        const joints = await page.evaluate(() =>
            [...new Set([...document.querySelectorAll('button.joint-toggle[data-joint]')].map((b) => b.getAttribute('data-joint')))]);
        assert.deepEqual(joints, ['0', '1', '2', '3', '4']);
        const metrics = await text(page, 'dl#metrics');
        assert.match(metrics, /loop residual max/);
        assert.match(metrics, /3 independent/);

        /* the chain is drawn */
        const img = await animImage(page);
        assert.notEqual(img.image, img.blank, 'canvas#anim is blank');
        await screenshot(page, 'loop-five-bar.png');
    });
});

test('a run stopped as singular shows it in its status and message', async () => {
    assert.equal(singular.status, 'failed');
    assert.equal(singular.metrics.status, 'singular');
    await withView(browser, srv, `#/jobs/${singular.id}`, 'loop-singular', async (page) => {
        assert.equal(await text(page, '#job-status'), 'failed (singular)');
        assert.match(await text(page, 'dl#metrics'), /singular: .*cannot drive the loop/);
        const by = Object.fromEntries((await plots(page)).map((p) => [p.channel, p]));
        assert.ok(by.loop?.uplot, 'the samples up to the stop are plotted');
    });
});

test('a passive loop of dependent joints has no torque plot, and its residuals are plotted', async () => {
    assert.equal(four.status, 'done', four.message);
    await withView(browser, srv, `#/jobs/${four.id}`, 'loop-four-bar', async (page) => {
        const channels = (await plots(page)).map((p) => p.channel);
        assert.deepEqual(channels, ['q', 'energy', 'loop']);
        assert.match(await text(page, 'dl#metrics'), /none \(every joint passive\)/);
    });
});

test('a loop closed on a body: its pivot is drawn on the body, where the tip closes the loop', async () => {
    assert.equal(arm.status, 'done', arm.message);
    await withView(browser, srv, `#/jobs/${arm.id}`, 'loop-arm-four-bar', async (page) => {
        const channels = (await plots(page)).map((p) => p.channel);
        for (const ch of ['q', 'e', 'tau', 'loop']) assert.ok(channels.includes(ch), `no ${ch} plot: ${channels}`);
        assert.match(await text(page, 'div.anim-wrap + p'), /pivot on a body/);
        const img = await animImage(page);
        assert.notEqual(img.image, img.blank, 'canvas#anim is blank');

        /* the page's kinematics: the anchor on the arm meets the tip's closing point at every
           sample; taken as a world point it would be metres away */
        const gaps = await page.evaluate(async (id) => {
            const kin = await import('/kinematics.js');
            const job = await (await fetch(`/api/jobs/${id}`)).json();
            const series = await (await fetch(`/api/jobs/${id}/series?format=json&channels=q`)).json();
            const loop = job.spec.scene.loop;
            const layout = kin.chainLayout(job.spec.scene.bodies, loop);
            const q = series.q;
            let onBody = 0, inWorld = 0;
            for (let k = 0; k < series.t.length; k++) {
                const pose = kin.chainPose(layout, (i) => q[i][k]);
                const end = pose[pose.length - 1].end;
                const a = kin.loopAnchor(loop, pose), w = loop.anchor;
                onBody = Math.max(onBody, Math.hypot(end[0] - a[0], end[1] - a[1], end[2] - a[2]));
                inWorld = Math.max(inWorld, Math.hypot(end[0] - w[0], end[1] - w[1], end[2] - w[2]));
            }
            return { onBody, inWorld };
        }, arm.id);
        assert.ok(gaps.onBody < 1e-6, `tip to the anchor on the arm: ${gaps.onBody} m`);
        assert.ok(gaps.inWorld > 0.1, `the anchor read as a world point would close it: ${gaps.inWorld} m`);
        await screenshot(page, 'loop-arm-four-bar.png');
    });
});

test('a loop on a tree: the branch is drawn and the tip meets its pivot on the arm', async () => {
    assert.equal(yfour.status, 'done', yfour.message);
    await withView(browser, srv, `#/jobs/${yfour.id}`, 'loop-y-four-bar', async (page) => {
        const channels = (await plots(page)).map((p) => p.channel);
        for (const ch of ['q', 'e', 'tau', 'loop']) assert.ok(channels.includes(ch), `no ${ch} plot: ${channels}`);
        assert.match(await text(page, 'div.anim-wrap + p'), /pivot on a body/);
        const img = await animImage(page);
        assert.notEqual(img.image, img.blank, 'canvas#anim is blank');

        /* the page's kinematics on the tree: the arm's end is drawn as a fan (the crank and the
           pendulum hang from it), and the tip's closing point meets the anchor on the arm */
        const got = await page.evaluate(async (id) => {
            const kin = await import('/kinematics.js');
            const job = await (await fetch(`/api/jobs/${id}`)).json();
            const series = await (await fetch(`/api/jobs/${id}/series?format=json&channels=q`)).json();
            const loop = job.spec.scene.loop;
            const layout = kin.chainLayout(job.spec.scene.bodies, loop);
            const q = series.q;
            let gap = 0;
            for (let k = 0; k < series.t.length; k++) {
                const pose = kin.chainPose(layout, (i) => q[i][k]);
                const end = pose[pose.length - 1].end, a = kin.loopAnchor(loop, pose);
                gap = Math.max(gap, Math.hypot(end[0] - a[0], end[1] - a[1], end[2] - a[2]));
            }
            return { gap, parents: layout.map((l) => l.parent), armEnds: layout[0].ends.length };
        }, yfour.id);
        assert.deepEqual(got.parents, [-1, 0, 1, 0, 3, 2]);
        assert.equal(got.armEnds, 2, 'the arm ends in two segments, to the crank and the pendulum');
        assert.ok(got.gap < 1e-6, `tip to the anchor on the arm: ${got.gap} m`);
        await screenshot(page, 'loop-y-four-bar.png');
    });
});
