/*
 * job.test.mjs - the job view (#/jobs/ID), opened by a deep link: status, plots drawn from the
 * samples the page fetched (actual and desired lines for q, one line per coordinate for e),
 * per-joint toggles, metrics and spec, the CSV and JSON downloads against the API, the time
 * cursor shared by the plots and the animation (planar and spatial), play and pause, the view of
 * a running job following its progress until it is cancelled, and the keyboard.
 */
import assert from 'node:assert/strict';
import { readFile } from 'node:fs/promises';
import { after, before, test } from 'node:test';

import {
    animImage,
    apiJob,
    attr,
    fetchedSeries,
    frames,
    launchBrowser,
    near,
    plotCursors,
    plots,
    poll,
    pollValue,
    runJob,
    screenshot,
    screenshotOf,
    setCursor,
    startWebServer,
    stopJob,
    submit,
    tabThrough,
    text,
    waitJob,
    withView,
} from './lib.mjs';

let srv;
let browser;
let planar; /* triple pendulum, PID, 2 s: 201 samples, 3 coordinates */
let spatial; /* spatial double pendulum, PID, 1 s: 2 coordinates */

before(async () => {
    srv = await startWebServer();
    browser = await launchBrowser();
    planar = await runJob(srv, { preset: 'triple_pendulum_pid', duration: 2 });
    spatial = await runJob(srv, { preset: 'spatial_double_pendulum_pid', duration: 1 });
});

after(async () => {
    await browser?.close();
    await srv?.stop();
});

test('a deep link #/jobs/ID opens the job: status done, metrics, the spec as JSON, no progress bar', async () => {
    await withView(browser, srv, `#/jobs/${planar.id}`, 'job-deep-link', async (page) => {
        assert.match(await text(page, '#job-status'), /done/i);
        assert.equal(await page.locator('progress#job-progress').count(), 0, 'progress#job-progress on a finished job');
        const dl = await page.evaluate(() => {
            const d = document.querySelector('dl#metrics');
            return d && { dt: d.querySelectorAll('dt').length, dd: d.querySelectorAll('dd').length };
        });
        assert.ok(dl, 'no dl#metrics');
        assert.ok(dl.dt >= 3 && dl.dd >= dl.dt, `dl#metrics: ${dl.dt} dt, ${dl.dd} dd`);
        let spec;
        try {
            spec = JSON.parse(await text(page, 'pre#spec'));
        } catch (e) {
            assert.fail(`pre#spec is not the job as JSON: ${e.message}`);
        }
        assert.deepEqual(spec, planar.spec, 'pre#spec differs from GET /api/jobs/ID spec');
        await screenshot(page, 'job.png');
    });
});

test('plots: q draws actual and desired per coordinate, e one per coordinate, from the samples fetched', async () => {
    const samples = planar.metrics.samples;
    const nq = planar.metrics.nq;
    assert.equal(samples, 201);
    await withView(browser, srv, `#/jobs/${planar.id}`, 'job-plots', async (page) => {
        const all = await plots(page);
        const by = Object.fromEntries(all.map((p) => [p.channel, p]));
        for (const ch of ['q', 'e', 'tau', 'w', 'energy']) {
            assert.ok(by[ch], `no div.plot[data-channel="${ch}"] (plots: ${JSON.stringify(all)})`);
            assert.ok(by[ch].uplot, `div.plot[data-channel="${ch}"] holds no drawn uPlot canvas`);
        }
        const q = by.q;
        assert.ok(q.points > 100 && q.points <= samples, `q data-points ${q.points}, want in (100, ${samples}]`);
        /* the points drawn are those of a series the page fetched (whatever decimation it chose) */
        const fetched = await fetchedSeries(page);
        assert.ok(
            fetched.some((s) => s.samples === q.points),
            `q data-points ${q.points} is the length of no series fetched: ${JSON.stringify(fetched)}`,
        );
        const every = fetched.find((s) => s.samples === q.points).every;
        assert.equal(q.points, Math.ceil(samples / every), `every=${every} of ${samples} samples`);
        assert.equal(q.series, 2 * nq, 'q data-series: actual and desired per coordinate');
        assert.equal(by.e.series, nq, 'e data-series');
        assert.equal(by.tau.series, nq, 'tau data-series');
        assert.equal(by.w.series, nq, 'w data-series');
        assert.ok(by.energy.series >= 2 && by.energy.series <= 3, `energy data-series ${by.energy.series}`);
        for (const p of all) assert.equal(p.points, q.points, `${p.channel} data-points against q's`);
    });
});

test('joint toggles: one per coordinate, aria-pressed flips on a click and back', async () => {
    await withView(browser, srv, `#/jobs/${planar.id}`, 'job-toggles', async (page) => {
        const joints = await page.evaluate(() =>
            [...new Set([...document.querySelectorAll('button.joint-toggle[data-joint]')].map((b) => b.getAttribute('data-joint')))].sort(),
        );
        assert.deepEqual(joints, ['0', '1', '2']);
        const sel = 'button.joint-toggle[data-joint="1"]';
        assert.equal(await attr(page, sel, 'aria-pressed'), 'true', `${sel} starts pressed (shown)`);
        await page.locator(sel).first().click();
        await pollValue(() => attr(page, sel, 'aria-pressed'), (v) => v === 'false', `${sel} aria-pressed after a click`);
        await page.locator(sel).first().click();
        await pollValue(() => attr(page, sel, 'aria-pressed'), (v) => v === 'true', `${sel} aria-pressed after a second click`);
    });
});

test('download CSV: the file is GET /api/jobs/ID/series?format=csv; the JSON link has every sample', async () => {
    await withView(browser, srv, `#/jobs/${planar.id}`, 'job-download', async (page) => {
        const href = await attr(page, 'a#download-csv', 'href');
        const url = new URL(href, srv.base);
        assert.equal(url.pathname, `/api/jobs/${planar.id}/series`);
        assert.equal(url.searchParams.get('format'), 'csv', href);
        const [download] = await Promise.all([page.waitForEvent('download', { timeout: 10000 }), page.locator('a#download-csv').click()]);
        const got = await readFile(await download.path(), 'utf8');
        const fromHref = await srv.get(url.pathname + url.search);
        assert.equal(fromHref.status, 200);
        assert.equal(got, fromHref.text, 'the downloaded file differs from its href');
        if ([...url.searchParams.keys()].length === 1) {
            const full = await srv.get(`/api/jobs/${planar.id}/series?format=csv`);
            assert.equal(got, full.text, 'the download differs from GET /api/jobs/ID/series?format=csv');
        }
        assert.match(got, /^t,q\[0\],/);
        assert.equal(got.trimEnd().split('\n').length - 1, planar.metrics.samples, 'CSV rows');

        const jhref = new URL(await attr(page, 'a#download-json', 'href'), srv.base);
        assert.equal(jhref.pathname, `/api/jobs/${planar.id}/series`);
        assert.equal(jhref.searchParams.get('format'), 'json');
        const json = await srv.get(jhref.pathname + jhref.search);
        assert.equal(json.status, 200);
        assert.equal(json.json.t.length, planar.metrics.samples, 'JSON download samples');
    });
});

test('time cursor: the animation follows it within one sample, by value, by keyboard and from a plot', async () => {
    const duration = planar.spec.duration;
    const dt = planar.spec.output.interval;
    await withView(browser, srv, `#/jobs/${planar.id}`, 'job-cursor', async (page) => {
        const range = await page.evaluate(() => {
            const el = document.querySelector('input#time-cursor');
            return el && { type: el.type, min: Number(el.min), max: Number(el.max), value: Number(el.value) };
        });
        assert.ok(range, 'no input#time-cursor');
        assert.equal(range.type, 'range');
        assert.equal(range.min, 0);
        near(range.max, duration, 1e-9, 'input#time-cursor max');
        assert.equal(await attr(page, 'canvas#anim', 'data-mode'), 'planar');
        const animTime = async () => Number(await attr(page, 'canvas#anim', 'data-time'));
        const follows = (want) =>
            pollValue(animTime, (t) => Math.abs(t - want) <= dt + 1e-9, `canvas#anim data-time following the cursor at ${want}`);

        /* by value */
        const t0 = await setCursor(page, 0);
        await follows(t0);
        const img0 = await animImage(page);
        assert.notEqual(img0.image, img0.blank, 'canvas#anim is blank');
        const t1 = await setCursor(page, 1.23);
        near(t1, 1.23, dt, 'input#time-cursor value kept');
        await follows(t1);
        await poll(async () => {
            const shown = Number((await text(page, 'output#time-value'))?.match(/-?[0-9.]+/)?.[0]);
            return Math.abs(shown - t1) <= dt + 1e-9;
        }, `output#time-value showing ${t1}`);
        const img1 = await animImage(page);
        assert.notEqual(img1.image, img0.image, 'the animation did not change between t = 0 and t = 1.23');
        /* and every plot's cursor line stands at t1 (the time axis spans [0, duration]) */
        await pollValue(
            () => plotCursors(page),
            (c) => c.length >= 5 && c.every((p) => p.at !== null && Math.abs(p.at - t1 / duration) < 0.02),
            `every plot's cursor line at ${t1 / duration} of its width`,
        );
        await screenshot(page, 'job-cursor.png');

        /* by keyboard */
        await page.locator('input#time-cursor').focus();
        await page.keyboard.press('ArrowRight');
        const t2 = await pollValue(
            () => page.evaluate(() => Number(document.querySelector('input#time-cursor').value)),
            (v) => v > t1,
            'input#time-cursor value after ArrowRight',
        );
        await follows(t2);
        await page.keyboard.press('End');
        await pollValue(
            () => page.evaluate(() => Number(document.querySelector('input#time-cursor').value)),
            (v) => Math.abs(v - duration) < 1e-9,
            'input#time-cursor value after End',
        );
        await follows(duration);

        /* from a plot: the cursor over the middle of the e plot moves the time cursor there */
        const over = page.locator('div.plot[data-channel="e"] .u-over').first();
        const box = await over.boundingBox();
        assert.ok(box, 'the e plot has no .u-over (uPlot cursor layer)');
        await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
        const tm = await pollValue(
            () => page.evaluate(() => Number(document.querySelector('input#time-cursor').value)),
            (v) => Math.abs(v - duration / 2) <= 0.1 * duration,
            `input#time-cursor after moving the cursor over the middle of the e plot (about ${duration / 2})`,
        );
        await follows(tm);
    });
});

test('play advances the animation, pause stops it; speeds 4, 2, 1, 0.5, 0.25, 0.1', async () => {
    await withView(browser, srv, `#/jobs/${planar.id}`, 'job-play', async (page) => {
        const speeds = await page.evaluate(() => [...document.querySelectorAll('select#speed option')].map((o) => Number(o.value)));
        assert.deepEqual([...speeds].sort((a, b) => a - b), [0.1, 0.25, 0.5, 1, 2, 4]);
        await page.selectOption('select#speed', { index: speeds.indexOf(0.5) });
        await setCursor(page, 0);
        const animTime = async () => Number(await attr(page, 'canvas#anim', 'data-time'));
        await pollValue(animTime, (t) => t < 0.02, 'canvas#anim data-time at the start');
        await page.locator('button#play').click();
        await pollValue(() => attr(page, 'button#play', 'aria-pressed'), (v) => v === 'true', 'button#play aria-pressed while playing');
        await pollValue(animTime, (t) => t > 0.05, 'canvas#anim data-time advancing while playing');
        await page.locator('button#play').click();
        await pollValue(() => attr(page, 'button#play', 'aria-pressed'), (v) => v === 'false', 'button#play aria-pressed after pause');
        /* paused: the time drawn stays where it stopped, over several frames */
        await frames(page, 2);
        const stopped = await animTime();
        await frames(page, 10);
        assert.equal(await animTime(), stopped, 'canvas#anim data-time moved while paused');
    });
});

test('a spatial chain is animated in 3-D (data-mode spatial) and its plots count its 2 coordinates', async () => {
    assert.equal(spatial.metrics.form, 'spatial');
    await withView(browser, srv, `#/jobs/${spatial.id}`, 'spatial-anim', async (page) => {
        assert.equal(await attr(page, 'canvas#anim', 'data-mode'), 'spatial');
        const by = Object.fromEntries((await plots(page)).map((p) => [p.channel, p]));
        assert.equal(by.q?.series, 4, 'q data-series');
        assert.equal(by.e?.series, 2, 'e data-series');
        const t = await setCursor(page, 0.5);
        await pollValue(
            async () => Number(await attr(page, 'canvas#anim', 'data-time')),
            (v) => Math.abs(v - t) <= spatial.spec.output.interval + 1e-9,
            'canvas#anim data-time following the cursor',
        );
        const img = await animImage(page);
        assert.notEqual(img.image, img.blank, 'canvas#anim is blank');
        await screenshot(page, 'job-spatial.png');
        await screenshotOf(page, 'canvas#anim', 'spatial-anim.png');
    });
});

test('a running job shows its progress rising, then cancelled when it is cancelled', async () => {
    /* about 70 s of work: it runs all through this test, which cancels it */
    const row = await submit(srv, {
        preset: 'n_link_pendulum',
        n: 32,
        duration: 100,
        integrator: { method: 'rk4', step: 0.0001 },
        output: { interval: 0.5 },
    });
    try {
        await waitJob(srv, row.id, { until: (j) => j.status === 'running' && j.progress > 0 });
        await withView(
            browser,
            srv,
            `#/jobs/${row.id}`,
            'job-running',
            async (p) => {
                assert.match(await text(p, '#job-status'), /running/i);
                const value = () => p.evaluate(() => document.querySelector('progress#job-progress')?.value ?? null);
                const first = await pollValue(value, (v) => v !== null, 'progress#job-progress on a running job');
                await pollValue(value, (v) => v !== null && v > first, `progress#job-progress rising from ${first}`);
                await screenshot(p, 'job-running.png');
                const del = await srv.del(`/api/jobs/${row.id}`);
                assert.equal(del.status, 202, del.text);
                await pollValue(() => text(p, '#job-status'), (s) => /cancel/i.test(s || ''), '#job-status after DELETE');
                await poll(async () => (await p.locator('progress#job-progress').count()) === 0, 'progress#job-progress gone once cancelled');
            },
            { selector: '#job-status', jobLinks: false },
        );
    } finally {
        await stopJob(srv, row.id);
    }
});

test('keyboard: Tab reaches the nav links, the play button, the cursor, the toggles and the downloads', async () => {
    await withView(browser, srv, `#/jobs/${planar.id}`, 'job-keyboard', async (page) => {
        const targets = [
            'nav a[href="#/jobs"]',
            'nav a[href="#/submit"]',
            'nav a[href="#/compare"]',
            'button#play',
            'input#time-cursor',
            'select#speed',
            'button.joint-toggle[data-joint="0"]',
            'a#download-csv',
            'a#download-json',
        ];
        const r = await tabThrough(page, targets);
        assert.deepEqual(r.missed, [], `never focused by Tab; the order was ${r.order.join(' > ')}`);
        /* a focused toggle answers the keyboard */
        await page.locator('button.joint-toggle[data-joint="0"]').first().focus();
        await page.keyboard.press('Enter');
        await pollValue(
            () => attr(page, 'button.joint-toggle[data-joint="0"]', 'aria-pressed'),
            (v) => v === 'false',
            'joint toggle 0 aria-pressed after Enter',
        );
    });
});

test('the job view names the job as GET /api/jobs/ID does', async () => {
    const job = await apiJob(srv, planar.id);
    await withView(browser, srv, `#/jobs/${planar.id}`, 'job-name', async (page) => {
        const body = await page.evaluate(() => document.querySelector('#view').textContent);
        assert.ok(body.includes(job.name), `the view does not name the job "${job.name}"`);
    });
});

test("the page's kinematics walks each body's parent: a chain in closed form, a branch from its parent", async () => {
    await withView(browser, srv, `#/jobs/${planar.id}`, 'job-kinematics', async (page) => {
        const r = await page.evaluate(async (id) => {
            const kin = await import('/kinematics.js');
            const job = await (await fetch(`/api/jobs/${id}`)).json();
            const bodies = job.spec.scene.bodies; /* three 1 m rods, revolute about +z */
            const q = [0.4, -1.1, 2.3];
            const layout = kin.chainLayout(bodies, null);
            const chain = kin.chainPose(layout, (i) => q[i]);
            /* closed form: rod k hangs at the absolute angle th_k = q_0 + ... + q_k */
            let gap = 0, th = 0, x = 0, y = 0;
            for (let k = 0; k < 3; k++) {
                th += q[k];
                gap = Math.max(gap, Math.hypot(chain[k].origin[0] - x, chain[k].origin[1] - y));
                x += Math.sin(th), y -= Math.cos(th);
                gap = Math.max(gap, Math.hypot(chain[k].end[0] - x, chain[k].end[1] - y));
            }
            /* a tree by hand: rod 2 on rod 0's tip (joint 2's location is rod 0's end too) */
            layout[2].parent = 0;
            const tree = kin.chainPose(layout, (i) => q[i]);
            const th2 = q[0] + q[2], t0 = tree[0].end;
            const branch = Math.max(Math.hypot(tree[2].origin[0] - t0[0], tree[2].origin[1] - t0[1]),
                Math.hypot(tree[2].end[0] - t0[0] - Math.sin(th2), tree[2].end[1] - t0[1] + Math.cos(th2)));
            return { parents: kin.chainParents(bodies), gap, branch, moved: tree[2].origin[0] - chain[2].origin[0] };
        }, planar.id);
        assert.deepEqual(r.parents, [-1, 0, 1]);
        assert.ok(r.gap < 1e-12, `the chain's poses are ${r.gap} m from the closed form`);
        assert.ok(r.branch < 1e-12, `rod 2 hung on rod 0 is ${r.branch} m from where it should be`);
        assert.ok(Math.abs(r.moved) > 0.1, 'the branch was drawn where the chain puts rod 2');
    });
});
