/*
 * axes.test.mjs - the plots' axes: each coordinate's own unit (rad or m, N m or N) from its
 * joint's type, tick labels that tell a loop's tiny residuals apart and are never wider than
 * their axis, a one-sample run drawn around its time rather than on 0-100 s, and joint colours
 * that do not repeat (an n-link chain's toggles). Screenshots at 1400x900 and 390x844
 * (artifacts/axes-*.png).
 */
import assert from 'node:assert/strict';
import { after, before, test } from 'node:test';

import { attr, launchBrowser, newPage, runJob, screenshot, startWebServer, waitView } from './lib.mjs';

let srv;
let browser;
const jobs = {};

before(async () => {
    srv = await startWebServer();
    browser = await launchBrowser();
    /* the triple pendulum with its last joint prismatic (along -y, where the rod hangs) */
    const doc = (await srv.get('/api/presets/triple_pendulum_pd')).json;
    doc.scene.bodies[2].joint = { type: 'prismatic', axis: [0, -1, 0], location: doc.scene.bodies[2].joint.location };
    doc.duration = 0.5;
    doc.name = 'slider';
    jobs.slider = await runJob(srv, doc);
    jobs.pid = await runJob(srv, { preset: 'triple_pendulum_pid', duration: 1, controller: { kp: 400, kv: 40 } });
    jobs.five = await runJob(srv, { preset: 'five_bar_pd', duration: 1 });
    jobs.chain = await runJob(srv, { preset: 'n_link_pendulum', n: 12, duration: 0.2 });
});

after(async () => {
    await browser?.close();
    await srv?.stop();
});

async function atJob(id, name, fn, { width = 1400, height = 900 } = {}) {
    const page = await newPage(browser);
    try {
        await page.setViewportSize({ width, height });
        await page.goto(`${srv.base}/#/jobs/${id}`);
        await waitView(page, `#/jobs/${id}`);
        await fn(page);
        assert.deepEqual(page.errors, [], `uncaught errors in the page of job ${id}`);
    } catch (e) {
        await screenshot(page, `FAIL-${name}.png`).catch(() => {});
        throw e;
    } finally {
        await page.context().close();
    }
}

const unit = (page, ch) => attr(page, `div.plot[data-channel="${ch}"]`, 'data-unit');

test('each coordinate has its own unit: rad and m, N m and N', async () => {
    await atJob(jobs.slider.id, 'axes-units', async (page) => {
        assert.equal(await unit(page, 'q'), 'q [rad | m]');
        assert.equal(await unit(page, 'e'), 'e [rad | m]');
        assert.equal(await unit(page, 'tau'), 'tau [N m | N]');
        assert.equal(await unit(page, 'w'), 'w [rad/s² | m/s²]');
        const labels = await page.locator('div.plot[data-channel="q"] .u-legend .u-label').allTextContents();
        assert.ok(labels.includes('q[2] (m)') && labels.includes('q[0] (rad)'), `q's legend: ${JSON.stringify(labels)}`);
        const tau = await page.locator('div.plot[data-channel="tau"] .u-legend .u-label').allTextContents();
        assert.ok(tau.includes('tau[2] (N)') && tau.includes('tau[1] (N m)'), `tau's legend: ${JSON.stringify(tau)}`);
        await screenshot(page, 'axes-units-1400.png');
    });
    await atJob(jobs.pid.id, 'axes-units-revolute', async (page) => {
        assert.equal(await unit(page, 'q'), 'q [rad]');
        assert.equal(await unit(page, 'tau'), 'tau [N m]');
        assert.equal(await unit(page, 'w'), 'w [rad/s²]');
    });
});

test('tick labels: a loop residual is readable, and no label is wider than its axis', async () => {
    await atJob(jobs.five.id, 'axes-loop', async (page) => {
        const ticks = (await attr(page, 'div.plot[data-channel="loop"]', 'data-y-ticks')).split('|');
        const nonzero = ticks.filter((t) => t !== '0');
        assert.ok(nonzero.length >= 2, `loop ticks ${ticks}`);
        assert.equal(new Set(ticks).size, ticks.length, `every loop tick tells itself apart: ${ticks}`);
        assert.ok(nonzero.every((t) => /e-[0-9]+$/.test(t)), `tiny ticks in exponent form: ${ticks}`);
        await screenshot(page, 'axes-loop-1400.png');
        await page.setViewportSize({ width: 390, height: 844 });
        await screenshot(page, 'axes-loop-390.png');
    });
    await atJob(jobs.pid.id, 'axes-clip', async (page) => {
        for (const ch of ['q', 'e', 'tau', 'w', 'energy']) {
            const { width, text } = await page.evaluate((c) => {
                const box = document.querySelector(`div.plot[data-channel="${c}"]`);
                const labels = box.dataset.yTicks.split('|');
                const ctx = document.createElement('canvas').getContext('2d');
                ctx.font = '13px system-ui, sans-serif';
                const longest = Math.max(...labels.map((l) => ctx.measureText(l).width));
                return { width: Number(box.dataset.axisWidth), text: longest, labels };
            }, ch);
            /* the label, the tick (10 px), the gap and the axis title (26 px) fit in the axis */
            assert.ok(width >= text + 36, `${ch}: axis ${width} px for labels ${text} px wide`);
        }
    });
});

test('a run of one sample is drawn around its time, not on 0-100 s', async () => {
    await atJob(jobs.pid.id, 'axes-one-sample', async (page) => {
        const r = await page.evaluate(async () => {
            const { createPlots } = await import('/plots.js');
            const { createTimeline } = await import('/timeline.js');
            const host = document.createElement('div');
            host.style.width = '600px';
            document.body.append(host);
            const plots = createPlots(host, [{ label: 'one', color: '#000', series: { t: [0.25], q: [[0.1]], e: [[0.01]] }, joints: null, coords: [], loop: false }], createTimeline(0.25));
            await new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r)));
            const box = host.querySelector('div.plot[data-channel="q"]');
            const out = { points: box.dataset.points, xmin: Number(box.dataset.xmin), xmax: Number(box.dataset.xmax) };
            plots.destroy();
            host.remove();
            return out;
        });
        assert.equal(r.points, '1');
        assert.ok(r.xmin < 0.25 && r.xmax > 0.25 && r.xmax - r.xmin < 1, `x from ${r.xmin} to ${r.xmax}`);
    });
});

test('joint colours do not repeat: twelve coordinates, twelve colours', async () => {
    await atJob(jobs.chain.id, 'axes-colours', async (page) => {
        const colours = await page.locator('button.joint-toggle .swatch').evaluateAll((s) => s.map((x) => getComputedStyle(x).backgroundColor));
        assert.equal(colours.length, 12);
        assert.equal(new Set(colours).size, 12, `toggle colours ${colours}`);
        const palette = await page.evaluate(async () => (await import('/plots.js')).PALETTE.slice(0, 64));
        assert.equal(new Set(palette).size, 64, 'the first 64 colours are distinct');
        await screenshot(page, 'axes-colours-1400.png');
        await page.setViewportSize({ width: 390, height: 844 });
        await screenshot(page, 'axes-colours-390.png');
    });
});
