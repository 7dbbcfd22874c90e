/*
 * browse.test.mjs - the jobs table (#/jobs, #/ and the empty address): rows newest first as GET
 * /api/jobs lists them, a row leading to its job and Back leading back, a running job's progress
 * rising live and its status turning cancelled, the status filter, picking two jobs to compare,
 * pagination, and the keyboard.
 */
import assert from 'node:assert/strict';
import { after, before, test } from 'node:test';

import {
    launchBrowser,
    listAll,
    poll,
    pollValue,
    runJob,
    screenshot,
    startWebServer,
    stopJob,
    submit,
    tabThrough,
    waitJob,
    waitView,
    withView,
} from './lib.mjs';

let srv;
let browser;
const jobs = []; /* the finished jobs made here, oldest first */

/* the rows shown: [{id, status, name, progress (the <progress> value or null)}] */
function rows(page) {
    return page.evaluate(() =>
        [...document.querySelectorAll('table#jobs-table tbody tr[data-job-id]')].map((tr) => ({
            id: Number(tr.getAttribute('data-job-id')),
            status: tr.querySelector('td[data-col="status"]')?.textContent.trim() ?? null,
            name: tr.querySelector('td[data-col="name"]')?.textContent.trim() ?? null,
            progress: tr.querySelector('td[data-col="progress"] progress')?.value ?? null,
        })),
    );
}

before(async () => {
    srv = await startWebServer();
    browser = await launchBrowser();
    jobs.push(await runJob(srv, { preset: 'triple_pendulum_pid', duration: 1 }));
    jobs.push(await runJob(srv, { preset: 'triple_pendulum_pd', duration: 1 }));
    jobs.push(await runJob(srv, { preset: 'spatial_double_pendulum_pid', duration: 1 }));
});

after(async () => {
    await browser?.close();
    await srv?.stop();
});

test('keyboard: Tab reaches the nav links and the buttons; Enter on a nav link opens its view', async () => {
    await withView(browser, srv, '#/jobs', 'browse-keyboard', async (page) => {
        /* with two jobs picked, compare-selected can act; the pages' buttons only when there is
         * a page to go to (a disabled button cannot take the focus) */
        await page.locator(`input.compare-pick[data-job-id="${jobs[0].id}"]`).check();
        await page.locator(`input.compare-pick[data-job-id="${jobs[1].id}"]`).check();
        const buttons = await page.evaluate(() =>
            ['button#next-page', 'button#prev-page'].filter((s) => {
                const b = document.querySelector(s);
                return b && !b.disabled && b.offsetParent !== null;
            }),
        );
        const targets = [
            'nav a[href="#/jobs"]',
            'nav a[href="#/submit"]',
            'nav a[href="#/compare"]',
            'select#status-filter',
            'input.compare-pick',
            'button#compare-selected',
            ...buttons,
        ];
        const r = await tabThrough(page, targets);
        assert.deepEqual(r.missed, [], `never focused by Tab; the order was ${r.order.join(' > ')}`);
        await page.locator('nav a[href="#/submit"]').focus();
        await page.keyboard.press('Enter');
        await waitView(page, '#/submit');
    });
});

test('the table lists the jobs newest first, as GET /api/jobs does, with name and status', async () => {
    await withView(browser, srv, '#/jobs', 'browse', async (page) => {
        const api = await listAll(srv);
        const shown = await rows(page);
        assert.ok(shown.length >= jobs.length, `${shown.length} rows`);
        assert.deepEqual(
            shown.map((r) => r.id),
            api.slice(0, shown.length).map((r) => r.id),
            'rows against GET /api/jobs (newest first)',
        );
        for (let i = 1; i < shown.length; i++) assert.ok(shown[i - 1].id > shown[i].id, 'ids decrease down the table');
        for (const r of shown) {
            const a = api.find((j) => j.id === r.id);
            assert.match(r.status, new RegExp(a.status, 'i'), `row ${r.id} status`);
            assert.ok(r.name.includes(a.name), `row ${r.id} name "${r.name}", want "${a.name}"`);
        }
        await screenshot(page, 'browse.png');
    });
});

test('#/ and the empty address show the table too', async () => {
    for (const hash of ['#/', '']) {
        await withView(browser, srv, hash, 'browse-root', async (page) => {
            assert.ok((await rows(page)).length >= jobs.length, `rows at "${hash}"`);
        });
    }
});

test('a row opens its job at #/jobs/ID; Back returns to the table', async () => {
    const target = jobs[1];
    await withView(browser, srv, '#/jobs', 'browse-row-link', async (page) => {
        await page.locator(`table#jobs-table tbody tr[data-job-id="${target.id}"] td[data-col="name"]`).click();
        await waitView(page, `#/jobs/${target.id}`);
        assert.match(await page.locator('#job-status').textContent(), /done/i);
        await page.goBack();
        await waitView(page, '#/jobs');
        assert.ok((await rows(page)).some((r) => r.id === target.id));
    });
});

test('a running job: its row shows a progress bar that rises live, then cancelled when cancelled', async () => {
    /* about 70 s of work; the test cancels it */
    const row = await submit(srv, {
        preset: 'n_link_pendulum',
        n: 32,
        duration: 100,
        integrator: { method: 'rk4', step: 0.0001 },
        output: { interval: 0.5 },
    });
    try {
        await waitJob(srv, row.id, { until: (j) => j.status === 'running' });
        await withView(browser, srv, '#/jobs', 'browse-running', async (page) => {
            const mine = async () => (await rows(page)).find((r) => r.id === row.id) || null;
            const first = await pollValue(mine, (r) => r && /running/i.test(r.status) && r.progress !== null, `row ${row.id} running with a <progress>`);
            assert.equal((await rows(page))[0].id, row.id, 'the newest job is the first row');
            await pollValue(mine, (r) => r && r.progress > first.progress, `row ${row.id} progress rising from ${first.progress}`);
            await screenshot(page, 'browse-running.png');
            const del = await srv.del(`/api/jobs/${row.id}`);
            assert.equal(del.status, 202, del.text);
            await pollValue(mine, (r) => r && /cancel/i.test(r.status), `row ${row.id} status after DELETE`);
        });
    } finally {
        await stopJob(srv, row.id);
    }
});

test('the status filter shows only the jobs with that status', async () => {
    await withView(browser, srv, '#/jobs', 'browse-filter', async (page) => {
        const done = (await listAll(srv, { status: 'done' })).map((j) => j.id);
        const cancelled = (await listAll(srv, { status: 'cancelled' })).map((j) => j.id);
        assert.ok(cancelled.length >= 1, 'a cancelled job to filter out');
        await page.selectOption('select#status-filter', 'done');
        await poll(async () => {
            const shown = await rows(page);
            return shown.length > 0 && shown.every((r) => /done/i.test(r.status)) && shown.map((r) => r.id).join() === done.slice(0, shown.length).join();
        }, 'rows after filtering on done');
        await page.selectOption('select#status-filter', 'cancelled');
        await poll(async () => (await rows(page)).map((r) => r.id).join() === cancelled.join(), `rows ${cancelled} after filtering on cancelled`);
    });
});

test('two picked jobs open the compare view with both', async () => {
    const [a, b] = [jobs[0].id, jobs[2].id];
    await withView(browser, srv, '#/jobs', 'browse-compare', async (page) => {
        await page.locator(`input.compare-pick[data-job-id="${a}"]`).check();
        await page.locator(`input.compare-pick[data-job-id="${b}"]`).check();
        await page.locator('button#compare-selected').click();
        await poll(() => page.evaluate(() => decodeURIComponent(location.hash).startsWith('#/compare?ids=')), 'the address #/compare?ids=...');
        const hash = await page.evaluate(() => decodeURIComponent(location.hash));
        const ids = hash.replace('#/compare?ids=', '').split(',').map(Number).sort((x, y) => x - y);
        assert.deepEqual(ids, [a, b], hash);
        await waitView(page, hash);
        const legend = await page.evaluate(() => [...document.querySelectorAll('#compare-legend li[data-job-id]')].map((li) => Number(li.getAttribute('data-job-id'))));
        assert.deepEqual([...legend].sort((x, y) => x - y), [a, b]);
    });
});

test('pagination: next page continues with older jobs, previous page comes back', async () => {
    /* enough tiny jobs to need a second page at any page size up to 60 */
    const tiny = [];
    for (let i = 0; i < 60; i++) tiny.push(await submit(srv, { preset: 'triple_pendulum_pd', duration: 0.05 }));
    for (const t of tiny) await waitJob(srv, t.id);
    await withView(browser, srv, '#/jobs', 'browse-pages', async (page) => {
        const api = (await listAll(srv)).map((j) => j.id);
        const first = (await rows(page)).map((r) => r.id);
        assert.ok(first.length > 0 && first.length < api.length, `${first.length} rows on the first page of ${api.length}`);
        assert.deepEqual(first, api.slice(0, first.length));
        await page.locator('button#next-page').click();
        const second = await pollValue(
            async () => (await rows(page)).map((r) => r.id),
            (ids) => ids.length > 0 && ids[0] < first[first.length - 1],
            'rows after next page',
        );
        assert.deepEqual(second, api.slice(first.length, first.length + second.length), 'the second page against GET /api/jobs');
        await page.locator('button#prev-page').click();
        await pollValue(async () => (await rows(page)).map((r) => r.id).join(), (ids) => ids === first.join(), 'rows after previous page');
    });
});
