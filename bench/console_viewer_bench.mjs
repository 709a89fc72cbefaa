// One opening of a capture's 3D view in chromium (bench/console_viewer_bench.sh):
// prints JSON with the time from "Open" to the model's first frame and the
// frame rate while the camera orbits for 5 s (as a drag does: the coarse
// strands while moving), then 5 s more drawing every strand; screenshots of the view opened,
// orbited, and with the ground truth shown.
//   node console_viewer_bench.mjs URL CAPTURE_ID SCREENSHOT_PREFIX
// chromium as the console's browser tests start it (playwright-core as
// scripts/install-deps --tests installs it in tests/console_browser).
import { launchChromium } from '../tests/console_browser/browser.mjs';

const [url, captureId, shot] = process.argv.slice(2);
const ORBIT_MS = 5000;
const browser = await launchChromium({ webgl: true });
try {
  const page = await browser.newPage({ viewport: { width: 1440, height: 1100 } });
  await page.goto(url);
  const row = page.locator(`#archive tr[data-capture="${captureId}"]`);
  await row.waitFor({ timeout: 60_000 });
  const clickedAt = await page.evaluate(() => performance.now());
  await row.locator('button.open').click();
  await page.waitForFunction(() => window.hairrigViewer?.firstFrameAt != null, null,
                             { timeout: 120_000 });
  const firstFrameAt = await page.evaluate(() => window.hairrigViewer.firstFrameAt);
  const viewerBox = async () => {
    await page.locator('#viewer').scrollIntoViewIfNeeded();
    return page.locator('#viewer').boundingBox();
  };
  const shoot = async (name) => page.screenshot({
    path: `${shot}-${name}.png`, clip: await viewerBox() });
  await shoot('opened');
  const intervals = await page.evaluate((ms) => window.hairrigViewer.orbitFor(ms), ORBIT_MS);
  await shoot('orbited');
  const fullIntervals = await page.evaluate(
    (ms) => window.hairrigViewer.orbitFor(ms, { fullDetail: true }), ORBIT_MS);
  const fps = (iv) => (1000 * iv.length) / iv.reduce((a, b) => a + b, 0);
  const playIntervals = await page.evaluate((ms) => window.hairrigViewer.playFor(ms), ORBIT_MS);
  await page.check('#show-truth');
  await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
  await shoot('truth');
  const sorted = [...intervals].sort((a, b) => a - b);
  console.log(JSON.stringify({
    first_frame_ms: firstFrameAt - clickedAt,
    orbit_frames: intervals.length,
    orbit_fps: fps(intervals),
    orbit_fps_full_detail: fps(fullIntervals),
    play_fps: playIntervals.length > 0 ? fps(playIntervals) : null,
    software_renderer: await page.evaluate(() => window.hairrigViewer.software),
    interval_ms_p95: sorted[Math.floor(0.95 * (sorted.length - 1))],
  }));
} finally {
  await browser.close();
}
