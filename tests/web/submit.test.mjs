/*
 * submit.test.mjs - the job form (#/submit): the presets of GET /api/presets, a preset filling the
 * form and the JSON, the two kept in sync both ways, a preset submitted from the form showing its
 * progress and ending on the job's view with the job as entered, the server's validation errors
 * shown at their fields (and nothing queued), a job uploaded from a file, a robot uploaded as a
 * URDF file (the job `ctcsim import` makes, run with the bodies the server converted), and the
 * keyboard.
 */
import assert from 'node:assert/strict';
import { readFile, writeFile } from 'node:fs/promises';
import path from 'node:path';
import { after, before, test } from 'node:test';

import {
    API_DIR,
    apiJob,
    launchBrowser,
    listAll,
    poll,
    pollValue,
    screenshot,
    startWebServer,
    tempDir,
    tabThrough,
    waitView,
    withView,
} from './lib.mjs';

let srv;
let browser;
let presets; /* GET /api/presets */

before(async () => {
    srv = await startWebServer();
    browser = await launchBrowser();
    presets = (await srv.get('/api/presets')).json.presets.map((p) => p.name);
});

after(async () => {
    await browser?.close();
    await srv?.stop();
});

/* the value of the form field named name (select, input, textarea), or null */
function field(page, name) {
    return page.evaluate((n) => {
        const el = document.querySelector(`#view [name="${n}"]`);
        return el ? el.value : null;
    }, name);
}

/* textarea#job-json parsed, or {unparsable: text} */
function jobJson(page) {
    return page.evaluate(() => {
        const t = document.querySelector('textarea#job-json').value;
        try {
            return JSON.parse(t);
        } catch {
            return { unparsable: t };
        }
    });
}

/* Fills the field named name as a user would (a select is selected, an input filled). */
async function setField(page, name, value) {
    const loc = page.locator(`#view [name="${name}"]`).first();
    if ((await loc.evaluate((el) => el.tagName)) === 'SELECT') await loc.selectOption(String(value));
    else await loc.fill(String(value));
}

/* The visible .field-error elements with text: [{field, text}] */
function fieldErrors(page) {
    return page.evaluate(() =>
        [...document.querySelectorAll('.field-error[data-field]')]
            .filter((e) => e.offsetParent !== null && e.textContent.trim() !== '')
            .map((e) => ({ field: e.getAttribute('data-field'), text: e.textContent.trim() })),
    );
}

/* Picks a preset in select#preset and waits for the form to take it (controller.type filled). */
async function pickPreset(page, name, controllerType) {
    /* the form fills itself from GET /api/presets/NAME: wait for that answer, so that fields set
       afterwards are not overwritten by it (controller.type alone may match before it lands) */
    const loaded = page.waitForResponse((r) => new URL(r.url()).pathname === `/api/presets/${name}`);
    await page.selectOption('select#preset', name);
    await loaded;
    await page.evaluate(() => new Promise((done) => requestAnimationFrame(() => setTimeout(done, 0))));
    await pollValue(() => field(page, 'controller.type'), (v) => v === controllerType, `controller.type after picking ${name}`);
}

test('select#preset offers the presets of GET /api/presets; #/submit?preset= picks one and fills the form', async () => {
    await withView(browser, srv, '#/submit?preset=triple_pendulum_pid', 'submit-preset', async (page) => {
        const options = await page.evaluate(() => [...document.querySelectorAll('select#preset option')].map((o) => o.value));
        for (const p of presets) assert.ok(options.includes(p), `select#preset has no option ${p} (${options})`);
        assert.equal(await page.locator('select#preset').inputValue(), 'triple_pendulum_pid');
        assert.equal(await field(page, 'controller.type'), 'pid');
        assert.equal(Number(await field(page, 'controller.kp')), 100);
        assert.equal(Number(await field(page, 'controller.kv')), 20);
        assert.equal(Number(await field(page, 'controller.ki')), 250);
        assert.equal(Number(await field(page, 'duration')), 5);
        const doc = await jobJson(page);
        assert.equal(doc.controller?.type, 'pid', `textarea#job-json: ${JSON.stringify(doc).slice(0, 300)}`);
        assert.equal(doc.controller?.kp, 100);
        await screenshot(page, 'submit.png');
        /* another preset replaces it */
        await pickPreset(page, 'spatial_double_pendulum_lqr', 'lqr');
        assert.equal((await jobJson(page)).controller?.type, 'lqr');
    });
});

test('the form and textarea#job-json stay in sync both ways', async () => {
    await withView(browser, srv, '#/submit?preset=triple_pendulum_pd', 'submit-sync', async (page) => {
        await pollValue(() => field(page, 'controller.type'), (v) => v === 'pd', 'controller.type of the preset');
        await setField(page, 'duration', 1.5);
        await pollValue(() => jobJson(page), (d) => d.duration === 1.5, 'textarea#job-json duration after filling duration = 1.5');
        await setField(page, 'controller.kp', 80);
        await pollValue(() => jobJson(page), (d) => d.controller?.kp === 80, 'textarea#job-json controller.kp after filling 80');
        /* the reverse: an edit of the JSON shows in the fields */
        const doc = await jobJson(page);
        doc.duration = 0.75;
        doc.controller.kv = 15;
        await page.locator('textarea#job-json').fill(JSON.stringify(doc, null, 2));
        await pollValue(() => field(page, 'duration'), (v) => Number(v) === 0.75, 'duration field after editing the JSON');
        await pollValue(() => field(page, 'controller.kv'), (v) => Number(v) === 15, 'controller.kv field after editing the JSON');
    });
});

test('a preset submitted from the form shows its progress, then the job view of that job as entered', async () => {
    const before = (await listAll(srv)).length;
    await withView(browser, srv, '#/submit', 'submit-run', async (page) => {
        await pickPreset(page, 'triple_pendulum_pid', 'pid');
        /* about a second of work, so that there is progress to see */
        await setField(page, 'duration', 2);
        await setField(page, 'integrator.method', 'rk4');
        await setField(page, 'integrator.step', 0.00001);
        await pollValue(() => jobJson(page), (d) => d.integrator?.method === 'rk4' && d.integrator?.step === 0.00001, 'the JSON with rk4, step 1e-5');
        /* watch progress#submit-progress from the click on: whether it appears, its largest value */
        await page.evaluate(() => {
            window.__submitProgress = { seen: false, max: 0 };
            const look = () => {
                const p = document.querySelector('progress#submit-progress');
                if (!p) return;
                window.__submitProgress.seen = true;
                if (p.hasAttribute('value')) window.__submitProgress.max = Math.max(window.__submitProgress.max, p.value);
            };
            new MutationObserver(look).observe(document.documentElement, { subtree: true, childList: true, attributes: true });
        });
        await page.locator('button#submit-job').click();
        await poll(() => page.evaluate(() => /^#\/jobs\/[0-9]+$/.test(location.hash)), 'the address #/jobs/ID after submitting', 30000);
        const hash = await page.evaluate(() => location.hash);
        const id = Number(hash.split('/')[2]);
        await waitView(page, hash);
        const seen = await page.evaluate(() => window.__submitProgress);
        assert.ok(seen.seen, 'progress#submit-progress never appeared while the job ran');
        assert.match(await page.locator('#job-status').textContent(), /done/i);
        const job = await apiJob(srv, id);
        assert.equal(job.status, 'done');
        assert.equal(job.spec.duration, 2);
        assert.equal(job.spec.integrator.method, 'rk4');
        assert.equal(job.spec.integrator.step, 0.00001);
        assert.equal(job.spec.controller.type, 'pid');
        assert.equal(job.spec.controller.kp, 100);
        assert.equal((await listAll(srv)).length, before + 1, 'one job made');
    });
});

test('a bad gain is shown at the controller, a bad duration at its field; nothing is queued', async () => {
    const before = (await listAll(srv)).length;
    await withView(browser, srv, '#/submit?preset=triple_pendulum_pid', 'submit-error', async (page) => {
        await pollValue(() => field(page, 'controller.type'), (v) => v === 'pid', 'controller.type of the preset');
        await setField(page, 'controller.kp', -5);
        await page.locator('button#submit-job').click();
        /* the server says field "controller", message "kp must be positive and finite (got -5)" */
        const errs = await pollValue(
            () => fieldErrors(page),
            (e) => e.some((x) => (x.field === 'controller' || x.field === 'controller.kp') && x.text.includes('kp must be positive and finite (got -5)')),
            '.field-error[data-field="controller"] (or "controller.kp") with the server\'s message',
        );
        assert.equal(errs.length, 1, `one field error: ${JSON.stringify(errs)}`);
        assert.equal(await page.evaluate(() => location.hash), '#/submit?preset=triple_pendulum_pid', 'the page stays on the form');
        await screenshot(page, 'submit-error.png');

        /* validate: the duration's error next to its field, the gain's gone */
        await setField(page, 'controller.kp', 100);
        await setField(page, 'duration', -1);
        await page.locator('button#validate-job').click();
        await pollValue(
            () => fieldErrors(page),
            (e) => e.length === 1 && e[0].field === 'duration' && e[0].text.includes('must be positive (got -1 s)'),
            'only .field-error[data-field="duration"] with "must be positive (got -1 s)"',
        );
        const [err, input] = await Promise.all([
            page.locator('.field-error[data-field="duration"]').boundingBox(),
            page.locator('#view [name="duration"]').boundingBox(),
        ]);
        const gap = Math.max(0, err.y - (input.y + input.height), input.y - (err.y + err.height));
        assert.ok(gap < 80, `the duration's error is ${gap} px from its field`);
        await screenshot(page, 'submit-error-duration.png');

        /* fixed: no error left */
        await setField(page, 'duration', 1);
        await page.locator('button#validate-job').click();
        await pollValue(() => fieldErrors(page), (e) => e.length === 0, 'no .field-error once the job is valid');
        assert.equal((await listAll(srv)).length, before, 'a job was queued by an invalid submit or by validate');
    });
});

test('a job uploaded from a file fills the JSON and the form, and runs as the file says', async () => {
    const file = path.join(API_DIR, 'examples', 'spline_tracking.json');
    const doc = JSON.parse(await readFile(file, 'utf8'));
    doc.duration = Math.min(doc.duration ?? 1, 1);
    const small = path.join(tempDir('ctcsim-web-upload-'), 'job.json');
    await writeFile(small, JSON.stringify(doc, null, 2));
    await withView(browser, srv, '#/submit', 'submit-upload', async (page) => {
        await page.locator('input#job-file').setInputFiles(small);
        await pollValue(() => jobJson(page), (d) => d.name === doc.name, 'textarea#job-json after the upload');
        assert.deepEqual(await jobJson(page), doc, 'textarea#job-json against the file');
        await pollValue(() => field(page, 'controller.type'), (v) => v === doc.controller.type, 'controller.type after the upload');
        await page.locator('button#submit-job').click();
        await poll(() => page.evaluate(() => /^#\/jobs\/[0-9]+$/.test(location.hash)), 'the address #/jobs/ID after submitting', 30000);
        const hash = await page.evaluate(() => location.hash);
        await waitView(page, hash);
        const job = await apiJob(srv, Number(hash.split('/')[2]));
        assert.equal(job.name, doc.name);
        /* the whole job was sent, also what the form has no field for */
        /* (with the defaults the normalised job writes out: a continuous controller) */
        assert.deepEqual(job.spec.controller, {sample_period: 0, sample_delay: 0, seed: 0, ...doc.controller},
            'controller (per-joint poles, model error) as in the file');
        assert.deepEqual(job.spec.trajectory, doc.trajectory, 'the splines as in the file');
        assert.equal(job.spec.duration, doc.duration);
    });
});

test('a URDF file uploaded becomes a robot job that runs with its converted bodies', async () => {
    const urdf = `<?xml version="1.0"?>
<robot name="web_arm">
  <link name="base"/>
  <link name="upper"><inertial><origin xyz="0.5 0 0"/><mass value="1"/>
    <inertia ixx="1e-4" iyy="0.0833" izz="0.0833"/></inertial></link>
  <link name="fore"><inertial><origin xyz="0.5 0 0"/><mass value="1"/>
    <inertia ixx="1e-4" iyy="0.0833" izz="0.0833"/></inertial></link>
  <joint name="shoulder" type="continuous"><parent link="base"/><child link="upper"/><axis xyz="0 0 1"/></joint>
  <joint name="elbow" type="revolute"><parent link="upper"/><child link="fore"/><origin xyz="1 0 0"/><axis xyz="0 1 0"/></joint>
</robot>
`;
    const file = path.join(tempDir('ctcsim-web-urdf-'), 'arm.urdf');
    await writeFile(file, urdf);
    await withView(browser, srv, '#/submit', 'submit-urdf', async (page) => {
        await page.locator('input#job-file').setInputFiles(file);
        await pollValue(() => jobJson(page), (d) => d.name === 'web_arm', 'textarea#job-json after the URDF upload');
        const doc = await jobJson(page);
        assert.equal(doc.scene.urdf, urdf);
        assert.deepEqual(doc.trajectory, { type: 'min_jerk', from: 0, to: 0.2, start: 0, end: 2 });
        await page.locator('button#submit-job').click();
        await poll(() => page.evaluate(() => /^#\/jobs\/[0-9]+$/.test(location.hash)), 'the address #/jobs/ID after submitting', 30000);
        const hash = await page.evaluate(() => location.hash);
        await waitView(page, hash);
        const job = await apiJob(srv, Number(hash.split('/')[2]));
        assert.equal(job.name, 'web_arm');
        assert.equal(job.status, 'done');
        assert.deepEqual(job.spec.scene.bodies.map((b) => b.name), ['upper', 'fore']);
        assert.equal(job.spec.scene.urdf, undefined);
    });
});

test('keyboard: Tab reaches the nav links, the preset, the fields and both buttons', async () => {
    await withView(browser, srv, '#/submit?preset=triple_pendulum_pid', 'submit-keyboard', async (page) => {
        const r = await tabThrough(page, [
            'nav a[href="#/jobs"]',
            'nav a[href="#/submit"]',
            'nav a[href="#/compare"]',
            'select#preset',
            '[name="duration"]',
            '[name="controller.kp"]',
            'textarea#job-json',
            'button#validate-job',
            'button#submit-job',
        ]);
        assert.deepEqual(r.missed, [], `never focused by Tab; the order was ${r.order.join(' > ')}`);
    });
});
