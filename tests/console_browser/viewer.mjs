// The console's 3D view in a real browser (Debian's chromium through
// playwright-core): a capture with a reconstruction, its ground truth and a
// 10-frame simulation is opened from the archive; the canvas must draw the
// hair, turn with the mouse, show the truth when asked and play the
// simulation. Each step is checked on the canvas's pixels and saved as a
// screenshot.
//   node viewer.mjs URL SCREENSHOT_DIR CAPTURE_ID
import { launchChromium, stepper } from './browser.mjs';

const [url, shots, captureId] = process.argv.slice(2);
const BACKGROUND = [0x15, 0x18, 0x1d];  // viewer.js
const LOAD_TIMEOUT_MS = 5 * 60 * 1000;  // a liveness bound: software WebGL under sanitizers is slow

const browser = await launchChromium({ webgl: true });  // no GPU here: SwiftShader
const page = await browser.newPage({ viewport: { width: 1440, height: 1100 } });
const pageErrors = [];
page.on('pageerror', (err) => pageErrors.push(String(err)));

// The 3D view's box in the viewport, scrolled into it (a clip is taken from
// the viewport; an element screenshot would wait for the element to be still,
// which a playing simulation never is).
async function viewerBox() {
  await page.locator('#viewer').scrollIntoViewIfNeeded();
  return page.locator('#viewer').boundingBox();
}

const step = stepper(page, shots, {
  prefix: 'viewer-',
  screenshot: async (file) => page.screenshot({ path: file, clip: await viewerBox() }),
});

// The canvas's pixels after the next drawn frame: how many differ from the
// background, how many are mostly green (the truth's colour), and a digest
// to tell two pictures apart.
async function canvasPixels() {
  return page.evaluate((background) => {
    const viewer = window.hairrigViewer;
    // Drawn and read in one task: the canvas keeps no picture once composited.
    viewer.draw();
    const gl = viewer.renderer.getContext();
    const w = gl.drawingBufferWidth, h = gl.drawingBufferHeight;
    const px = new Uint8Array(4 * w * h);
    gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px);
    let drawn = 0, green = 0, digest = 0;
    for (let i = 0; i < px.length; i += 4) {
      const [r, g, b] = [px[i], px[i + 1], px[i + 2]];
      if (Math.abs(r - background[0]) + Math.abs(g - background[1]) + Math.abs(b - background[2]) > 24) {
        drawn += 1;
        digest = (digest * 31 + (i >> 2) + r + 3 * g + 7 * b) >>> 0;
      }
      if (g > 120 && g > r + 60 && g > b + 30) green += 1;
    }
    return { drawn, green, digest, total: w * h };
  }, BACKGROUND);
}

const differs = (a, b) => a.digest !== b.digest || Math.abs(a.drawn - b.drawn) > 0;

try {
  let shown;
  await step('opened', async () => {
    await page.goto(url);
    const row = page.locator(`#archive tr[data-capture="${captureId}"]`);
    await row.waitFor({ timeout: 60_000 });
    await row.locator('button.open').click();
    await page.waitForFunction(
      () => window.hairrigViewer?.firstFrameAt != null && !document.querySelector('#viewer').hidden,
      null, { timeout: LOAD_TIMEOUT_MS });
    const status = await page.locator('#viewer-status').innerText();
    if (!status.startsWith('simulation "head-shake"')) throw new Error(`viewer status: ${status}`);
    shown = await canvasPixels();
    // The hair and head fill a visible part of the canvas, not a speck or all of it.
    const share = shown.drawn / shown.total;
    if (!(share > 0.03 && share < 0.9)) throw new Error(`${(100 * share).toFixed(1)} % of the canvas drawn`);
    const figures = await page.locator('#reconstruction-figures').innerText();
    if (!/oriented points/.test(figures) || !/strands/.test(figures))
      throw new Error(`the reconstruction's figures are not beside the view: "${figures}"`);
    if (await page.locator('#show-truth').isDisabled()) throw new Error('no ground truth to toggle');
  });

  await step('turned', async () => {
    const box = await page.locator('#viewer-canvas').boundingBox();
    const [x, y] = [box.x + box.width / 2, box.y + box.height / 2];
    await page.mouse.move(x, y);
    await page.mouse.down();
    await page.mouse.move(x + 300, y, { steps: 12 });
    await page.mouse.up();
    const turned = await canvasPixels();
    if (!differs(turned, shown)) throw new Error('the picture did not change when dragged');
    // Once the drag ends, every strand is drawn again (the coarse set only while moving).
    const parts = await page.evaluate(() => ({
      full: window.hairrigViewer.parts.strands.visible,
      coarse: window.hairrigViewer.coarse?.visible ?? false,
    }));
    if (!parts.full || parts.coarse) throw new Error(`after the drag: ${JSON.stringify(parts)}`);
    if (turned.drawn / turned.total < 0.03) throw new Error('the hair left the view when turned');
    shown = turned;
  });

  await step('truth', async () => {
    await page.check('#show-truth');
    const withTruth = await canvasPixels();
    if (!(withTruth.green > shown.green + 500))
      throw new Error(`the truth drew ${withTruth.green - shown.green} green pixels`);
  });

  await step('truth-hidden', async () => {
    await page.uncheck('#show-truth');
    const without = await canvasPixels();
    if (without.green > shown.green + 100) throw new Error('the truth stayed after it was turned off');
  });

  await step('by-wisp', async () => {
    await page.selectOption('#colour-by', 'wisp');  // fails if disabled: the export found no wisps
    const byWisp = await canvasPixels();
    if (!differs(byWisp, shown)) throw new Error('colouring by wisp did not change the picture');
    shown = byWisp;
  });

  await step('points-by-strand', async () => {
    await page.selectOption('#colour-by', 'strand');
    const recoloured = await canvasPixels();
    if (!differs(recoloured, shown)) throw new Error('colouring by strand did not change the picture');
    await page.check('#show-points');
    const withPoints = await canvasPixels();
    if (!differs(withPoints, recoloured)) throw new Error('the points did not change the picture');
    shown = withPoints;
  });

  await step('simulation', async () => {
    await page.click('#play-simulation');
    const frames = new Set();
    const deadline = Date.now() + 60_000;
    while (frames.size < 3 && Date.now() < deadline) {
      frames.add(await page.evaluate(() => window.hairrigViewer.shownFrame()));
      await page.waitForTimeout(40);
    }
    frames.delete(-1);
    if (frames.size < 3) throw new Error(`the simulation showed frames ${[...frames]}`);
    if ((await page.locator('#play-simulation').innerText()) !== 'Stop simulation')
      throw new Error('the play button does not offer to stop');
  });

  await step('stopped', async () => {
    await page.click('#play-simulation');
    const parts = await page.evaluate(() => ({
      playing: window.hairrigViewer.playing,
      strands: window.hairrigViewer.parts.strands.visible,
      simulation: window.hairrigViewer.parts.simulation.visible,
    }));
    if (parts.playing || !parts.strands || parts.simulation)
      throw new Error(`after stopping: ${JSON.stringify(parts)}`);
  });

  if (pageErrors.length) throw new Error(`errors in the page: ${pageErrors.join('; ')}`);
  console.log('console viewer test: all steps passed');
} finally {
  await browser.close();
}
