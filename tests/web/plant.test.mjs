/*
 * plant.test.mjs - the job form's lab plant (web/jobform.js "Plant and sampling"): the torque
 * limit, friction, sensor noise, sample period and delay fields write their keys into the job
 * (and an emptied field removes its key), a job submitted from them runs with them (the stored
 * spec holds them, the metrics show the clipping and the error the sampling causes), and the
 * server's error about noise without a sample period is shown at the noise's field.
 */
import assert from 'node:assert/strict';
import { after, before, test } from 'node:test';

import { apiJob, launchBrowser, listAll, poll, pollValue, screenshot, startWebServer, waitView, withView } from './lib.mjs';

let srv;
let browser;

before(async () => {
    srv = await startWebServer();
    browser = await launchBrowser();
});

after(async () => {
    await browser?.close();
    await srv?.stop();
});

const field = (page, name) =>
    page.evaluate((n) => document.querySelector(`#view [name="${n}"]`)?.value ?? null, name);

const jobJson = (page) =>
    page.evaluate(() => {
        try {
            return JSON.parse(document.querySelector('textarea#job-json').value);
        } catch {
            return {};
        }
    });

const fill = (page, name, value) => page.locator(`#view [name="${name}"]`).first().fill(String(value));

const fieldErrors = (page) =>
    page.evaluate(() =>
        [...document.querySelectorAll('.field-error[data-field]')]
            .filter((e) => e.offsetParent !== null && e.textContent.trim() !== '')
            .map((e) => ({ field: e.getAttribute('data-field'), text: e.textContent.trim() })),
    );

test('the plant fields write the job; a run from them is limited and sampled', async () => {
    await withView(browser, srv, '#/submit?preset=triple_pendulum_pid', 'plant-form', async (page) => {
        await pollValue(() => field(page, 'controller.type'), (v) => v === 'pid', 'controller.type of the preset');
        for (const name of ['plant.torque_limit', 'plant.viscous', 'plant.coulomb', 'plant.coulomb_velocity',
            'plant.noise_q', 'plant.noise_v', 'controller.sample_period', 'controller.sample_delay']) {
            assert.equal(await field(page, name), '', `${name}: an empty field, the term off`);
        }
        await fill(page, 'duration', 1);
        await fill(page, 'plant.torque_limit', 100);
        await fill(page, 'plant.viscous', 0.3);
        await fill(page, 'controller.sample_period', 0.02);
        await fill(page, 'controller.sample_delay', 1);
        const doc = await pollValue(() => jobJson(page),
            (d) => d.plant?.torque_limit === 100 && d.plant?.viscous === 0.3 &&
                d.controller?.sample_period === 0.02 && d.controller?.sample_delay === 1,
            'textarea#job-json with the plant and the sampling');
        assert.deepEqual(Object.keys(doc.plant).sort(), ['torque_limit', 'viscous'], 'only the terms given');
        /* emptied, a field removes its key */
        await fill(page, 'plant.viscous', '');
        await pollValue(() => jobJson(page), (d) => d.plant && !('viscous' in d.plant), 'plant.viscous removed');
        await screenshot(page, 'plant-form.png');

        await page.locator('button#submit-job').click();
        await poll(() => page.evaluate(() => /^#\/jobs\/[0-9]+$/.test(location.hash)), 'the job view after submitting', 30000);
        const hash = await page.evaluate(() => location.hash);
        await waitView(page, hash);
        const job = await apiJob(srv, Number(hash.split('/')[2]));
        assert.equal(job.status, 'done');
        assert.equal(job.spec.plant.torque_limit, 100);
        assert.equal(job.spec.controller.sample_period, 0.02);
        assert.equal(job.spec.controller.sample_delay, 1);
        const m = job.metrics;
        assert.ok(m.sat_fraction[0] > 0, `joint 0 is clipped: sat_fraction ${m.sat_fraction}`);
        assert.ok(m.error_by_cause.sampling.every((x) => x > 0), `sampling causes error: ${JSON.stringify(m.error_by_cause)}`);
    });
});

test('noise without a sample period is refused at the noise field; nothing is queued', async () => {
    const before = (await listAll(srv)).length;
    await withView(browser, srv, '#/submit?preset=triple_pendulum_pd', 'plant-error', async (page) => {
        await pollValue(() => field(page, 'controller.type'), (v) => v === 'pd', 'controller.type of the preset');
        await fill(page, 'plant.noise_q', 0.001);
        await pollValue(() => jobJson(page), (d) => d.plant?.noise_q === 0.001, 'textarea#job-json plant.noise_q');
        await page.locator('button#submit-job').click();
        const errs = await pollValue(() => fieldErrors(page),
            (e) => e.some((x) => x.field === 'plant.noise_q' && x.text.includes('needs a sampled controller')),
            '.field-error[data-field="plant.noise_q"] with the server\'s message');
        assert.equal(errs.length, 1, `one field error: ${JSON.stringify(errs)}`);
        await screenshot(page, 'plant-error.png');
    });
    assert.equal((await listAll(srv)).length, before, 'nothing queued');
});
