/*
 * joburl.test.mjs - the job view's address keeps its state (web/README.md, viewstate.js): after
 * moving the time cursor, zooming time and value axes and hiding a coordinate, the address
 * holds t, x, y and hide, and a reload of that address shows the same cursor, the same ranges
 * on every plot and the same coordinate hidden. An address that does not parse opens the view
 * unzoomed. Screenshot at 1400x900 (artifacts/job-url-1400.png).
 */
import assert from 'node:assert/strict';
import { after, before, test } from 'node:test';

import { attr, launchBrowser, near, poll, runJob, screenshot, setCursor, startWebServer, waitView, withView } from './lib.mjs';

let srv;
let browser;
let job;

before(async () => {
    srv = await startWebServer();
    browser = await launchBrowser();
    job = await runJob(srv, { preset: 'triple_pendulum_pd', duration: 2 });
});

after(async () => {
    await browser?.close();
    await srv?.stop();
});

/* each plot's shown ranges: {channel: [xmin, xmax, ymin, ymax]} */
function ranges(page) {
    return page.evaluate(() =>
        Object.fromEntries(
            [...document.querySelectorAll('div.plot[data-channel]')].map((d) => [
                d.dataset.channel,
                ['xmin', 'xmax', 'ymin', 'ymax'].map((k) => Number(d.dataset[k])),
            ]),
        ),
    );
}

/* waits for the job view after a reload at an address with a query (no exact-hash match) */
function waitJobView(page) {
    return waitView(page, null, { selector: `a#download-csv[href^="/api/jobs/${job.id}/series"]` });
}

test('cursor, zooms and hidden joints go into the address, and a reload restores them', async () => {
    await withView(browser, srv, `#/jobs/${job.id}`, 'job-url', async (page) => {
        const before = await ranges(page);
        await setCursor(page, 0.5);
        await page.click('div.zoom button:text-is("Zoom in")');
        await page.click('div.zoom button.zoom-y');
        await page.click('button.joint-toggle[data-joint="1"]');
        const hash = await poll(async () => {
            const h = await page.evaluate(() => decodeURIComponent(location.hash));
            return /[?&]t=0\.5(&|$)/.test(h) && /[?&]x=0,1(&|$)/.test(h) && /[?&]y=/.test(h) && /[?&]hide=1(&|$)/.test(h) ? h : null;
        }, 'the state in the address');
        assert.match(hash, new RegExp(`^#/jobs/${job.id}\\?`));
        const zoomed = await ranges(page);
        assert.deepEqual(zoomed.q.slice(0, 2), [0, 1], 'time zoomed to [0, 1] s around the cursor');
        assert.ok(zoomed.e[3] - zoomed.e[2] < before.e[3] - before.e[2], 'the value axis zoomed in');

        await page.reload();
        await waitJobView(page);
        assert.equal(await page.evaluate(() => decodeURIComponent(location.hash)), hash, 'the address kept');
        assert.equal(await page.inputValue('input#time-cursor'), '0.5', 'the cursor restored');
        const restored = await ranges(page);
        for (const [ch, r] of Object.entries(zoomed)) {
            for (let k = 0; k < 4; k++) near(restored[ch][k], r[k], 1e-5 * Math.max(1, Math.abs(r[k])), `${ch} range ${k}`);
        }
        assert.equal(await attr(page, 'button.joint-toggle[data-joint="1"]', 'aria-pressed'), 'false', 'joint 1 still hidden');
        assert.equal(await attr(page, 'button.joint-toggle[data-joint="0"]', 'aria-pressed'), 'true');
        await page.setViewportSize({ width: 1400, height: 900 });
        await screenshot(page, 'job-url-1400.png');
    });
});

test('an address whose state does not parse opens the job unzoomed', async () => {
    const hash = `#/jobs/${job.id}?t=abc&x=2,1&y=e:nope:1&hide=-1,x`;
    await withView(browser, srv, hash, 'job-url-bad', async (page) => {
        const r = await ranges(page);
        assert.deepEqual(r.q.slice(0, 2), [0, 2], 'the whole run');
        assert.equal(await page.inputValue('input#time-cursor'), '0');
        const hidden = await page.locator('button.joint-toggle[aria-pressed="false"]').count();
        assert.equal(hidden, 0, 'nothing hidden');
    }, { selector: `a#download-csv[href^="/api/jobs/${job.id}/series"]` });
});
