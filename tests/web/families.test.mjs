/*
 * families.test.mjs - studies on the page (#/families, #/families/{id}): families posted through
 * the API, then their list (counts, progress), a family's table checked against the API's
 * (GET /api/families/{id}: rows, job links, the CSV byte for byte), its sort and the address
 * that keeps it, the chart (one point per member, one line per value of the second axis, the
 * Monte-Carlo replicas as points, log axes, SVG export), "compare selected", cancel and delete
 * through the confirm dialog, and the 390 px layout. Screenshots at 1400x900 and 390x844
 * (artifacts/families-*.png, family-*.png).
 */
import assert from 'node:assert/strict';
import { readFileSync } from 'node:fs';
import { after, before, test } from 'node:test';

import {
    attr,
    launchBrowser,
    near,
    newPage,
    overflowing,
    poll,
    pollValue,
    screenshot,
    startWebServer,
    text,
    waitFor,
    waitView,
    withView,
} from './lib.mjs';

const DESKTOP = { width: 1400, height: 900 };
const PHONE = { width: 390, height: 844 };

let srv;
let browser;
let sweep; /* {id, family}: kp x kv, 3 x 2 members */
let mc; /* {id, family}: 2 mass errors x 3 replicas */

/* POSTs a family and waits until every member has finished; resolves GET /api/families/{id} */
async function runFamily(doc) {
    const res = await srv.post('/api/families', doc);
    assert.equal(res.status, 202, `POST /api/families: ${res.text}`);
    let fam;
    await waitFor(
        async () => {
            fam = (await srv.get(`/api/families/${res.json.id}`)).json;
            return !fam.counts.queued && !fam.counts.running;
        },
        { timeoutMs: 60000, intervalMs: 200, what: () => `family ${res.json.id} to finish: ${JSON.stringify(fam?.counts)}` },
    );
    return fam;
}

before(async () => {
    srv = await startWebServer();
    browser = await launchBrowser();
    sweep = await runFamily({
        name: 'kp and kv',
        base: { preset: 'triple_pendulum_pd', duration: 0.5 },
        axes: [
            { path: 'controller.kp', values: [50, 100, 400] },
            { path: 'controller.kv', values: [10, 40] },
        ],
    });
    mc = await runFamily({
        name: 'mass error',
        base: { preset: 'triple_pendulum_pd', duration: 0.5, controller: { model: { random: { seed: 0, mass: 0.1 } } } },
        axes: [{ path: 'controller.model.random.mass', values: [0.05, 0.3] }],
        replicas: 3,
        seed: 7,
    });
});

after(async () => {
    await browser?.close();
    await srv?.stop();
});

/* the family table's rows as the page shows them: [{job, member, href, cells: {key: data-value}}] */
function tableRows(page) {
    return page.evaluate(() =>
        [...document.querySelectorAll('table#family-table tbody tr')].map((tr) => ({
            job: Number(tr.getAttribute('data-job-id')),
            member: Number(tr.getAttribute('data-member')),
            href: tr.querySelector('th[data-key="member"] a')?.getAttribute('href') ?? null,
            cells: Object.fromEntries([...tr.querySelectorAll('td[data-key]')].map((td) => [td.getAttribute('data-key'), td.getAttribute('data-value') ?? td.textContent])),
        })),
    );
}

function chart(page) {
    return page.evaluate(() => {
        const d = document.querySelector('#family-chart');
        const c = d?.querySelector('.uplot canvas');
        return {
            x: d?.dataset.x, y: d?.dataset.y, by: d?.dataset.by, points: Number(d?.dataset.points), lines: Number(d?.dataset.lines),
            logX: d?.dataset.logX, logY: d?.dataset.logY, uplot: !!c && c.width > 0, legend: [...(d?.querySelectorAll('.u-legend .u-series') || [])].filter((r) => getComputedStyle(r).display !== 'none').map((r) => r.querySelector('.u-label')?.textContent).filter((l) => l),
        };
    });
}

test('the studies list: each family with its counts and progress, linked from the nav', async () => {
    await withView(browser, srv, '#/jobs', 'families-nav', async (page) => {
        await page.click('nav a[href="#/families"]');
        await waitView(page, '#/families');
        for (const f of [sweep, mc]) {
            const row = `table#families-table tr[data-family-id="${f.id}"]`;
            assert.equal(await text(page, `${row} td[data-col="members"]`), '6');
            assert.equal(await attr(page, `${row} [data-status="done"]`, 'data-count'), '6', 'every member done');
            assert.equal(await attr(page, `${row} progress`, 'value'), '6');
            assert.equal(await attr(page, `${row} a`, 'href'), `#/families/${f.id}`);
        }
        await page.setViewportSize(DESKTOP);
        await screenshot(page, 'families-1400.png');
        await page.setViewportSize(PHONE);
        assert.deepEqual(await overflowing(page), [], 'the studies list at 390 px');
        await screenshot(page, 'families-390.png');
    });
});

test('a family page: its table is the API table, each row links to its member job, the CSV is the API CSV', async () => {
    await withView(browser, srv, `#/families/${sweep.id}`, 'family-table', async (page) => {
        const rows = await tableRows(page);
        assert.equal(rows.length, 6, 'one row per member');
        const api = sweep.table.rows;
        for (const r of api) {
            const shown = rows.find((x) => x.member === r.member);
            assert.ok(shown, `member ${r.member} shown`);
            assert.equal(shown.job, r.job);
            assert.equal(shown.href, `#/jobs/${r.job}`);
            assert.equal(Number(shown.cells['axis.0']), r.values[0], 'the kp column');
            assert.equal(Number(shown.cells['axis.1']), r.values[1], 'the kv column');
            assert.equal(Number(shown.cells.e_rms), r.e_rms, 'e_rms as the API gives it');
        }
        assert.equal(await attr(page, '#family-counts [data-status="done"]', 'data-count'), '6');
        assert.equal(await attr(page, 'progress#family-progress', 'value'), '6');
        assert.equal(await page.locator('#cancel-family').isHidden(), true, 'nothing to cancel');
        assert.equal(await page.locator('#delete-family').isVisible(), true);

        /* the CSV: the link's file is the API's CSV */
        const [download] = await Promise.all([page.waitForEvent('download'), page.click('a#family-csv')]);
        const csv = readFileSync(await download.path(), 'utf8');
        const want = (await srv.get(`/api/families/${sweep.id}?format=csv`)).text;
        assert.equal(csv, want, 'the downloaded CSV');
        assert.equal(csv.trim().split('\n').length, 7, 'a header and 6 rows');
        assert.match(csv.split('\n')[0], /^member,replica,controller\.kp,controller\.kv,status,e_final,e_rms/);

        /* a member's link opens its job */
        const first = rows[0];
        await page.click(`table#family-table tr[data-member="${first.member}"] th a`);
        await waitView(page, `#/jobs/${first.job}`);
    });
});

test('the table sorts by a column, the address keeps the sort, and a reload restores it', async () => {
    await withView(browser, srv, `#/families/${sweep.id}`, 'family-sort', async (page) => {
        const byErms = (rs) => rs.map((r) => Number(r.cells.e_rms));
        await page.click('table#family-table button.sort[data-key="e_rms"]');
        let vals = byErms(await tableRows(page));
        assert.deepEqual(vals, [...vals].sort((a, b) => a - b), 'ascending');
        assert.equal(await attr(page, 'th:has(button.sort[data-key="e_rms"])', 'aria-sort'), 'ascending');
        await page.click('table#family-table button.sort[data-key="e_rms"]');
        vals = byErms(await tableRows(page));
        assert.deepEqual(vals, [...vals].sort((a, b) => b - a), 'descending');
        assert.ok(vals[0] > vals[vals.length - 1], 'the members differ in e_rms');
        await poll(() => page.evaluate(() => decodeURIComponent(location.hash).includes('sort=e_rms:desc')), 'sort in the address');
        await page.reload();
        await waitView(page, null, { selector: 'table#family-table' });
        assert.deepEqual(byErms(await tableRows(page)), vals, 'the sort after a reload');
        assert.equal(await attr(page, 'th:has(button.sort[data-key="e_rms"])', 'aria-sort'), 'descending');
    });
});

test('the chart: a point per member, a line per kv, any metric against any axis, log axes, SVG export', async () => {
    await withView(browser, srv, `#/families/${sweep.id}`, 'family-chart', async (page) => {
        let c = await chart(page);
        assert.equal(c.uplot, true, 'a uPlot is drawn');
        assert.equal(c.x, 'controller.kp');
        assert.equal(c.by, 'controller.kv');
        assert.equal(c.y, 'e_rms');
        assert.equal(c.points, 6, 'one point per member');
        assert.equal(c.lines, 2, 'one line per value of kv');
        assert.deepEqual(c.legend.filter((l) => l.startsWith('controller.kv')), ['controller.kv = 10', 'controller.kv = 40']);

        /* pooled: kv no longer splits the lines; the two members at each kp are points */
        await page.selectOption('select#family-by', '-1');
        c = await pollValue(() => chart(page), (v) => v.by === '', 'pooled');
        assert.equal(c.lines, 1);
        assert.equal(c.points, 6);
        await page.selectOption('select#family-by', { label: 'controller.kv' });
        await page.selectOption('select#family-x', { label: 'controller.kv' });
        c = await pollValue(() => chart(page), (v) => v.x === 'controller.kv', 'x is kv');
        assert.equal(c.by, 'controller.kp', 'the other axis makes the lines');
        assert.equal(c.lines, 3);
        await page.selectOption('select#family-y', 'us_per_eval');
        await page.check('input#family-logx');
        await page.check('input#family-logy');
        c = await pollValue(() => chart(page), (v) => v.y === 'us_per_eval' && v.logX === '1' && v.logY === '1', 'log axes');
        assert.equal(c.points, 6);
        await poll(() => page.evaluate(() => /x=controller\.kv&y=us_per_eval&by=controller\.kp&logx=1&logy=1/.test(decodeURIComponent(location.hash))), 'the chart in the address');
        await page.reload();
        await waitView(page, null, { selector: 'table#family-table' });
        c = await chart(page);
        assert.deepEqual([c.x, c.y, c.by, c.logX, c.logY], ['controller.kv', 'us_per_eval', 'controller.kp', '1', '1'], 'the chart after a reload');

        const [svg] = await Promise.all([page.waitForEvent('download'), page.click('figure:has(#family-chart) button.export-svg')]);
        assert.equal(svg.suggestedFilename(), 'ctcsim-family.svg');
        const doc = readFileSync(await svg.path(), 'utf8');
        assert.equal((doc.match(/<path /g) || []).length, 3, 'a path per line');
        assert.match(doc, />controller\.kv<\/text>/, 'the x axis label');
        const [png] = await Promise.all([page.waitForEvent('download'), page.click('figure:has(#family-chart) button.export-png')]);
        assert.equal(png.suggestedFilename(), 'ctcsim-family.png');
        assert.deepEqual([...readFileSync(await png.path()).subarray(1, 4)].map((b) => String.fromCharCode(b)).join(''), 'PNG');
    });
});

test('Monte-Carlo: each replica a point, their mean and spread a line per mass error', async () => {
    await withView(browser, srv, `#/families/${mc.id}`, 'family-mc', async (page) => {
        const c = await chart(page);
        assert.equal(c.x, 'controller.model.random.mass');
        assert.equal(c.points, 6, 'every replica drawn');
        assert.equal(c.lines, 1, 'one axis: one line');
        assert.deepEqual(c.legend, ['RMS e (mean)', 'RMS e, each replica', 'RMS e − 1 sd', 'RMS e + 1 sd'], 'one key entry for the replicas');
        assert.match(await text(page, '#family-chart-note'), /mean ± 1 standard deviation/);
        /* the replicas differ (seeded mass errors), so the spread is not zero */
        const erms = mc.table.rows.filter((r) => r.values[0] === 0.3).map((r) => r.e_rms);
        assert.equal(new Set(erms).size, 3, `three different replicas: ${erms}`);
        const [svg] = await Promise.all([page.waitForEvent('download'), page.click('figure:has(#family-chart) button.export-svg')]);
        const doc = readFileSync(await svg.path(), 'utf8');
        assert.equal((doc.match(/<circle /g) || []).length, 6, 'a dot per replica in the SVG');
        await page.setViewportSize(DESKTOP);
        await screenshot(page, 'family-mc-1400.png');
    });
});

test('chartData: the mean and sample sd per x and group, categories for a string axis', async () => {
    await withView(browser, srv, '#/families', 'family-chartdata', async (page) => {
        const d = await page.evaluate(async () => {
            const { chartData } = await import('/families.js');
            /* rows as GET /api/families/{id} gives them: values [method, rtol]; y = e_rms */
            const rows = [
                ['bdf', 1e-6, 2], ['bdf', 1e-6, 4], ['bdf', 1e-6, 9], ['bdf', 1e-8, 1],
                ['dopri5', 1e-6, 5], ['dopri5', 1e-8, null], ['dopri5', 1e-8, 3],
            ].map(([m, r, y], i) => ({ member: i, values: [m, r], e_rms: y }));
            return { byMethod: chartData(rows, 1, 'e_rms', 0), overMethod: chartData(rows, 0, 'e_rms', -1) };
        });
        const m = d.byMethod;
        assert.deepEqual(m.xs, [1e-8, 1e-6]);
        assert.equal(m.cats, null);
        assert.deepEqual(m.groups.map((g) => g.value), ['bdf', 'dopri5']);
        /* bdf at 1e-6: 2, 4, 9: mean 5, sample variance ((-3)^2 + (-1)^2 + 4^2) / 2 = 13 */
        assert.deepEqual(m.groups[0].mean, [1, 5]);
        near(m.groups[0].sd[1], Math.sqrt(13), 1e-12, 'sd of 2, 4, 9');
        assert.equal(m.groups[0].sd[0], 0, 'one value: no spread');
        /* dopri5 at 1e-8: the null e_rms is left out */
        assert.deepEqual(m.groups[1].mean, [3, 5]);
        assert.equal(m.groups[1].points.length, 2);
        const c = d.overMethod;
        assert.deepEqual(c.cats, ['bdf', 'dopri5'], 'a string axis as categories, in the order met');
        assert.deepEqual(c.xs, [0, 1]);
        assert.deepEqual(c.groups[0].mean, [4, 4], 'bdf (2+4+9+1)/4, dopri5 (5+3)/2');
    });
});

test('compare selected members opens the compare view with them', async () => {
    await withView(browser, srv, `#/families/${sweep.id}`, 'family-compare', async (page) => {
        const jobs = sweep.table.rows.slice(0, 2).map((r) => r.job);
        assert.equal(await page.locator('#family-compare').isDisabled(), true, 'nothing ticked');
        for (const j of jobs) await page.check(`input.compare-pick[data-job-id="${j}"]`);
        await page.click('#family-compare');
        await waitView(page, `#/compare?ids=${jobs.join(',')}`);
        const legend = await page.evaluate(() => [...document.querySelectorAll('#compare-legend li[data-job-id]')].map((li) => Number(li.dataset.jobId)));
        assert.deepEqual(legend, jobs);
    });
});

test('the page at 390 px: no element wider than the viewport; screenshots', async () => {
    const page = await newPage(browser);
    try {
        await page.setViewportSize(PHONE);
        await page.goto(`${srv.base}/#/families/${sweep.id}`);
        await waitView(page, null, { selector: 'table#family-table' });
        assert.deepEqual(await overflowing(page), [], 'the family page at 390 px');
        await screenshot(page, 'family-390.png');
        await page.setViewportSize(DESKTOP);
        await page.reload();
        await waitView(page, null, { selector: 'table#family-table' });
        await screenshot(page, 'family-1400.png');
        assert.deepEqual(page.errors, []);
    } finally {
        await page.context().close();
    }
});

test('a running family: live counts, cancel through the dialog, then delete', async () => {
    const res = await srv.post('/api/families', {
        name: 'long runs',
        /* runs for minutes: only ever cancelled */
        base: { preset: 'n_link_pendulum', n: 32, duration: 100, integrator: { method: 'rk4', step: 0.0001 }, output: { interval: 0.5 } },
        axes: [{ path: 'controller.kp', values: [100, 200, 300, 400, 500, 600] }],
    });
    assert.equal(res.status, 202, res.text);
    const id = res.json.id;
    try {
        await withView(browser, srv, `#/families/${id}`, 'family-cancel', async (page) => {
            assert.equal(await page.locator('#delete-family').isHidden(), true, 'no delete while members run');
            await pollValue(() => attr(page, '#family-counts [data-status="running"]', 'data-count'), (v) => Number(v) >= 1, 'a member running');
            assert.equal(await attr(page, 'progress#family-progress', 'max'), '6');
            await page.click('#cancel-family');
            assert.match(await text(page, '#confirm-text'), /long runs/);
            await page.keyboard.press('Escape');
            await page.waitForSelector('dialog#confirm-dialog', { state: 'detached' });
            assert.equal((await srv.get(`/api/families/${id}`)).json.counts.cancelled ?? 0, 0, 'Escape cancels nothing');
            await page.click('#cancel-family');
            await page.click('#confirm-yes');
            await pollValue(() => attr(page, '#family-counts [data-status="cancelled"]', 'data-count'), (v) => Number(v) === 6, 'every member cancelled', 30000);
            await page.waitForSelector('#delete-family:visible');
            await page.click('#delete-family');
            assert.match(await text(page, '#confirm-text'), /6 of 6 members finished/);
            await page.click('#confirm-yes');
            await waitView(page, '#/families');
            assert.equal(await page.locator(`tr[data-family-id="${id}"]`).count(), 0, 'gone from the list');
            assert.equal((await srv.get(`/api/families/${id}`)).status, 404);
        });
    } finally {
        const left = await srv.get(`/api/families/${id}`);
        if (left.status === 200 && (left.json.counts.queued || left.json.counts.running)) await srv.del(`/api/families/${id}`);
    }
});
