// One capture through the console in chromium (bench/console_bench.sh): the
// live view's rate, then a capture with the page open; prints JSON with the
// capture's wall time, each view's delay from frame_stored to its thumbnail
// loaded in the page, and the live frames per second per camera.
import fs from 'node:fs';
import { createRequire } from 'node:module';
import path from 'node:path';

// playwright-core as tests/console_browser installs it (scripts/install-deps).
const here = path.dirname(new URL(import.meta.url).pathname);
const require = createRequire(path.join(here, '../tests/console_browser/package.json'));
const { chromium } = require('playwright-core');

const [url, captures] = process.argv.slice(2);
const browser = await chromium.launch({
  executablePath: '/usr/bin/chromium',
  args: ['--no-sandbox', '--disable-gpu', '--no-first-run', '--disable-background-networking',
         '--disable-component-update', '--disable-sync'],
});
try {
  const page = await browser.newPage();
  await page.goto(url);
  await page.waitForFunction(() => document.querySelector('#connection').textContent === 'live');
  // Each thumbnail's load time, in the page's wall clock (the journal's clock: the same machine).
  await page.evaluate(() => {
    window.thumbLoaded = {};
    new MutationObserver(() => {
      for (const img of document.querySelectorAll('#thumbnails img.thumb')) {
        if (img.dataset.timed) continue;
        img.dataset.timed = '1';
        img.addEventListener('load', () => { window.thumbLoaded[img.dataset.view] = Date.now(); });
      }
    }).observe(document.querySelector('#thumbnails'), { childList: true });
  });
  await page.waitForTimeout(10_000);
  const cameras = await (await page.request.get(new URL('/api/cameras', url).toString())).json();
  const liveFps = Object.fromEntries(cameras.cameras.map((c) => [c.name, c.live?.fps ?? 0]));
  await page.click('#take-control');
  await page.fill('#subject', 'bench');
  await page.uncheck('#calibrate');
  await page.click('#start-capture');
  await page.waitForFunction(() => document.querySelector('#capture-status').textContent === 'complete',
                             null, { timeout: 30 * 60_000 });
  const loaded = await page.evaluate(() => window.thumbLoaded);
  const state = await (await page.request.get(new URL('/api/state', url).toString())).json();
  const journal = fs.readFileSync(path.join(captures, state.capture.id, 'journal.jsonl'), 'utf8')
    .trim().split('\n').map((line) => JSON.parse(line));
  const latency = journal.filter((r) => r.event === 'frame_stored' && loaded[r.view])
    .map((r) => loaded[r.view] - Date.parse(r.time_utc));
  console.log(JSON.stringify({ wall_s: state.capture.wall_s, view_latency_ms: latency,
                               live_fps: liveFps }));
} finally {
  await browser.close();
}
