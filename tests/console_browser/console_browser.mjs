// The operator console in a real browser (Debian's chromium through
// playwright-core): the steps a lab operator takes on the default simulated
// rig, each checked on the page and saved as a screenshot.
//   node console_browser.mjs URL SCREENSHOT_DIR
import { launchChromium, stepper } from './browser.mjs';

const [url, shots] = process.argv.slice(2);
const CAPTURE_TIMEOUT_MS = 15 * 60 * 1000;  // a liveness bound: sanitizer builds render slowly

const browser = await launchChromium();
const page = await browser.newPage({ viewport: { width: 1440, height: 1100 } });
page.on('dialog', (dialog) => dialog.accept());
const consoleErrors = [];
page.on('pageerror', (err) => consoleErrors.push(String(err)));

const step = stepper(page, shots, {
  // The sticky header at the top of the picture.
  beforeShot: () => page.evaluate(() => window.scrollTo(0, 0)),
  screenshot: (file) => page.screenshot({ path: file, fullPage: true }),
});

const text = (selector) => page.locator(selector).innerText();
const waitText = (selector, expected, timeout = 60_000) =>
  page.waitForFunction(([s, e]) => document.querySelector(s)?.textContent?.trim() === e,
                       [selector, expected], { timeout });
const thumbCount = () => page.locator('#thumbnails img.thumb').count();
const api = async (p) => (await page.request.get(new URL(p, url).toString())).json();

try {
  await step('live-view', async () => {
    await page.goto(url);
    await waitText('#connection', 'live');
    for (const camera of ['upper', 'lower']) {
      // A preview image that has loaded a frame, twice (the view is live, not a still).
      const img = page.locator(`#live .camera[data-camera="${camera}"] img.preview`);
      await page.waitForFunction((el) => el.complete && el.naturalWidth > 0, await img.elementHandle(),
                                 { timeout: 120_000 });
      const first = await img.getAttribute('src');
      await page.waitForFunction(([el, src]) => el.getAttribute('src') !== src && el.naturalWidth > 0,
                                 [await img.elementHandle(), first], { timeout: 60_000 });
    }
    const rows = await page.locator('#devices tbody tr').count();
    if (rows !== 7) throw new Error(`${rows} device rows, expected 7`);
    if (!(await text('#plan-summary')).startsWith('38 views, 19 stops'))
      throw new Error(`plan summary: ${await text('#plan-summary')}`);
  });

  // The mean luminance of each camera's newest live frame, from its histogram (64 bins of 4 levels).
  const liveLuminance = async () => {
    const { cameras } = await api('/api/cameras');
    return cameras.map((c) => {
      const bins = c.live?.histogram ?? [];
      const total = bins.reduce((a, b) => a + b, 0);
      return total ? bins.reduce((a, count, i) => a + count * (4 * i + 2), 0) / total : 0;
    });
  };

  await step('control-and-lights', async () => {
    await page.click('#take-control');
    await waitText('#control-status', 'You control the rig');
    if (await page.locator('#start-capture').isDisabled()) throw new Error('start stays disabled');
    const dark = await liveLuminance();
    await page.check('#light-top');
    await page.check('#light-bottom');
    const deadline = Date.now() + 60_000;
    let lit = await liveLuminance();
    while (!lit.every((l, i) => l > dark[i] + 20) && Date.now() < deadline) {
      await page.waitForTimeout(250);
      lit = await liveLuminance();
    }
    if (!lit.every((l, i) => l > dark[i] + 20))
      throw new Error(`the live views did not brighten with the lights: ${dark} -> ${lit}`);
    await page.waitForTimeout(1000);  // the lit frames on the page
  });

  await step('capture-running', async () => {
    await page.fill('#subject', 'wig browser');
    await page.click('#start-capture');
    await page.waitForFunction(() => document.querySelectorAll('#thumbnails img.thumb').length >= 8,
                               null, { timeout: CAPTURE_TIMEOUT_MS });
    const eta = await text('#eta');
    if (!/^ETA \d/.test(eta)) throw new Error(`ETA shows "${eta}"`);
  });

  await step('capture-complete', async () => {
    await waitText('#progress-text', '38 / 38 views', CAPTURE_TIMEOUT_MS);
    await page.waitForFunction(() => document.querySelectorAll('#thumbnails img.thumb').length === 38,
                               null, { timeout: 60_000 });
    await page.waitForFunction(
      () => [...document.querySelectorAll('#thumbnails img.thumb')].every((i) => i.naturalWidth > 0),
      null, { timeout: 60_000 });
  });

  await step('calibration-verdict', async () => {
    await waitText('#verdict', 'good', CAPTURE_TIMEOUT_MS);
    await page.waitForFunction(() => document.querySelectorAll('#residuals img').length === 38,
                               null, { timeout: 60_000 });
    await page.locator('#residuals').scrollIntoViewIfNeeded();
    await page.waitForFunction(
      () => [...document.querySelectorAll('#residuals img')].every((i) => i.complete && i.naturalWidth > 0),
      null, { timeout: 60_000 });
  });

  let stoppedId = '';
  await step('estop', async () => {
    await waitText('#busy', 'idle', CAPTURE_TIMEOUT_MS);
    await page.fill('#subject', 'wig estop');
    await page.uncheck('#calibrate');
    await page.click('#start-capture');
    // Mid-sweep: the turntable on its way to the fourth of nineteen stops.
    await page.waitForFunction(
      () => /^stop ([4-9]|1[0-5]) of 19$/.test(document.querySelector('#current-stop').textContent),
      null, { timeout: CAPTURE_TIMEOUT_MS });
    await page.click('#estop');
    await waitText('#capture-status', 'stopped', 120_000);
    if (await page.locator('#estop-banner').isHidden()) throw new Error('no e-stop banner');
    const state = await api('/api/state');
    stoppedId = state.capture.id;
    const angle = state.turntable.angle_deg;
    await page.waitForTimeout(500);
    const later = (await api('/api/state')).turntable.angle_deg;
    if (Math.abs(later - angle) > 1e-6) throw new Error(`turntable still moving: ${angle} -> ${later}`);
    if (Object.values(state.lights).some(Boolean)) throw new Error('a light is still on');
    await page.locator(`#archive tr[data-capture="${stoppedId}"] .status`).waitFor();
    if ((await text(`#archive tr[data-capture="${stoppedId}"] .status`)) !== 'stopped')
      throw new Error('the archive does not mark the capture stopped');
    const views = await text(`#archive tr[data-capture="${stoppedId}"] .views`);
    if (!(parseInt(views, 10) < 38)) throw new Error(`the e-stop came after the sweep: ${views} views`);
  });

  await step('resumed', async () => {
    await page.click('#estop-release');
    await page.waitForFunction(() => document.querySelector('#estop-banner').hidden, null,
                               { timeout: 30_000 });
    const row = page.locator(`#archive tr[data-capture="${stoppedId}"]`);
    await row.locator('button.resume').click();
    await waitText('#progress-text', '38 / 38 views', CAPTURE_TIMEOUT_MS);
    await waitText('#capture-status', 'complete', CAPTURE_TIMEOUT_MS);
    await waitText('#busy', 'idle', CAPTURE_TIMEOUT_MS);
    await page.waitForFunction(
      (id) => document.querySelector(`#archive tr[data-capture="${id}"] .status`)?.textContent === 'complete',
      stoppedId, { timeout: 60_000 });
  });

  await step('control-released', async () => {
    await page.click('#release-control');
    await page.waitForFunction(() => document.querySelector('#control-status')?.dataset.mine === 'false',
                               null, { timeout: 30_000 });
    const { control } = await api('/api/state');
    if (control.holder !== null) throw new Error(`the server still names a holder: ${control.holder}`);
  });

  if (consoleErrors.length) throw new Error(`errors in the page: ${consoleErrors.join('; ')}`);
  console.log('console browser test: all steps passed');
} finally {
  await browser.close();
}
