/*
 * cost.test.mjs - what a run cost and how accurate it was, in the job page's compact metrics
 * panel, and how far a stopped run got, in the job list (issue 23's loose ends): a sampled
 * controller's job shows the tracking error by cause (sampling, noise, model: each one's RMS
 * and share, checked against the metrics' own arrays; none for a job without the causes), a job whose tolerances are below the
 * accelerations' rounding shows them raised with the reason, every job shows µs per evaluation,
 * steps and evaluations, and the panel stays a handful of lines; a diverged job's row in the
 * list says how far it ran, the fraction metrics.t_end / spec.duration, not "0 %". And the page
 * of a large chain is drawn in stages: on a phone, where the animation's panel is below the
 * fold, the view is ready with the plots and the heat-map and no animation series fetched; the
 * series comes, and the animation is drawn, when the panel scrolls into view. Screenshots go to
 * artifacts/.
 */
import assert from 'node:assert/strict';
import { after, before, test } from 'node:test';

import { fetchedSeries, launchBrowser, newPage, poll, runJob, screenshot, screenshotOf, startWebServer, text, waitView, withView } from './lib.mjs';

/* a sampled PID: the sampling causes error, noise and model none */
const SAMPLED = { preset: 'triple_pendulum_pid', duration: 1, controller: { sample_period: 0.02 } };
/* tolerances far below what a triple pendulum's accelerations carry (~1e-15 relative): raised */
const TIGHT = { preset: 'triple_pendulum_pid', duration: 0.05, integrator: { method: 'dopri5', rtol: 1e-17, atol: 1e-20 } };
/* diverges at t = 0.04 s of 0.2 s: a stiff PD on RK4 with a 0.02 s step */
const DIVERGING = {
    preset: 'triple_pendulum_pid',
    duration: 0.2,
    controller: { type: 'pd', kp: 1e5, kv: 200 },
    integrator: { method: 'rk4', step: 0.02 },
    output: { interval: 0.02 },
};

let srv, browser, sampled, tight, diverged, chain;

before(async () => {
    srv = await startWebServer();
    browser = await launchBrowser();
    sampled = await runJob(srv, SAMPLED);
    tight = await runJob(srv, TIGHT);
    const res = await srv.post('/api/jobs?wait=60', DIVERGING);
    assert.equal(res.json?.status, 'diverged', res.text);
    diverged = res.json;
    chain = await runJob(srv, { preset: 'n_link_pendulum', n: 64, duration: 1, output: { interval: 0.01 } });
});

after(async () => {
    await browser?.close();
    await srv?.stop();
});

/* the dd after the dt whose text is term, or null */
const metric = (page, term) =>
    page.evaluate((t) => {
        const dt = [...document.querySelectorAll('dl#metrics dt')].find((d) => d.textContent === t);
        return dt ? dt.nextElementSibling.textContent : null;
    }, term);

const rmsOf = (xs) => Math.sqrt(xs.reduce((s, x) => s + x * x, 0) / xs.length);

test('a sampled run: the error by cause with each share, the cost, in a short panel', async () => {
    const causes = sampled.metrics.error_by_cause;
    assert.ok(causes && causes.sampling.every((x) => x > 0), JSON.stringify(causes));
    await withView(browser, srv, `#/jobs/${sampled.id}`, 'job-causes', async (page) => {
        const line = await metric(page, 'tracking error by cause');
        assert.ok(line, 'no "tracking error by cause" in dl#metrics');
        /* the shares, from the metrics' arrays: sampling is the only cause of this job */
        const sampling = rmsOf(causes.sampling), noise = rmsOf(causes.noise), model = rmsOf(causes.model);
        const share = (x) => Math.round((100 * x) / (sampling + noise + model));
        assert.match(line, new RegExp(`^sampling [0-9.e-]+ \\(${share(sampling)} %\\), noise 0 \\(0 %\\), model 0 \\(0 %\\)`));
        assert.equal(share(sampling), 100);
        const shown = Number(/^sampling ([0-9.e-]+)/.exec(line)[1]);
        assert.ok(Math.abs(shown - sampling) <= 1e-3 * sampling, `sampling ${shown}, the metrics' RMS ${sampling}`);
        const cost = await metric(page, 'cost');
        const m = sampled.metrics;
        assert.match(cost, /µs per evaluation/);
        assert.ok(cost.includes(`${m.steps} steps (${m.rejected} rejected), ${m.rhs_evals} evaluations`), cost);
        const perEval = Number(/^([0-9.e+-]+) µs/.exec(cost)[1]);
        assert.ok(Math.abs(perEval - m.us_per_eval) <= 1e-3 * m.us_per_eval, `${perEval} µs shown, ${m.us_per_eval} stored`);
        /* dopri5 on a triple pendulum: tolerances as asked */
        assert.match(await metric(page, 'tolerances'), /as asked/);
        const lines = await page.evaluate(() => document.querySelectorAll('dl#metrics dt').length);
        assert.ok(lines <= 16, `dl#metrics has ${lines} lines`);
        await screenshotOf(page, 'dl#metrics', 'job-metrics-causes.png');
    });
});

test('tolerances below the rounding: shown raised, with the reason', async () => {
    const floor = tight.metrics.tolerance_floor;
    assert.ok(floor && floor.raised, JSON.stringify(floor));
    assert.ok(floor.rtol > 1e-17 && floor.atol > 1e-20, JSON.stringify(floor));
    await withView(browser, srv, `#/jobs/${tight.id}`, 'job-tolerance-floor', async (page) => {
        const line = await metric(page, 'tolerances');
        assert.equal(line, `raised: ${floor.reason}`);
        assert.match(floor.reason, /atol 1e-20 raised to .*rtol 1e-17 raised to/);
        /* no sampling, noise or model error: no line for them */
        assert.ok(tight.metrics.error_by_cause.sampling.every((x) => x === 0));
        assert.equal(await metric(page, 'tracking error by cause'), null);
        await screenshotOf(page, 'dl#metrics', 'job-metrics-tolerance-floor.png');
    });
});

test('the job list: a diverged run says how far it ran, not 0 %', async () => {
    const m = diverged.metrics;
    const reached = m.t_end / diverged.spec.duration;
    assert.ok(reached > 0.1 && reached < 1, `t_end ${m.t_end} of ${diverged.spec.duration} s`);
    assert.ok(Math.abs(diverged.progress - reached) < 1e-9, `stored progress ${diverged.progress}, reached ${reached}`);
    await withView(browser, srv, '#/jobs', 'list-stopped', async (page) => {
        const cell = `tr:has(a[href="#/jobs/${diverged.id}"]) td[data-col="progress"]`;
        assert.equal(await text(page, cell), `ran ${Math.floor(100 * reached + 1e-9)} %`);
        const done = `tr:has(a[href="#/jobs/${sampled.id}"]) td[data-col="progress"]`;
        assert.equal(await text(page, done), '100 %');
        await screenshot(page, 'list-stopped.png');
    });
});

test('a 64-link chain on a phone: ready without the animation below the fold; it loads when scrolled to', async () => {
    const page = await newPage(browser);
    try {
        await page.setViewportSize({ width: 390, height: 844 });
        const hash = `#/jobs/${chain.id}`;
        await page.goto(`${srv.base}/${hash}`);
        await waitView(page, hash);
        assert.equal(await page.evaluate(() => document.querySelector('#view .plots').getAttribute('data-drawn')), '1');
        assert.ok(await page.evaluate(() => !!document.querySelector('canvas#heatmap')), 'the heat-map is drawn');
        const below = await page.evaluate(() => document.querySelector('section.anim').getBoundingClientRect().top);
        assert.ok(below > 844, `the animation's panel starts at ${below} px, below the fold`);
        const q = (xs) => xs.filter((s) => s.channels === 'q,q_des');
        assert.equal(q(await fetchedSeries(page)).length, 0, 'no animation series before it is in view');
        assert.match(await text(page, '#anim-waiting'), /loads when this panel is in view/);
        await page.locator('section.anim').scrollIntoViewIfNeeded();
        await poll(() => page.evaluate(() => !!document.querySelector('section.anim canvas') &&
            document.querySelector('#view').getAttribute('data-ready') === '1'), 'the animation drawn once in view');
        const got = q(await fetchedSeries(page));
        assert.equal(got.length, 1, 'one animation series');
        assert.equal(got[0].reduce, 'stride');
        assert.deepEqual(page.errors, []);
        await screenshot(page, 'job-chain-phone-anim.png');
    } catch (e) {
        await screenshot(page, 'FAIL-job-chain-phone-anim.png').catch(() => {});
        throw e;
    } finally {
        await page.context().close();
    }
});
