/*
 * runs.test.mjs - comparing runs (#/compare?ids=...): the table of figures against each job's
 * metrics from the API (the oracle), its sort and its CSV; legends that name the controller and
 * what differs; |e| on a log axis and the value zoom; the paper's layout; the view restored from
 * its address; each plot saved as PNG and SVG; the runs animated side by side at 1x to 4x; the
 * 3-D view's zoom, pan and reset; a closed chain's desired pose. Screenshots at 1400x900 and
 * 390x844 (artifacts/compare-*.png, anim-*.png).
 */
import assert from 'node:assert/strict';
import { readFileSync } from 'node:fs';
import { after, before, test } from 'node:test';

import {
    animImage,
    apiJob,
    attr,
    launchBrowser,
    newPage,
    poll,
    pollValue,
    runJob,
    screenshot,
    setCursor,
    startWebServer,
    text,
    waitView,
} from './lib.mjs';

let srv;
let browser;
const jobs = {};

before(async () => {
    srv = await startWebServer();
    browser = await launchBrowser();
    jobs.pid = await runJob(srv, { preset: 'triple_pendulum_pid', duration: 2 });
    jobs.fast = await runJob(srv, { preset: 'triple_pendulum_pid', duration: 2, controller: { kp: 400 } });
    jobs.pd = await runJob(srv, { preset: 'triple_pendulum_pd', duration: 2 });
    jobs.spatial = await runJob(srv, { preset: 'spatial_double_pendulum_pd', duration: 1 });
    jobs.five = await runJob(srv, { preset: 'five_bar_pd', duration: 1 });
});

after(async () => {
    await browser?.close();
    await srv?.stop();
});

/* Runs fn(page) on a fresh page of the given size at hash; no uncaught errors allowed. */
async function atView(hash, name, fn, { width = 1400, height = 900, selector } = {}) {
    const page = await newPage(browser);
    try {
        await page.setViewportSize({ width, height });
        await page.goto(`${srv.base}/${hash}`);
        await waitView(page, hash.startsWith('#/compare') ? null : hash, { selector: selector ?? (hash.startsWith('#/compare') ? 'table#compare-table' : undefined) });
        await fn(page);
        assert.deepEqual(page.errors, [], `uncaught errors in the page at ${hash}`);
    } catch (e) {
        await screenshot(page, `FAIL-${name}.png`).catch(() => {});
        if (page.errors.length) e.message += `\n  page errors:\n    ${page.errors.join('\n    ')}`;
        throw e;
    } finally {
        await page.context().close();
    }
}

/* the table: [{id, values: {key: data-value as a number}}] in the order shown */
function tableRows(page) {
    return page.evaluate(() =>
        [...document.querySelectorAll('table#compare-table tbody tr')].map((tr) => ({
            id: Number(tr.dataset.jobId),
            values: Object.fromEntries([...tr.querySelectorAll('td[data-value]')].map((td) => [td.dataset.key, td.dataset.value === '' ? null : Number(td.dataset.value)])),
        })),
    );
}

/* a download started by clicking sel: {name, bytes} */
async function downloadOf(page, sel) {
    const [dl] = await Promise.all([page.waitForEvent('download'), page.locator(sel).first().click()]);
    return { name: dl.suggestedFilename(), bytes: readFileSync(await dl.path()) };
}

const hashOf = (page) => page.evaluate(() => decodeURIComponent(location.hash));
const plotAttr = (page, sel, name) => attr(page, `div.plot${sel}`, name);

test('the comparison table: each job\'s figures as its metrics say, sorted by any column, saved as CSV', async () => {
    const ids = [jobs.pid.id, jobs.fast.id, jobs.pd.id];
    const full = Object.fromEntries(await Promise.all(ids.map(async (id) => [id, await apiJob(srv, id)])));
    await atView(`#/compare?ids=${ids.join(',')}`, 'compare-table', async (page) => {
        const rows = await tableRows(page);
        assert.deepEqual(rows.map((r) => r.id), ids, 'one row per job, in the order of the address');
        for (const r of rows) {
            const m = full[r.id].metrics;
            for (let j = 0; j < 3; j++) {
                assert.equal(r.values[`e_final.${j}`], Math.abs(m.e_final[j]), `job ${r.id} final |e| [${j}]`);
                assert.equal(r.values[`e_rms.${j}`], Math.abs(m.e_rms[j]), `job ${r.id} RMS e [${j}]`);
                assert.equal(r.values[`e_max.${j}`], Math.abs(m.e_max[j]), `job ${r.id} max |e| [${j}]`);
            }
            assert.equal(r.values.tau_peak, Math.max(...m.tau_peak.map(Math.abs)), `job ${r.id} peak torque`);
            assert.equal(r.values.us_per_eval, m.us_per_eval, `job ${r.id} µs per evaluation`);
        }
        const gains = await text(page, `table#compare-table tr[data-job-id="${jobs.fast.id}"] td[data-key="gains"]`);
        assert.match(gains, /kp 400/, 'the gains column');

        /* sorted by the final error of coordinate 2, then the other way */
        const byFinal = (dir) => ids.slice().sort((a, b) => dir * (Math.abs(full[a].metrics.e_final[2]) - Math.abs(full[b].metrics.e_final[2])));
        await page.locator('button.sort[data-key="e_final.2"]').click();
        assert.deepEqual((await tableRows(page)).map((r) => r.id), byFinal(1), 'ascending');
        assert.equal(await attr(page, 'th:has(button.sort[data-key="e_final.2"])', 'aria-sort'), 'ascending');
        await page.locator('button.sort[data-key="e_final.2"]').click();
        assert.deepEqual((await tableRows(page)).map((r) => r.id), byFinal(-1), 'descending');
        await pollValue(() => hashOf(page), (h) => h.includes('sort=e_final.2:desc'), 'the sort in the address');

        const csv = await downloadOf(page, 'button#compare-csv');
        assert.equal(csv.name, 'ctcsim-compare.csv');
        const lines = csv.bytes.toString('utf8').trim().split(/\r\n/);
        const head = lines[0].split(',');
        assert.ok(head.includes('e_final[2]') && head.includes('us_per_eval'), `CSV header ${lines[0]}`);
        assert.equal(lines.length, 4, 'a header and three rows');
        for (const line of lines.slice(1)) {
            const cells = line.match(/("([^"]|"")*"|[^,]*)(,|$)/g).map((c) => c.replace(/,$/, ''));
            const m = full[Number(cells[0])].metrics;
            assert.equal(Number(cells[head.indexOf('e_final[2]')]), m.e_final[2]);
            assert.equal(Number(cells[head.indexOf('e_rms[0]')]), m.e_rms[0]);
        }
        await screenshot(page, 'compare-table-1400.png');
        await page.setViewportSize({ width: 390, height: 844 });
        await screenshot(page, 'compare-table-390.png');
    });
});

test('legends name the controller and what differs, not job numbers', async () => {
    await atView(`#/compare?ids=${jobs.pid.id},${jobs.fast.id}`, 'compare-labels', async (page) => {
        const labels = await page.locator('#compare-legend a.run-label').allTextContents();
        assert.deepEqual(labels, ['pid, kp = 100', 'pid, kp = 400']);
        const series = await page.locator('div.plot[data-channel="e"] .u-legend .u-label').allTextContents();
        assert.ok(series.includes('pid, kp = 400 e[0]'), `e's legend: ${JSON.stringify(series)}`);
        assert.ok(series.every((s) => !/#[0-9]/.test(s)), `a job number in e's legend: ${JSON.stringify(series)}`);
    });
    await atView(`#/compare?ids=${jobs.pid.id},${jobs.pd.id},${jobs.five.id}`, 'compare-labels-scenes', async (page) => {
        const labels = await page.locator('#compare-legend a.run-label').allTextContents();
        assert.deepEqual(labels, ['pid, triple_pendulum_pid', 'pd, triple_pendulum_pd', 'pd, five_bar_pd']);
    });
});

test('|e| on a log axis, and the value axes zoom by button and by a vertical drag', async () => {
    await atView(`#/compare?ids=${jobs.pid.id},${jobs.pd.id}`, 'compare-log', async (page) => {
        assert.equal(await plotAttr(page, '[data-channel="e"]', 'data-log'), null);
        await page.locator('input#log-e').check();
        await pollValue(() => plotAttr(page, '[data-channel="e"]', 'data-log'), (v) => v === '1', 'the e plot on a log axis');
        assert.equal(await plotAttr(page, '[data-channel="e"]', 'data-unit'), '|e| [rad] (log)');
        const ticks = (await plotAttr(page, '[data-channel="e"]', 'data-y-ticks')).split('|').filter((t) => t);
        assert.ok(ticks.length >= 2 && ticks.every((t) => /^1e[+-][0-9]+$/.test(t)), `log ticks: ${ticks}`);
        assert.ok(Number(await plotAttr(page, '[data-channel="e"]', 'data-ymin')) > 0, 'a log axis starts above 0');

        /* "Zoom y in" halves each value span */
        const span = async () => Number(await plotAttr(page, '[data-channel="q"]', 'data-ymax')) - Number(await plotAttr(page, '[data-channel="q"]', 'data-ymin'));
        const before = await span();
        await page.locator('button.zoom-y').click();
        const after = await pollValue(span, (s) => Math.abs(s - before / 2) < 1e-9 * before, 'the q span halved');
        assert.ok(after < before);

        /* a vertical drag zooms q's value axis only */
        const xBefore = [await plotAttr(page, '[data-channel="q"]', 'data-xmin'), await plotAttr(page, '[data-channel="q"]', 'data-xmax')];
        const over = await page.locator('div.plot[data-channel="q"] .u-over').boundingBox();
        await page.mouse.move(over.x + over.width / 2, over.y + 10);
        await page.mouse.down();
        await page.mouse.move(over.x + over.width / 2 + 2, over.y + over.height / 2, { steps: 5 });
        await page.mouse.up();
        await pollValue(span, (s) => s < after * 0.75, 'the q span after a vertical drag');
        assert.deepEqual([await plotAttr(page, '[data-channel="q"]', 'data-xmin'), await plotAttr(page, '[data-channel="q"]', 'data-xmax')], xBefore, 'the time axis kept');
        await pollValue(() => hashOf(page), (h) => h.includes('log=1') && /[?&]y=[^&]*q:/.test(h), 'log and the q zoom in the address');
        await screenshot(page, 'compare-log-1400.png');
    });
});

test("the paper's layout: a panel per coordinate with the runs overlaid", async () => {
    await atView(`#/compare?ids=${jobs.pid.id},${jobs.pd.id}`, 'compare-paper', async (page) => {
        await page.locator('select#layout').selectOption('paper');
        await poll(() => page.evaluate(() => document.querySelectorAll('div.plot[data-channel="e"][data-joint]').length === 3), 'three e panels');
        const panels = await page.evaluate(() => [...document.querySelectorAll('div.plot[data-joint]')].map((d) => [d.dataset.channel, Number(d.dataset.joint), Number(d.dataset.series)]));
        for (const ch of ['q', 'e', 'tau']) {
            const mine = panels.filter((p) => p[0] === ch);
            assert.deepEqual(mine.map((p) => p[1]), [0, 1, 2], `${ch} panels`);
            for (const p of mine) assert.equal(p[2], ch === 'q' ? 4 : 2, `${ch}[${p[1]}]: each run's line${ch === 'q' ? ' and its q_d' : ''}`);
        }
        await pollValue(() => hashOf(page), (h) => h.includes('layout=paper'), 'the layout in the address');
        await screenshot(page, 'compare-paper-1400.png');
        await page.setViewportSize({ width: 390, height: 844 });
        await screenshot(page, 'compare-paper-390.png');
    });
});

test('the address keeps the cursor, the zoom, hidden joints, log, layout and the set; a reload restores them', async () => {
    let hash;
    let x;
    await atView(`#/compare?ids=${jobs.pid.id},${jobs.pd.id}`, 'compare-url', async (page) => {
        await setCursor(page, 0.75);
        await page.locator('.zoom button', { hasText: 'Zoom in' }).click();
        await page.locator('button.joint-toggle[data-joint="1"]').click();
        await page.locator('input#log-e').check();
        await page.locator('select#layout').selectOption('paper');
        /* the pointer off the plots (hovering one moves the cursor), then the cursor again */
        await page.mouse.move(1, 1);
        await setCursor(page, 0.75);
        hash = await pollValue(() => hashOf(page), (h) => ['t=0.75', 'x=', 'hide=1', 'log=1', 'layout=paper'].every((k) => h.includes(k)), 'the state in the address');
        x = [Number(await plotAttr(page, '[data-channel="e"][data-joint="0"]', 'data-xmin')), Number(await plotAttr(page, '[data-channel="e"][data-joint="0"]', 'data-xmax'))];
        assert.ok(x[1] - x[0] < 1.5, `zoomed: ${x}`);
    });
    await atView(hash, 'compare-url-reload', async (page) => {
        assert.equal(await text(page, 'output#time-value'), '0.750 s');
        assert.equal(await attr(page, 'button.joint-toggle[data-joint="1"]', 'aria-pressed'), 'false');
        assert.equal(await page.locator('input#log-e').isChecked(), true);
        assert.equal(await page.locator('select#layout').inputValue(), 'paper');
        const got = [Number(await plotAttr(page, '[data-channel="e"][data-joint="0"]', 'data-xmin')), Number(await plotAttr(page, '[data-channel="e"][data-joint="0"]', 'data-xmax'))];
        for (let i = 0; i < 2; i++) assert.ok(Math.abs(got[i] - x[i]) < 1e-6, `time zoom ${got}, want ${x}`);
        const hidden = await page.evaluate(() => [...document.querySelectorAll('div.plot[data-channel="e"][data-joint="1"] .u-legend tr.u-series')].slice(1).map((tr) => tr.classList.contains('u-off')));
        assert.ok(hidden.length === 2 && hidden.every(Boolean), `joint 1's lines hidden: ${hidden}`);
        assert.deepEqual(await page.locator('#compare-legend li[data-job-id]').evaluateAll((l) => l.map((li) => Number(li.dataset.jobId))), [jobs.pid.id, jobs.pd.id]);
    });
});

test('each plot saves as PNG and as SVG with the lines shown', async () => {
    await atView(`#/jobs/${jobs.pid.id}`, 'export', async (page) => {
        const png = await downloadOf(page, 'button.export-png[data-channel="q"]');
        assert.equal(png.name, 'ctcsim-q.png');
        assert.deepEqual([...png.bytes.subarray(0, 8)], [0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a], 'a PNG signature');
        const width = png.bytes.readUInt32BE(16);
        assert.ok(width >= 280, `PNG width ${width}`);

        const svg = (await downloadOf(page, 'button.export-svg[data-channel="e"]'));
        assert.equal(svg.name, 'ctcsim-e.svg');
        const doc = svg.bytes.toString('utf8');
        assert.match(doc, /^<svg xmlns="http:\/\/www.w3.org\/2000\/svg"/);
        const titles = [...doc.matchAll(/<path d="M[^"]+"[^>]*><title>([^<]*)<\/title>/g)].map((m) => m[1]);
        assert.deepEqual(titles, ['e[0]', 'e[1]', 'e[2]'], 'one path per line');
        assert.match(doc, />e \[rad\]</, 'the value axis label');
        /* a hidden coordinate is left out */
        await page.locator('button.joint-toggle[data-joint="2"]').click();
        const again = (await downloadOf(page, 'button.export-svg[data-channel="e"]')).bytes.toString('utf8');
        assert.deepEqual([...again.matchAll(/<title>([^<]*)<\/title>/g)].map((m) => m[1]), ['e[0]', 'e[1]']);
    });
});

test('several runs animated side by side under one cursor, played at 4x', async () => {
    await atView(`#/compare?ids=${jobs.pid.id},${jobs.spatial.id}`, 'compare-anim', async (page) => {
        const canvases = await page.evaluate(() => [...document.querySelectorAll('canvas.anim')].map((c) => [Number(c.dataset.jobId), c.dataset.mode]));
        assert.deepEqual(canvases, [[jobs.pid.id, 'planar'], [jobs.spatial.id, 'spatial']]);
        const t = await setCursor(page, 0.5);
        await poll(() => page.evaluate((v) => [...document.querySelectorAll('canvas.anim')].every((c) => Math.abs(Number(c.dataset.time) - v) < 1e-9), t), 'both drawn at the cursor');
        const speeds = await page.locator('select#speed option').evaluateAll((o) => o.map((x) => x.value));
        assert.deepEqual(speeds, ['4', '2', '1', '0.5', '0.25', '0.1']);
        assert.equal(await page.locator('select#speed').inputValue(), '1', '1x at first');
        await setCursor(page, 0);
        await page.locator('select#speed').selectOption('4');
        await page.locator('button#play').click();
        /* the simulated time per real second while playing, over 0.4 s (1.6 s of the 2 s run):
         * each reading lags its frame by up to a frame, and a frame may take 0.1 s on a loaded
         * machine, so the bounds only tell 4x from 1x */
        const rate = await page.evaluate(
            () =>
                new Promise((resolve) => {
                    const c = document.querySelector('canvas.anim');
                    const t0 = performance.now();
                    const s0 = Number(c.dataset.time);
                    setTimeout(() => resolve((Number(c.dataset.time) - s0) / ((performance.now() - t0) / 1000)), 400);
                }),
        );
        await page.locator('button#play').click();
        assert.ok(rate > 1.5 && rate < 6, `played at ${rate} s per s at 4x`);
        await screenshot(page, 'compare-anim-1400.png');
        await page.setViewportSize({ width: 390, height: 844 });
        await screenshot(page, 'compare-anim-390.png');
    });
});

test('the 3-D view zooms, pans and resets', async () => {
    await atView(`#/jobs/${jobs.spatial.id}`, 'anim-view', async (page) => {
        assert.equal(await attr(page, 'canvas#anim', 'data-mode'), 'spatial');
        const first = await animImage(page);
        const box = await page.locator('canvas#anim').boundingBox();
        await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
        await page.mouse.wheel(0, -400);
        const zoom = Number(await pollValue(() => attr(page, 'canvas#anim', 'data-zoom'), (z) => Number(z) > 1.2, 'zoomed in by the wheel'));
        assert.notEqual((await animImage(page)).image, first.image, 'the drawing changed');
        await page.keyboard.down('Shift');
        await page.mouse.down();
        await page.mouse.move(box.x + box.width / 2 + 40, box.y + box.height / 2 + 25, { steps: 4 });
        await page.mouse.up();
        await page.keyboard.up('Shift');
        assert.equal(await attr(page, 'canvas#anim', 'data-pan'), '40,25', 'panned by a shift-drag');
        assert.equal(Number(await attr(page, 'canvas#anim', 'data-zoom')), zoom, 'a pan keeps the zoom');
        await page.locator('canvas#anim').focus();
        await page.keyboard.press('+');
        assert.ok(Number(await attr(page, 'canvas#anim', 'data-zoom')) > zoom, '+ zooms in');
        await screenshot(page, 'anim-zoom-1400.png');
        await page.locator('button.anim-reset').click();
        assert.equal(await attr(page, 'canvas#anim', 'data-zoom'), '1');
        assert.equal(await attr(page, 'canvas#anim', 'data-pan'), '0,0');
        assert.equal((await animImage(page)).image, first.image, 'reset: the first view again');
    });
});

test("a closed chain's desired pose is drawn as a ghost", async () => {
    await atView(`#/jobs/${jobs.five.id}`, 'anim-loop-ghost', async (page) => {
        await setCursor(page, 0.3);
        await pollValue(() => attr(page, 'canvas#anim', 'data-time'), (t) => Math.abs(Number(t) - 0.3) < 1e-9, 'drawn at 0.3 s');
        assert.equal(await attr(page, 'canvas#anim', 'data-ghost'), '1', 'the ghost drawn');
        assert.match(await text(page, '.anim-wrap + p'), /desired/);
        await screenshot(page, 'anim-loop-ghost-1400.png');
        await page.setViewportSize({ width: 390, height: 844 });
        await screenshot(page, 'anim-loop-ghost-390.png');
    });
});
