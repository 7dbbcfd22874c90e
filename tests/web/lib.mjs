/*
 * lib.mjs - what the browser tests share: a ctcsim-server serving the assembled page (WEB_ROOT)
 * on a free port with its own temporary database (started by ../api/lib.mjs, the API tests'
 * helpers, used read-only), Debian's Chromium driven headless by playwright-core, one fresh page
 * per test that records uncaught script errors and every series the page fetches, waits on the
 * page's test hooks (web/README.md), and screenshots under tests/web/artifacts/.
 *
 * Nothing here sleeps for a fixed time: every wait is a condition polled until it holds or its
 * time runs out, and the timeout message says what was last seen.
 *
 * Environment: CTCSIM_SERVER (server binary), WEB_ROOT (the served folder: the page plus
 * vendor/uPlot.*; default build/web), API_DIR (default api/), CHROMIUM (default /usr/bin/chromium),
 * CTCSIM_WEB_HEADED=1 to watch the browser. Relative paths are taken from the repository root.
 */
import assert from 'node:assert/strict';
import { mkdirSync } from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

import { chromium } from 'playwright-core';

import { FINAL, ROOT, startServer, waitFor, waitJob } from '../api/lib.mjs';

export { FINAL, listAll, submit, tempDir, waitFor, waitJob } from '../api/lib.mjs';
export { ROOT };

const HERE = path.dirname(fileURLToPath(import.meta.url));
export const WEB_ROOT = path.resolve(ROOT, process.env.WEB_ROOT || 'build/web');
export const API_DIR = path.resolve(ROOT, process.env.API_DIR || 'api');
export const CHROMIUM = process.env.CHROMIUM || '/usr/bin/chromium';
export const ARTIFACTS = path.join(HERE, 'artifacts');

/* how long a condition may take to hold (ms): a page reacting to input, a short job finishing */
export const WAIT_MS = 15000;

const VIEWPORT = { width: 1280, height: 900 };

/* ---- server and browser ---- */

/* Starts ctcsim-server on WEB_ROOT and API_DIR (opts as startServer in ../api/lib.mjs). */
export function startWebServer(opts = {}) {
    return startServer({ workers: 2, web: WEB_ROOT, api: API_DIR, ...opts });
}

/* Launches headless Chromium. Close it with browser.close(). */
export function launchBrowser() {
    return chromium.launch({
        executablePath: CHROMIUM,
        headless: !process.env.CTCSIM_WEB_HEADED,
        args: ['--no-sandbox', '--disable-gpu', '--disable-background-networking', '--disable-component-update'],
    });
}

/* Submits a job through the API and waits for it to finish (?wait=); throws unless it is done.
 * Resolves GET /api/jobs/{id}. */
export async function runJob(srv, job) {
    const res = await srv.post('/api/jobs?wait=60', job);
    if (res.status !== 200 || res.json?.status !== 'done') {
        throw new Error(`POST /api/jobs?wait=60 ${JSON.stringify(job)}: ${res.status} ${res.text.slice(0, 300)}`);
    }
    return res.json;
}

/* GET /api/jobs/{id}, the job or a throw. */
export async function apiJob(srv, id) {
    const res = await srv.get(`/api/jobs/${id}`);
    if (res.status !== 200) throw new Error(`GET /api/jobs/${id}: ${res.status} ${res.text}`);
    return res.json;
}

/* Cancels job id unless it has finished (a DELETE of a finished job would delete it) and waits
 * for it to stop; for clean-up after a test that may have failed halfway. */
export async function stopJob(srv, id) {
    const job = await apiJob(srv, id);
    if (FINAL.has(job.status)) return;
    await srv.del(`/api/jobs/${id}`);
    await waitJob(srv, id);
}

/* ---- pages ---- */

/* The rows of a series answer in the f32 form (its JSON header's "rows"), or null. */
function rowsInF32(buf) {
    if (buf.length < 4) return null;
    const h = buf.readUInt32LE(0);
    try {
        return JSON.parse(buf.subarray(4, 4 + h).toString('utf8')).rows;
    } catch {
        return null;
    }
}

/* The number of samples in a series answer (JSON: t's length; CSV: its rows). */
function samplesIn(text) {
    try {
        const doc = JSON.parse(text);
        if (Array.isArray(doc?.t)) return doc.t.length;
        if (Array.isArray(doc?.series?.t)) return doc.series.t.length;
        return null;
    } catch {
        const lines = text.split('\n').filter((l) => l !== '');
        return lines.length ? lines.length - 1 : null;
    }
}

/* A new page (in its own browser context, so no state is shared between tests) that records:
 *   page.errors  uncaught exceptions and unhandled rejections of the page's scripts
 *   page.console its console errors and warnings (shown when a test fails, not asserted)
 *   page.series  promises of {url, every, channels, reduce (f32: "stride" or "minmax", else
 *                null), bytes, samples (rows)} for each series answer fetched */
export async function newPage(browser) {
    const context = await browser.newContext({ viewport: VIEWPORT, acceptDownloads: true });
    const page = await context.newPage();
    page.errors = [];
    page.console = [];
    page.series = [];
    page.on('pageerror', (e) => page.errors.push(String(e && e.stack ? e.stack : e)));
    page.on('console', (m) => {
        if (m.type() === 'error' || m.type() === 'warning') page.console.push(`${m.type()}: ${m.text()}`);
    });
    page.on('response', (res) => {
        const url = new URL(res.url());
        if (!/^\/api\/jobs\/[0-9]+\/series$/.test(url.pathname) || res.status() !== 200) return;
        const f32 = url.searchParams.get('format') === 'f32';
        page.series.push(
            res.body().then(
                (buf) => ({
                    url: url.pathname + url.search,
                    every: Number(url.searchParams.get('every') || 1),
                    channels: url.searchParams.get('channels'),
                    reduce: f32 ? url.searchParams.get('reduce') || 'stride' : null,
                    bytes: buf.length,
                    samples: f32 ? rowsInF32(buf) : samplesIn(buf.toString('utf8')),
                }),
                () => ({ url: url.pathname + url.search, samples: null }),
            ),
        );
    });
    return page;
}

/* A selector that exists only once the view at `hash` has loaded: each view has its own hook. */
export function viewHook(hash) {
    const h = hash.replace(/^#?\/?/, '');
    if (h === '' || /^jobs\/?(\?.*)?$/.test(h)) return 'table#jobs-table';
    if (/^jobs\/[0-9]+/.test(h)) return '#job-status';
    if (h.startsWith('compare')) return '#compare-legend';
    if (h.startsWith('submit')) return 'select#preset';
    if (/^families\/?(\?.*)?$/.test(h)) return 'table#families-table';
    if (/^families\/[0-9]+/.test(h)) return 'table#family-table';
    throw new Error(`no view for ${hash}`);
}

/* Waits until the address is `hash` (when given), #view has data-ready="1" and `selector` exists.
 * The job view of a job must also link that job's downloads, so that the view of the previous job
 * (or any other view, still marked ready while the router starts) never passes; jobLinks: false
 * drops that for a job that has no series yet. */
export async function waitView(page, hash, { selector, jobLinks = true, timeoutMs = WAIT_MS } = {}) {
    const sel = selector || viewHook(hash);
    const m = /^#\/jobs\/([0-9]+)$/.exec(hash || '');
    const jobId = m && jobLinks ? m[1] : null;
    try {
        await page.waitForFunction(
            ({ hash: want, sel: s, jobId: id }) => {
                if (want !== null && decodeURIComponent(location.hash) !== want) return false;
                if (!document.querySelector('#view[data-ready="1"]') || !document.querySelector(s)) return false;
                if (id) {
                    const a = document.querySelector('a#download-csv');
                    return !!a && new URL(a.href, location.href).pathname === `/api/jobs/${id}/series`;
                }
                return true;
            },
            { hash: hash ?? null, sel, jobId },
            { timeout: timeoutMs, polling: 50 },
        );
    } catch (e) {
        const seen = await page
            .evaluate(() => ({
                hash: location.hash,
                ready: document.querySelector('#view')?.getAttribute('data-ready') ?? '(no #view)',
                status: document.querySelector('#job-status')?.textContent ?? null,
                formError: document.querySelector('#form-error')?.textContent ?? null,
            }))
            .catch(() => ({}));
        throw new Error(`view ${hash} (${sel}) not ready within ${timeoutMs} ms; seen ${JSON.stringify(seen)}\n${e.message}`);
    }
}

/* Opens base/hash in a new page and waits for the view. */
export async function openView(browser, srv, hash, opts = {}) {
    const page = await newPage(browser);
    await page.goto(`${srv.base}/${hash}`);
    await waitView(page, hash, opts);
    return page;
}

/* Runs fn(page) on a new page at `hash`; afterwards asserts that the page threw nothing, and closes
 * it. A failing test leaves artifacts/FAIL-<name>.png behind. */
export async function withView(browser, srv, hash, name, fn, opts = {}) {
    const page = await newPage(browser);
    try {
        await page.goto(`${srv.base}/${hash}`);
        await waitView(page, hash, opts);
        await fn(page);
        assert.deepEqual(page.errors, [], `uncaught errors in the page at ${hash}`);
    } catch (e) {
        await screenshot(page, `FAIL-${name}.png`).catch(() => {});
        if (page.errors.length) e.message += `\n  page errors:\n    ${page.errors.join('\n    ')}`;
        if (page.console.length) e.message += `\n  console:\n    ${page.console.slice(0, 10).join('\n    ')}`;
        throw e;
    } finally {
        await page.context().close();
    }
}

/* Saves a full-page screenshot as artifacts/NAME. */
export async function screenshot(page, name) {
    mkdirSync(ARTIFACTS, { recursive: true });
    await page.screenshot({ path: path.join(ARTIFACTS, name), fullPage: true });
}

/* Saves a screenshot of the first element matching sel as artifacts/NAME. */
export async function screenshotOf(page, sel, name) {
    mkdirSync(ARTIFACTS, { recursive: true });
    await page.locator(sel).first().screenshot({ path: path.join(ARTIFACTS, name) });
}

/* Where each plot's uPlot cursor line stands, as a fraction of its plotting area's width:
 * [{channel, at (null when the line is hidden)}]. */
export function plotCursors(page) {
    return page.evaluate(() =>
        [...document.querySelectorAll('div.plot[data-channel]')].map((d) => {
            const over = d.querySelector('.u-over')?.getBoundingClientRect();
            const line = d.querySelector('.u-cursor-x');
            if (!over || !line || getComputedStyle(line).display === 'none' || line.classList.contains('u-off')) {
                return { channel: d.getAttribute('data-channel'), at: null };
            }
            const r = line.getBoundingClientRect();
            return { channel: d.getAttribute('data-channel'), at: (r.left - over.left) / over.width };
        }),
    );
}

/* Polls fn() (async, may read the page) until it returns a truthy value; the timeout message
 * shows the last value. */
export function poll(fn, what, timeoutMs = WAIT_MS) {
    let last;
    return waitFor(
        async () => {
            last = await fn();
            return last;
        },
        { timeoutMs, intervalMs: 50, what: () => `${what}; last seen ${JSON.stringify(last)}` },
    );
}

/* Waits until fn() returns a value for which ok(value) holds; resolves that value. */
export async function pollValue(fn, ok, what, timeoutMs = WAIT_MS) {
    let last;
    await waitFor(
        async () => {
            last = await fn();
            return ok(last);
        },
        { timeoutMs, intervalMs: 50, what: () => `${what}; last seen ${JSON.stringify(last)}` },
    );
    return last;
}

/* An attribute of the first element matching sel, or null (also when there is none). */
export function attr(page, sel, name) {
    return page.evaluate(([s, n]) => document.querySelector(s)?.getAttribute(n) ?? null, [sel, name]);
}

/* The trimmed text of the first element matching sel, or null. */
export function text(page, sel) {
    return page.evaluate((s) => document.querySelector(s)?.textContent.trim() ?? null, sel);
}

/* Every plot of the view: [{channel, points, series, uplot (a uPlot is drawn inside)}]. */
export function plots(page) {
    return page.evaluate(() =>
        [...document.querySelectorAll('div.plot[data-channel]')].map((d) => {
            const c = d.querySelector('.uplot canvas');
            return {
                channel: d.getAttribute('data-channel'),
                points: d.hasAttribute('data-points') ? Number(d.getAttribute('data-points')) : null,
                series: d.hasAttribute('data-series') ? Number(d.getAttribute('data-series')) : null,
                uplot: !!c && c.width > 0 && c.height > 0,
            };
        }),
    );
}

/* The series answers the page fetched so far. */
export function fetchedSeries(page) {
    return Promise.all(page.series);
}

/* Sets input#time-cursor to t as a user would (value, then an input event); resolves the value
 * the range kept (it rounds to its step). */
export function setCursor(page, t) {
    return page.evaluate((v) => {
        const el = document.querySelector('input#time-cursor');
        el.value = String(v);
        el.dispatchEvent(new Event('input', { bubbles: true }));
        el.dispatchEvent(new Event('change', { bubbles: true }));
        return Number(el.value);
    }, t);
}

/* canvas#anim as a data URL, and a blank canvas of its size as one, to compare drawings. */
export function animImage(page) {
    return page.evaluate(() => {
        const c = document.querySelector('canvas#anim');
        const blank = document.createElement('canvas');
        blank.width = c.width;
        blank.height = c.height;
        return { image: c.toDataURL(), blank: blank.toDataURL(), width: c.width, height: c.height };
    });
}

/* Resolves after n animation frames of the page. */
export function frames(page, n = 3) {
    return page.evaluate(
        (k) =>
            new Promise((resolve) => {
                const step = () => (k-- <= 0 ? resolve() : requestAnimationFrame(step));
                requestAnimationFrame(step);
            }),
        n,
    );
}

/* Presses Tab (at most max times) from the top of the page until every selector in `targets`
 * has had the focus. Resolves {reached: [selectors focused], missed: [...], order: [what had the
 * focus, in order]}. */
export async function tabThrough(page, targets, max = 150) {
    /* start from the top: focus a stand-in placed before everything (a click would otherwise
     * leave the browser's starting point for Tab where it was), removed again afterwards */
    await page.evaluate(() => {
        const start = document.createElement('span');
        start.id = 'tab-start-for-tests';
        start.tabIndex = -1;
        document.body.prepend(start);
        start.focus();
    });
    const reached = new Set();
    const order = [];
    for (let i = 0; i < max && reached.size < targets.length; i++) {
        await page.keyboard.press('Tab');
        const hit = await page.evaluate((sels) => {
            const a = document.activeElement;
            if (!a || a === document.body) return { desc: '(body)', hits: [] };
            const desc =
                a.tagName.toLowerCase() +
                (a.id ? '#' + a.id : '') +
                (a.getAttribute('href') ? `[href="${a.getAttribute('href')}"]` : '') +
                (a.getAttribute('name') ? `[name="${a.getAttribute('name')}"]` : '');
            return { desc, hits: sels.filter((s) => a.matches(s)) };
        }, targets);
        order.push(hit.desc);
        for (const h of hit.hits) reached.add(h);
    }
    await page.evaluate(() => document.getElementById('tab-start-for-tests')?.remove());
    return { reached: [...reached], missed: targets.filter((t) => !reached.has(t)), order };
}

/* Asserts |a - b| <= tol with a message. */
export function near(a, b, tol, what) {
    assert.ok(Number.isFinite(a) && Math.abs(a - b) <= tol, `${what}: ${a}, want ${b} within ${tol}`);
}

/* the elements whose right edge passes the viewport's (outside any box that scrolls or clips
 * sideways, which keeps what it holds on screen), as "tag#id.class: right" */
export function overflowing(page) {
    return page.evaluate(() => {
        const width = document.documentElement.clientWidth;
        const clips = (e) => {
            for (let p = e.parentElement; p; p = p.parentElement) {
                const o = getComputedStyle(p).overflowX;
                if (o === 'auto' || o === 'scroll' || o === 'hidden' || o === 'clip') return true;
            }
            return false;
        };
        const out = [];
        for (const e of document.querySelectorAll('body *')) {
            const r = e.getBoundingClientRect();
            if (r.width === 0 && r.height === 0) continue;
            if (r.right > width + 0.5 && !clips(e)) {
                out.push(`${e.tagName.toLowerCase()}${e.id ? '#' + e.id : ''}${e.className && typeof e.className === 'string' ? '.' + e.className.split(' ').join('.') : ''}: ${Math.round(r.right)}`);
            }
        }
        if (document.documentElement.scrollWidth > width) out.push(`document scrollWidth ${document.documentElement.scrollWidth}`);
        return out;
    });
}
