/*
 * page_load.mjs - how long the job page of an n-link chain takes to become interactive, and how
 * many bytes it transfers (issue 23's target: a 4096-link job under 3 s and 5 MB on this
 * machine). A benchmark, not a test: it prints figures and asserts nothing.
 *
 * One ctcsim-server (build/ctcsim-server, the page from build/web: `make all web` first) on
 * loopback with a temporary database; for each n in PAGE_SIZES (default 64,1024,4096) it runs
 * the n_link_pendulum preset for PAGE_DURATION s (default 5) sampled every 0.01 s, then opens
 * #/jobs/ID in headless Chromium (playwright-core from tests/web) PAGE_REPEATS times (default
 * 3), each in a fresh context (no cache), at 1400 x 900, and records:
 *   - usable: ms from the navigation's start (performance.now() in the page) to the plots, the
 *     time cursor and the summary drawn (div.plots[data-drawn]), and wall usable: the same seen
 *     from this script, from page.goto to the selector found (adds the browser's own overhead:
 *     the target's clock);
 *   - ready: the same two to the view's data-ready (heat-map and animation drawn too);
 *   - data: ms from the navigation's start to the end of the last API response;
 *   - bytes: the encoded bytes of every response (CDP Network.loadingFinished), and of those the
 *     series requests and GET /api/jobs/ID;
 *   - slider: the median ms from a move of the time cursor to the next painted frame (20 moves);
 *   - height: the page's height in px.
 * It also fetches, for comparison, what the page fetched before the f32 form: the plot series
 * as JSON (every channel, the first 24 coordinates, every-th sample for ~2 per pixel) and the
 * animation's q and q_des as JSON at the same stride.
 *
 * Run: node bench/page_load.mjs (from the repository root). Prints a markdown table.
 */
import { startServer } from '../tests/api/lib.mjs';
import { chromium } from '../tests/web/node_modules/playwright-core/index.mjs';

const SIZES = (process.env.PAGE_SIZES || '64,1024,4096').split(',').map(Number);
const DURATION = Number(process.env.PAGE_DURATION || 5);
const REPEATS = Number(process.env.PAGE_REPEATS || 3);
const CHROMIUM = process.env.CHROMIUM || '/usr/bin/chromium';

const median = (xs) => [...xs].sort((a, b) => a - b)[Math.floor(xs.length / 2)];
const mb = (b) => (b / 1e6).toFixed(2);

async function measure(browser, srv, id) {
    const context = await browser.newContext({ viewport: { width: 1400, height: 900 } });
    const page = await context.newPage();
    const cdp = await context.newCDPSession(page);
    await cdp.send('Network.enable');
    const urls = new Map();
    let total = 0, series = 0, job = 0;
    cdp.on('Network.requestWillBeSent', (e) => urls.set(e.requestId, e.request.url));
    cdp.on('Network.loadingFinished', (e) => {
        const url = new URL(urls.get(e.requestId) || 'http://x/');
        total += e.encodedDataLength;
        if (/\/series$/.test(url.pathname)) series += e.encodedDataLength;
        if (url.pathname === `/api/jobs/${id}`) job += e.encodedDataLength;
    });
    await page.addInitScript(() => {
        new MutationObserver(() => {
            if (!window.__usableAt && document.querySelector('#view .plots[data-drawn="1"]')) window.__usableAt = performance.now();
            const v = document.getElementById('view');
            if (v && v.getAttribute('data-ready') === '1' && v.querySelector('a#download-csv') && !window.__readyAt) window.__readyAt = performance.now();
        }).observe(document, { subtree: true, attributes: true, childList: true });
    });
    const t0 = Date.now();
    await page.goto(`${srv.base}/#/jobs/${id}`);
    await page.waitForSelector('#view .plots[data-drawn="1"]', { timeout: 120000 });
    const wallUsable = Date.now() - t0;
    await page.waitForSelector('#view[data-ready="1"] a#download-csv', { timeout: 120000 });
    const wall = Date.now() - t0;
    const ready = Math.round(await page.evaluate(() => window.__readyAt));
    const usable = Math.round(await page.evaluate(() => window.__usableAt));
    const data = Math.round(await page.evaluate(() => Math.max(...performance.getEntriesByType('resource').filter((r) => r.name.includes('/api/')).map((r) => r.responseEnd))));
    const slider = [];
    for (let k = 1; k <= 20; k++) {
        slider.push(
            await page.evaluate(
                (frac) =>
                    new Promise((resolve) => {
                        const el = document.querySelector('input#time-cursor');
                        const t = performance.now();
                        el.value = String(Number(el.max) * frac);
                        el.dispatchEvent(new Event('input', { bubbles: true }));
                        requestAnimationFrame(() => requestAnimationFrame(() => resolve(performance.now() - t)));
                    }),
                k / 21,
            ),
        );
    }
    const height = await page.evaluate(() => document.documentElement.scrollHeight);
    await context.close();
    return { usable, wallUsable, ready, wall, data, total, series, job, slider: median(slider), height };
}

/* the bytes the page fetched before the f32 form, for the same job and width */
async function before(srv, job) {
    const m = job.metrics;
    const every = Math.max(1, Math.ceil(m.samples / (2 * 900)));
    const joints = m.nv > 24 ? `&joints=${Array.from({ length: 24 }, (_, i) => i).join(',')}` : '';
    const plot = await fetch(`${srv.base}/api/jobs/${job.id}/series?every=${every}&max_points=5000&format=json&channels=q,q_des,e,tau,w,energy${joints}`);
    let bytes = (await plot.arrayBuffer()).byteLength;
    if (joints) {
        const anim = await fetch(`${srv.base}/api/jobs/${job.id}/series?every=${every}&max_points=5000&format=json&channels=q,q_des`);
        bytes += (await anim.arrayBuffer()).byteLength;
    }
    return bytes;
}

const srv = await startServer({ workers: 1, web: 'build/web', api: 'api' });
const browser = await chromium.launch({ executablePath: CHROMIUM, args: ['--no-sandbox', '--disable-gpu'] });
const rows = [];
try {
    for (const n of SIZES) {
        const t0 = Date.now();
        const res = await srv.post('/api/jobs?wait=300', { preset: 'n_link_pendulum', n, duration: DURATION, output: { interval: 0.01 } });
        if (res.json?.status !== 'done') throw new Error(`n = ${n}: ${res.status} ${res.text.slice(0, 200)}`);
        const job = res.json;
        process.stderr.write(`n = ${n}: job ${job.id} ran in ${((Date.now() - t0) / 1000).toFixed(1)} s\n`);
        const runs = [];
        for (let r = 0; r < REPEATS; r++) runs.push(await measure(browser, srv, job.id));
        const pick = (k) => median(runs.map((x) => x[k]));
        rows.push({ n, samples: job.metrics.samples, usable: pick('usable'), wallUsable: pick('wallUsable'), ready: pick('ready'), wall: pick('wall'), data: pick('data'), total: pick('total'), series: pick('series'),
            job: pick('job'), slider: pick('slider'), height: pick('height'), before: await before(srv, job) });
    }
} finally {
    await browser.close();
    await srv.stop();
}
console.log(`| n | samples | usable (ms) | wall usable (ms) | ready (ms) | data in (ms) | wall ready (ms) | transferred (MB) | of which series | GET job | series before f32 (MB) | slider (ms/frame) | page height (px) |`);
console.log(`| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |`);
for (const r of rows) {
    console.log(`| ${r.n} | ${r.samples} | ${r.usable} | ${r.wallUsable} | ${r.ready} | ${r.data} | ${r.wall} | ${mb(r.total)} | ${mb(r.series)} | ${mb(r.job)} | ${mb(r.before)} | ${r.slider.toFixed(1)} | ${r.height} |`);
}
