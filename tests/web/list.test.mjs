/*
 * list.test.mjs - finding runs in the jobs table (#/jobs): the final and RMS errors shown as the
 * API lists them, the page sorted by a column (against the API's rows sorted here, the oracle),
 * the search box and the tags answering as GET /api/jobs?q= and ?tag= do, and the address
 * keeping the search, tag and sort; a job edited from a preset in the form listed with its preset
 * and named after the edit. Screenshots at 1400x900 and 390x844 (artifacts/list-*.png).
 */
import assert from 'node:assert/strict';
import { after, before, test } from 'node:test';

import { fmtNum } from '../../web/dom.js';
import { apiJob, attr, launchBrowser, newPage, poll, pollValue, runJob, screenshot, startWebServer, waitView } from './lib.mjs';

let srv;
let browser;

before(async () => {
    srv = await startWebServer();
    browser = await launchBrowser();
    await runJob(srv, { preset: 'triple_pendulum_pid', duration: 1, tags: ['sweep'] });
    await runJob(srv, { preset: 'triple_pendulum_pid', duration: 1, controller: { kp: 400 }, tags: ['sweep', 'fast'] });
    await runJob(srv, { preset: 'triple_pendulum_pd', duration: 1 });
    await runJob(srv, { preset: 'triple_pendulum_lqr', duration: 1, tags: ['designed'] });
});

after(async () => {
    await browser?.close();
    await srv?.stop();
});

async function atList(hash, name, fn, { width = 1400, height = 900 } = {}) {
    const page = await newPage(browser);
    try {
        await page.setViewportSize({ width, height });
        await page.goto(`${srv.base}/${hash}`);
        await waitView(page, null, { selector: 'table#jobs-table tbody tr' });
        await fn(page);
        assert.deepEqual(page.errors, [], `uncaught errors in the page at ${hash}`);
    } catch (e) {
        await screenshot(page, `FAIL-${name}.png`).catch(() => {});
        throw e;
    } finally {
        await page.context().close();
    }
}

const rowIds = (page) => page.locator('table#jobs-table tbody tr').evaluateAll((trs) => trs.map((tr) => Number(tr.dataset.jobId)));
const api = async (query) => (await srv.get(`/api/jobs?${query}`)).json.jobs;

test('the final and RMS errors are shown beside max |e|, as the API lists them', async () => {
    const rows = await api('limit=50');
    await atList('#/jobs', 'list-errors', async (page) => {
        for (const r of rows) {
            const cell = (col) => page.locator(`tr[data-job-id="${r.id}"] td[data-col="${col}"]`).textContent();
            assert.equal(await cell('e_final'), fmtNum(r.e_final), `job ${r.id} final |e|`);
            assert.equal(await cell('e_rms'), fmtNum(r.e_rms), `job ${r.id} RMS e`);
            assert.equal(await cell('e_max'), fmtNum(r.e_max), `job ${r.id} max |e|`);
            assert.deepEqual(await page.locator(`tr[data-job-id="${r.id}"] td[data-col="tags"] button.tag`).allTextContents(), r.tags);
        }
        await screenshot(page, 'list-1400.png');
        await page.setViewportSize({ width: 390, height: 844 });
        await screenshot(page, 'list-390.png');
    });
});

test('a column sorts the page, both ways, and the address keeps it', async () => {
    const rows = await api('limit=50');
    const by = (key, dir) => rows.slice().sort((a, b) => dir * (a[key] - b[key])).map((r) => r.id);
    await atList('#/jobs', 'list-sort', async (page) => {
        await page.locator('button.sort[data-key="e_final"]').click();
        assert.deepEqual(await rowIds(page), by('e_final', 1), 'by final |e|, ascending');
        assert.equal(await attr(page, 'th[data-key="e_final"]', 'aria-sort'), 'ascending');
        await page.locator('button.sort[data-key="e_final"]').click();
        assert.deepEqual(await rowIds(page), by('e_final', -1), 'descending');
        await page.locator('button.sort[data-key="e_rms"]').click();
        assert.deepEqual(await rowIds(page), by('e_rms', 1), 'by RMS e');
        assert.equal(await attr(page, 'th[data-key="e_final"]', 'aria-sort'), 'none');
        const hash = await page.evaluate(() => location.hash);
        assert.equal(hash, '#/jobs?sort=e_rms%3Aasc');
    });
    await atList('#/jobs?sort=e_rms:asc', 'list-sort-reload', async (page) => {
        assert.deepEqual(await rowIds(page), by('e_rms', 1), 'the sort from the address');
    });
});

test('the search box and the tags find what the API finds', async () => {
    await atList('#/jobs', 'list-search', async (page) => {
        await page.locator('input#job-search').fill('kp = 400');
        await page.locator('input#job-search').press('Enter');
        const want = (await api('q=kp%20%3D%20400')).map((j) => j.id);
        assert.equal(want.length, 1, 'the oracle finds the one edited job');
        await pollValue(() => rowIds(page), (ids) => JSON.stringify(ids) === JSON.stringify(want), 'the rows of the search');
        await page.locator('input#job-search').fill('');
        await page.locator('input#job-search').press('Enter');
        await pollValue(() => rowIds(page), (ids) => ids.length === 4, 'every job again');

        await page.locator('td[data-col="tags"] button.tag[data-tag="sweep"]').first().click();
        const tagged = (await api('tag=sweep')).map((j) => j.id);
        assert.equal(tagged.length, 2);
        await pollValue(() => rowIds(page), (ids) => JSON.stringify(ids) === JSON.stringify(tagged), 'the rows tagged sweep');
        assert.equal(await page.evaluate(() => location.hash), '#/jobs?tag=sweep');
        await screenshot(page, 'list-tag-1400.png');
        await page.locator('button#clear-tag').click();
        await pollValue(() => rowIds(page), (ids) => ids.length === 4, 'every job after clearing the tag');
    });
    await atList('#/jobs?q=lqr', 'list-search-reload', async (page) => {
        assert.equal(await page.locator('input#job-search').inputValue(), 'lqr');
        assert.deepEqual(await rowIds(page), (await api('q=lqr')).map((j) => j.id));
    });
});

test('a job edited from a preset in the form is listed with its preset, named after the edit', async () => {
    const page = await newPage(browser);
    try {
        await page.goto(`${srv.base}/#/submit?preset=triple_pendulum_pid`);
        await waitView(page, '#/submit?preset=triple_pendulum_pid');
        await pollValue(() => page.locator('#view [name="controller.kp"]').first().inputValue(), (v) => v === '100', 'the preset\'s kp in the form');
        await page.locator('#view [name="controller.kp"]').first().fill('400');
        await page.locator('#view [name="duration"]').first().fill('0.5');
        await poll(() => page.evaluate(() => JSON.parse(document.querySelector('textarea#job-json').value).controller.kp === 400), 'kp 400 in the JSON');
        await page.locator('button#submit-job').click();
        await poll(() => page.evaluate(() => /^#\/jobs\/[0-9]+$/.test(location.hash)), 'the job view after submitting', 30000);
        const id = Number((await page.evaluate(() => location.hash)).split('/')[2]);
        const job = await apiJob(srv, id);
        assert.equal(job.preset, 'triple_pendulum_pid', 'the preset recorded, not "custom"');
        assert.equal(job.name, 'triple_pendulum_pid, kp = 400, duration = 0.5');
        assert.equal(job.spec.controller.kp, 400);
        assert.equal(job.spec.controller.kv, 20, 'the rest of the preset kept');
        assert.deepEqual(page.errors, []);
    } finally {
        await page.context().close();
    }
});
