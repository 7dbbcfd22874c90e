/*
 * compare.test.mjs - several jobs overlaid (#/compare?ids=A,B): one legend entry per job in its
 * own colour, plots counting every job's lines (twice a single job's for two like jobs, the sum
 * for unlike ones; the jobs track different trajectories, so each job's q_d is a line of its
 * own), the shared time cursor, and the keyboard.
 */
import assert from 'node:assert/strict';
import { after, before, test } from 'node:test';

import {
    launchBrowser,
    plots,
    poll,
    runJob,
    screenshot,
    setCursor,
    startWebServer,
    tabThrough,
    text,
    waitView,
    withView,
} from './lib.mjs';

let srv;
let browser;
let pid; /* triple pendulum PID, 2 s */
let lqr; /* triple pendulum LQR, 1 s, slower and smaller sines than pid's (its own q_d) */
let spatial; /* spatial double pendulum PD, 1 s */

before(async () => {
    srv = await startWebServer();
    browser = await launchBrowser();
    pid = await runJob(srv, { preset: 'triple_pendulum_pid', duration: 2 });
    /* every job here tracks its own desired trajectory, so that a page which draws a q_d shared
     * by several jobs only once still draws each job's */
    const sine = (type) => ({ type, amplitude: 0.4, period: 2 });
    lqr = await runJob(srv, { preset: 'triple_pendulum_lqr', duration: 1, trajectory: [sine('sine'), sine('cosine'), sine('sine')] });
    spatial = await runJob(srv, { preset: 'spatial_double_pendulum_pd', duration: 1 });
});

after(async () => {
    await browser?.close();
    await srv?.stop();
});

/* the legend: [{id, colours (every colour used in the entry, as a sorted list)}] */
function legend(page) {
    return page.evaluate(() =>
        [...document.querySelectorAll('#compare-legend li[data-job-id]')].map((li) => {
            const colours = new Set();
            for (const el of [li, ...li.querySelectorAll('*')]) {
                const cs = getComputedStyle(el);
                for (const c of [cs.color, cs.backgroundColor, cs.borderLeftColor, cs.borderTopColor, cs.fill, cs.stroke]) {
                    if (c && c !== 'none' && !/rgba\(0, 0, 0, 0\)|transparent/.test(c)) colours.add(c);
                }
            }
            return { id: Number(li.getAttribute('data-job-id')), colours: [...colours].sort() };
        }),
    );
}

/* data-series of each plot of the single job view of id */
async function singleSeries(id) {
    let out;
    await withView(browser, srv, `#/jobs/${id}`, `compare-single-${id}`, async (page) => {
        out = Object.fromEntries((await plots(page)).map((p) => [p.channel, p.series]));
    });
    return out;
}

test('two jobs overlaid: two legend entries in their own colours, twice the lines of one job', async () => {
    const one = await singleSeries(pid.id);
    assert.equal(one.q, 6, 'a triple pendulum job view draws q with 6 lines');
    await withView(browser, srv, `#/compare?ids=${pid.id},${lqr.id}`, 'compare', async (page) => {
        const entries = await legend(page);
        assert.deepEqual(
            entries.map((e) => e.id),
            [pid.id, lqr.id],
            '#compare-legend li[data-job-id], in the order of the address',
        );
        assert.notDeepEqual(entries[0].colours, entries[1].colours, `the two legend entries share their colours: ${JSON.stringify(entries)}`);
        const by = Object.fromEntries((await plots(page)).map((p) => [p.channel, p]));
        assert.equal(by.q?.series, 2 * one.q, 'q data-series of two like jobs');
        assert.equal(by.e?.series, 2 * one.e, 'e data-series of two like jobs');
        for (const ch of ['q', 'e']) {
            assert.ok(by[ch].uplot, `div.plot[data-channel="${ch}"] holds no drawn uPlot`);
            assert.ok(by[ch].points > 100, `${ch} data-points ${by[ch].points}`);
        }
        const legendText = await text(page, '#compare-legend');
        for (const j of [pid, lqr]) {
            assert.ok(legendText.includes(String(j.id)) || legendText.includes(j.name), `the legend names neither job ${j.id} nor "${j.name}"`);
        }
        await screenshot(page, 'compare.png');
    });
});

test('unlike jobs overlaid: the lines add up (3 + 3 + 2 coordinates)', async () => {
    await withView(browser, srv, `#/compare?ids=${pid.id},${lqr.id},${spatial.id}`, 'compare-three', async (page) => {
        assert.equal((await legend(page)).length, 3);
        const by = Object.fromEntries((await plots(page)).map((p) => [p.channel, p]));
        assert.equal(by.q?.series, 2 * (3 + 3 + 2), 'q data-series');
        assert.equal(by.e?.series, 3 + 3 + 2, 'e data-series');
        const colours = (await legend(page)).map((e) => e.colours.join());
        assert.equal(new Set(colours).size, 3, `legend colours ${JSON.stringify(colours)}`);
        await screenshot(page, 'compare-three.png');
    });
});

test('the time cursor of the compare view moves and shows its time', async () => {
    await withView(browser, srv, `#/compare?ids=${pid.id},${lqr.id}`, 'compare-cursor', async (page) => {
        const max = await page.evaluate(() => Number(document.querySelector('input#time-cursor')?.max));
        assert.ok(max >= 1, `input#time-cursor max ${max}`);
        const t = await setCursor(page, 0.75);
        await poll(async () => {
            const shown = Number((await text(page, 'output#time-value'))?.match(/-?[0-9.]+/)?.[0]);
            return Math.abs(shown - t) <= 0.01 + 1e-9;
        }, `output#time-value showing ${t}`);
    });
});

test('keyboard: Tab reaches the nav links and the time cursor of the compare view', async () => {
    await withView(browser, srv, `#/compare?ids=${pid.id},${lqr.id}`, 'compare-keyboard', async (page) => {
        const r = await tabThrough(page, ['nav a[href="#/jobs"]', 'nav a[href="#/submit"]', 'nav a[href="#/compare"]', 'input#time-cursor']);
        assert.deepEqual(r.missed, [], `never focused by Tab; the order was ${r.order.join(' > ')}`);
    });
});

test('the Compare nav link opens the compare view without ids (screenshot compare-empty.png)', async () => {
    await withView(browser, srv, '#/jobs', 'compare-nav', async (page) => {
        await page.locator('nav a[href="#/compare"]').click();
        await waitView(page, '#/compare', { selector: '#view h1' });
        assert.equal(await page.locator('#compare-legend li[data-job-id]').count(), 0, 'legend entries with no ids');
        await screenshot(page, 'compare-empty.png');
    });
});
