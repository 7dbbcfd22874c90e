/*
 * pagejob.test.mjs - the job page for large chains, phones, running and failed jobs (issue 23,
 * part A): a 64-link chain's page stays short (a per-coordinate summary of the worst ten with
 * the whole table behind a button in a box that scrolls, not a line per value), plots the
 * coordinates the joint picker names (and says why it refuses a bad list), draws a coordinate x
 * time heat-map whose rows are the chain's coordinates, and fetches every series in the compact
 * f32 form; at 390 x 844 no element of any view reaches past the viewport's right edge and the
 * plots come before the JSON; a queued job shows its place in the queue and a running one its
 * simulated time and partial plots that grow from the samples recorded since the last fetch,
 * polling the brief row; a diverged job says how far it got and why, and its
 * re-run posts an edited copy; an RK4 step cut to the output interval is shown; Cancel and
 * Delete are separate, each confirmed in a dialog naming the job and its status, and a cancel
 * confirmed after the job finished keeps the job. Screenshots of each view at 1400 x 900 and
 * 390 x 844 go to artifacts/.
 */
import assert from 'node:assert/strict';
import { after, before, test } from 'node:test';

import {
    apiJob,
    attr,
    launchBrowser,
    newPage,
    overflowing,
    plots,
    poll,
    pollValue,
    runJob,
    screenshot,
    startWebServer,
    stopJob,
    submit,
    text,
    waitJob,
    waitView,
    withView,
} from './lib.mjs';

const DESKTOP = { width: 1400, height: 900 };
const PHONE = { width: 390, height: 844 };
/* runs for minutes: only ever cancelled */
const LONG = { preset: 'n_link_pendulum', n: 32, duration: 100, integrator: { method: 'rk4', step: 0.0001 }, output: { interval: 0.5 } };
/* diverges at t = 0.04 s: a stiff PD on RK4 with a 0.02 s step */
const DIVERGING = {
    preset: 'triple_pendulum_pid',
    controller: { type: 'pd', kp: 1e5, kv: 200 },
    integrator: { method: 'rk4', step: 0.02 },
    output: { interval: 0.02 },
};

let srv, browser, planar, chain, diverged, cut;

before(async () => {
    srv = await startWebServer();
    browser = await launchBrowser();
    planar = await runJob(srv, { preset: 'triple_pendulum_pid', duration: 2 });
    chain = await runJob(srv, { preset: 'n_link_pendulum', n: 64, duration: 1, output: { interval: 0.01 } });
    const res = await srv.post('/api/jobs?wait=60', DIVERGING);
    assert.equal(res.json.status, 'diverged', res.text);
    diverged = res.json;
    cut = await runJob(srv, { preset: 'triple_pendulum_pid', duration: 1, integrator: { method: 'rk4', step: 0.05 }, output: { interval: 0.01 } });
});

after(async () => {
    await browser?.close();
    await srv?.stop();
});

/* a page at a viewport size, on the view at hash */
async function openAt(viewport, hash, opts = {}) {
    const page = await newPage(browser);
    await page.setViewportSize(viewport);
    await page.goto(`${srv.base}/${hash}`);
    await waitView(page, hash, opts);
    return page;
}


test('a 64-link chain: summary of the worst 10, the whole table in a scrolling box, a short page, f32 series', async () => {
    const page = await openAt(DESKTOP, `#/jobs/${chain.id}`);
    try {
        const rows = await page.evaluate(() => document.querySelectorAll('table#joint-summary tbody tr').length);
        assert.equal(rows, 10, 'the worst 10 coordinates');
        /* worst first: RMS e falls down the table and is the job's largest at the top */
        const rms = chain.metrics.e_rms.map(Math.abs);
        const first = Number(await attr(page, 'table#joint-summary tbody tr', 'data-coord'));
        assert.equal(rms[first], Math.max(...rms), `row 1 is coordinate ${first}`);
        assert.match(await text(page, '#joint-summary-title'), /Worst 10 of 64/);
        /* the metrics list has no per-joint lines */
        const dl = await text(page, 'dl#metrics');
        assert.ok(dl.length < 2000, `dl#metrics is ${dl.length} characters`);
        const height0 = await page.evaluate(() => document.documentElement.scrollHeight);
        await page.locator('button#joint-summary-all').click();
        await poll(() => page.evaluate(() => document.querySelectorAll('table#joint-summary-full tbody tr').length === 64), 'all 64 rows');
        assert.equal(await attr(page, 'button#joint-summary-all', 'aria-expanded'), 'true');
        const box = await page.evaluate(() => {
            const b = document.querySelector('#joint-summary-all-box');
            return { client: b.clientHeight, scroll: b.scrollHeight, overflow: getComputedStyle(b).overflowY };
        });
        assert.ok(box.scroll > box.client && box.overflow === 'auto', `the table scrolls in its box: ${JSON.stringify(box)}`);
        const height1 = await page.evaluate(() => document.documentElement.scrollHeight);
        assert.ok(height1 - height0 < 600, `opening the table grew the page by ${height1 - height0} px`);
        assert.ok(height1 < 5000, `the page is ${height1} px tall`);
        /* every series came as f32 */
        const fetched = await Promise.all(page.series);
        assert.ok(fetched.length >= 2, JSON.stringify(fetched));
        for (const s of fetched) assert.ok(s.reduce !== null, `not f32: ${s.url}`);
        assert.ok(fetched.some((s) => /channels=e(&|$)/.test(s.url) && s.reduce === 'minmax'), 'the heat-map asks for e as minmax');
        await screenshot(page, 'job-large-desktop.png');
        assert.deepEqual(page.errors, []);
    } finally {
        await page.context().close();
    }
});

test('a 64-link chain: the joint picker plots what it names and refuses a bad list with a reason', async () => {
    await withView(browser, srv, `#/jobs/${chain.id}`, 'job-picker', async (page) => {
        const q0 = (await plots(page)).find((p) => p.channel === 'q');
        assert.equal(q0.series, 16, 'the 8 worst coordinates at first, actual and desired');
        await page.fill('input#joint-list', '3-5, 60');
        await page.locator('button#joint-plot').click();
        await pollValue(async () => (await plots(page)).find((p) => p.channel === 'q')?.series, (n) => n === 8, 'q lines for 4 coordinates');
        const toggles = await page.evaluate(() => [...document.querySelectorAll('button.joint-toggle')].map((b) => b.dataset.joint));
        assert.deepEqual(toggles, ['3', '4', '5', '60']);
        assert.match(await text(page, '#plotted-note'), /4 of 64 coordinates: 3-5, 60/);
        for (const [bad, why] of [
            ['64', /64 is past the last coordinate, 63/],
            ['7-2', /runs backwards/],
            ['x', /"x" is not an index/],
            ['0-30', /at most 24/],
        ]) {
            await page.fill('input#joint-list', bad);
            await page.locator('button#joint-plot').click();
            await pollValue(() => text(page, '#joint-list-error'), (t) => why.test(t || ''), `error for "${bad}"`);
            assert.equal(await attr(page, 'input#joint-list', 'aria-invalid'), 'true');
        }
        /* a coordinate's button in the summary adds it to the plots */
        const pick = await attr(page, 'table#joint-summary tbody tr button.plot-joint', 'data-coord');
        await page.locator('table#joint-summary tbody tr button.plot-joint').first().click();
        await pollValue(
            () => page.evaluate(() => [...document.querySelectorAll('button.joint-toggle')].map((b) => b.dataset.joint)),
            (j) => j.includes(pick),
            `coordinate ${pick} plotted after its summary button`,
        );
    });
});

test('a 64-link chain: the heat-map has a row per coordinate, is drawn, names the cell under the pointer', async () => {
    await withView(browser, srv, `#/jobs/${chain.id}`, 'job-heatmap', async (page) => {
        assert.equal(await attr(page, 'canvas#heatmap', 'data-rows'), '64');
        const cols = Number(await attr(page, 'canvas#heatmap', 'data-cols'));
        assert.ok(cols >= 2 && cols <= chain.metrics.samples, `${cols} time buckets`);
        const max = Number(await attr(page, 'canvas#heatmap', 'data-max'));
        const worst = Math.max(...chain.metrics.e_max.map(Math.abs));
        assert.ok(Math.abs(max - worst) <= 1e-6 * worst + 1e-6, `data-max ${max}, metrics max |e| ${worst}`);
        const colours = await page.evaluate(() => {
            const c = document.querySelector('canvas#heatmap');
            const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
            const seen = new Set();
            for (let k = 0; k < d.length; k += 4 * 97) seen.add(`${d[k]},${d[k + 1]},${d[k + 2]}`);
            return seen.size;
        });
        assert.ok(colours > 5, `${colours} colours drawn`);
        await page.locator('canvas#heatmap').scrollIntoViewIfNeeded();
        const box = await page.locator('canvas#heatmap').boundingBox();
        await page.mouse.move(box.x + 2, box.y + 1);
        await pollValue(() => text(page, '#heatmap-value'), (t) => /^joint 0, t 0/.test(t || ''), 'read-out of the top left cell');
        await page.locator('section.heat').screenshot({ path: 'tests/web/artifacts/heatmap.png' });
    });
});

test('phones (390 x 844): no element wider than the viewport on any view; plots before the JSON; list status in view', async () => {
    const views = [
        ['#/jobs', {}],
        [`#/jobs/${planar.id}`, {}],
        [`#/jobs/${chain.id}`, {}],
        [`#/jobs/${diverged.id}`, {}],
        ['#/submit?preset=triple_pendulum_pid', { selector: 'select#preset' }],
        [`#/compare?ids=${planar.id},${cut.id}`, {}],
    ];
    for (const [hash, opts] of views) {
        const page = await openAt(PHONE, hash, opts);
        try {
            if (hash === `#/jobs/${chain.id}`) {
                await page.locator('button#joint-summary-all').click();
            }
            const wide = await overflowing(page);
            assert.deepEqual(wide, [], `${hash}: elements past the right edge at 390 px`);
            const name = hash.replace(/[#/?=,]+/g, '-').replace(/^-|-$/g, '') || 'jobs';
            await screenshot(page, `phone-${name}.png`);
            if (/^#\/jobs\/\d+$/.test(hash)) {
                const order = await page.evaluate(() => ({
                    plot: document.querySelector('div.plot')?.getBoundingClientRect().top ?? null,
                    spec: document.querySelector('pre#spec').getBoundingClientRect().top,
                }));
                assert.ok(order.plot !== null && order.plot < order.spec, `${hash}: first plot at ${order.plot}, JSON at ${order.spec}`);
            }
            if (hash === '#/jobs') {
                const cells = await page.evaluate(() =>
                    ['status', 'progress'].map((c) => document.querySelector(`#jobs-table td[data-col="${c}"]`).getBoundingClientRect().right),
                );
                for (const right of cells) assert.ok(right <= 390, `a status or progress cell ends at ${right} px`);
            }
            assert.deepEqual(page.errors, []);
        } finally {
            await page.context().close();
        }
    }
});

test('a diverged job: how far it ran, why, a hint, and a re-run with BDF that posts an edited copy', async () => {
    await withView(browser, srv, `#/jobs/${diverged.id}`, 'job-diverged', async (page) => {
        const tEnd = diverged.metrics.t_end;
        assert.ok(tEnd > 0 && tEnd < 5, `t_end ${tEnd}`);
        assert.match(await text(page, '#job-ran'), new RegExp(`ran ${tEnd} s of 5 s`));
        assert.match(await text(page, '#job-progress-text'), /ran .* of 5 s/);
        assert.doesNotMatch(await text(page, '#job-progress-text'), /^0 %/);
        assert.match(await text(page, '#job-reason'), /exceeds the bound/);
        assert.match(await text(page, '#job-hint'), /smaller step or BDF/);
        assert.match(await text(page, 'button#rerun-smaller-step'), /step 0\.005 s/);
        await page.setViewportSize(DESKTOP);
        await screenshot(page, 'job-diverged-desktop.png');
        await page.locator('button#rerun-bdf').click();
        await pollValue(() => page.evaluate(() => location.hash), (h) => /^#\/jobs\/\d+$/.test(h) && h !== `#/jobs/${diverged.id}`, 'the new job opens');
        const newId = Number((await page.evaluate(() => location.hash)).split('/').pop());
        const made = await waitJob(srv, newId, { timeoutMs: 60000 });
        assert.equal(made.spec.integrator.method, 'bdf');
        assert.equal(made.spec.controller.kp, 1e5, 'the rest of the spec is the diverged one');
        assert.match(made.name, /with BDF/);
    });
});

test('a long run is plotted from min/max buckets: at most two rows per pixel, the extremes kept', async () => {
    /* 4001 samples: more than two per pixel of any plot on this page */
    const long = await runJob(srv, { preset: 'triple_pendulum_pid', duration: 4, output: { interval: 0.001 } });
    await withView(browser, srv, `#/jobs/${long.id}`, 'job-minmax', async (page) => {
        const q = (await plots(page)).find((p) => p.channel === 'q');
        const width = await page.evaluate(() => document.querySelector('div.plot[data-channel="q"]').clientWidth);
        const fetched = await Promise.all(page.series);
        const plotted = fetched.find((s) => /channels=q%2Cq_des%2Ce/.test(s.url) || /channels=q,q_des,e/.test(s.url));
        assert.ok(plotted, JSON.stringify(fetched));
        assert.equal(plotted.reduce, 'minmax', plotted.url);
        assert.equal(q.points, plotted.samples, 'the plot draws the rows fetched');
        assert.ok(q.points <= 2 * Math.max(200, width) + 1 && q.points < long.metrics.samples, `${q.points} rows for ${width} px`);
        /* the page's f32 reader, on min/max buckets, finds the run's largest |tau| */
        const all = (await srv.get(`/api/jobs/${long.id}/series?channels=tau`)).json.tau;
        const want = Math.max(...all.map((col) => Math.max(...col.map(Math.abs))));
        const bin = await page.evaluate(async (id) => {
            const { getSeriesF32 } = await import('/api.js');
            const s = await getSeriesF32(id, { channels: ['tau'], maxPoints: 400, reduce: 'minmax' });
            return Math.max(...s.tau.map((col) => Math.max(...col.map(Math.abs))));
        }, long.id);
        assert.ok(Math.abs(bin - want) <= 1e-6 * want, `minmax keeps the peak |tau|: ${bin}, want ${want}`);
    });
});

test('an RK4 step cut to the output interval is shown with what was asked', async () => {
    assert.deepEqual(cut.metrics.step_cut, { asked: 0.05, used: 0.01 });
    await withView(browser, srv, `#/jobs/${cut.id}`, 'job-step-cut', async (page) => {
        assert.match(await text(page, '#step-cut'), /step of 0\.01 s, not the 0\.05 s asked/);
        assert.match(await text(page, 'dl#metrics'), /RK4 step0\.01 s, cut from the 0\.05 s asked/);
    });
});

test('queued and running jobs: queue place, simulated time and time left, polled as brief rows', async () => {
    const a = (await submit(srv, LONG)).id;
    const b = (await submit(srv, LONG)).id;
    const c = (await submit(srv, LONG)).id;
    try {
        await waitJob(srv, a, { until: (j) => j.status === 'running' && j.progress > 0 });
        await waitJob(srv, b, { until: (j) => j.status === 'running' && j.progress > 0 });
        const page = await openAt(DESKTOP, `#/jobs/${c}`, { jobLinks: false });
        try {
            await pollValue(() => text(page, '#job-progress-text'), (t) => /1st in the queue/.test(t || ''), 'queue place');
            await screenshot(page, 'job-queued-desktop.png');
        } finally {
            await page.context().close();
        }
        const seen = [];
        const run = await openAt(PHONE, `#/jobs/${a}`, { jobLinks: false });
        try {
            run.on('request', (r) => seen.push(new URL(r.url()).pathname + new URL(r.url()).search));
            await pollValue(() => text(run, '#job-progress-text'), (t) => /simulated [0-9.]+ s of 100 s, about .* left/.test(t || ''), 'simulated time and ETA');
            await poll(() => seen.some((u) => u === `/api/jobs/${a}?brief=1`), 'a brief poll');
            assert.ok(!seen.includes(`/api/jobs/${a}`), `no full job while running: ${seen.join(' ')}`);
            /* partial plots: drawn while running, growing, each sample fetched once */
            const points = () => run.evaluate(() => Number(document.querySelector('[data-partial] div.plot[data-channel="q"]')?.getAttribute('data-points') || 0));
            const p1 = await pollValue(points, (n) => n >= 2, 'partial q plot');
            await pollValue(points, (n) => n > p1, `partial q plot growing from ${p1} points`, 20000);
            const partials = seen.filter((u) => u.startsWith(`/api/jobs/${a}/series?`) && u.includes('partial=1'));
            const froms = partials.map((u) => Number(new URL(u, 'http://x').searchParams.get('from') || 0));
            assert.ok(froms.length >= 2, partials.join(' '));
            for (let k = 1; k < froms.length; k++) assert.ok(froms[k] >= froms[k - 1], `from goes forward: ${froms}`);
            assert.ok(froms[froms.length - 1] > 0, `later fetches start past sample 0: ${froms}`);
            await screenshot(run, 'job-running-phone.png');
            await run.setViewportSize(DESKTOP);
            await screenshot(run, 'job-running-desktop.png');
            await screenshot(run, 'job-running-phone.png');
        } finally {
            await run.context().close();
        }
    } finally {
        for (const id of [a, b, c]) await stopJob(srv, id);
    }
});

test('cancel and delete: separate buttons, each confirmed naming the job and its status; a late cancel keeps the job', async () => {
    const id = (await submit(srv, LONG)).id;
    try {
        await waitJob(srv, id, { until: (j) => j.status === 'running' && j.progress > 0 });
        const page = await openAt(DESKTOP, `#/jobs/${id}`, { jobLinks: false });
        try {
            assert.equal(await page.locator('button#delete-job').isVisible(), false, 'no delete while running');
            await page.locator('button#cancel-job').click();
            await page.waitForSelector('dialog#confirm-dialog[open]');
            const said = await text(page, '#confirm-text');
            const name = (await apiJob(srv, id)).name;
            assert.equal(said, `Cancel job #${id} “${name}”, now running? It stops at its next step and keeps what it ran so far.`);
            assert.equal(await page.evaluate(() => document.activeElement?.id), 'confirm-no', '"Keep it" has the focus');
            await screenshot(page, 'confirm-cancel.png');
            await page.keyboard.press('Escape');
            await poll(async () => (await page.locator('dialog#confirm-dialog').count()) === 0, 'the dialog closes on Escape');
            assert.equal((await apiJob(srv, id)).status, 'running', 'Escape cancelled nothing');

            /* the job ends while the dialog is open: the confirmed cancel keeps it */
            await page.locator('button#cancel-job').click();
            await page.waitForSelector('dialog#confirm-dialog[open]');
            assert.equal((await srv.post(`/api/jobs/${id}/cancel`)).status, 202);
            await waitJob(srv, id);
            await page.locator('button#confirm-yes').click();
            await pollValue(() => text(page, 'p.message'), (t) => /Not cancelled: job \d+ is cancelled: there is nothing to cancel.*kept/.test(t || ''), 'the late cancel is refused');
            assert.equal((await srv.get(`/api/jobs/${id}`)).status, 200, 'the job is still there');

            /* finished: delete, confirmed */
            await poll(() => page.locator('button#delete-job').isVisible(), 'delete once finished');
            assert.equal(await page.locator('button#cancel-job').isVisible(), false, 'no cancel once finished');
            await page.locator('button#delete-job').click();
            await page.waitForSelector('dialog#confirm-dialog[open]');
            assert.match(await text(page, '#confirm-text'), new RegExp(`Delete job #${id} .*now cancelled, with its series`));
            await page.locator('button#confirm-yes').click();
            await pollValue(() => page.evaluate(() => location.hash), (h) => h === '#/jobs', 'back to the list');
            assert.equal((await srv.get(`/api/jobs/${id}`)).status, 404, 'deleted');
            assert.deepEqual(page.errors, []);
        } finally {
            await page.context().close();
        }
    } finally {
        if ((await srv.get(`/api/jobs/${id}`)).status === 200) await stopJob(srv, id);
    }
});
