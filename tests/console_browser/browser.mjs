// What the console's browser tests share (console_browser.mjs, viewer.mjs):
// Debian's chromium started through playwright-core, and named steps that
// each save a screenshot (a -FAILED one when the step throws).
import { chromium } from 'playwright-core';
import path from 'node:path';

// `webgl`: draw WebGL in software (SwiftShader), for the 3D view on a
// machine without a GPU; otherwise the GPU is off altogether.
export function launchChromium({ webgl = false } = {}) {
  const gpu = webgl
    ? ['--use-gl=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist']
    : ['--disable-gpu'];
  return chromium.launch({
    executablePath: '/usr/bin/chromium',
    args: ['--no-sandbox', ...gpu, '--disable-quic', '--no-first-run',
           '--disable-background-networking', '--disable-component-update', '--disable-sync'],
  });
}

// step(name, action): runs `action`, then saves SHOTS/<prefix>NN-<name>.png
// by `screenshot(file)`; a failing action saves <...>-FAILED.png (the whole
// page) and throws naming the step.
export function stepper(page, shots, { prefix = '', screenshot, beforeShot } = {}) {
  let stepNumber = 0;
  return async function step(name, action) {
    stepNumber += 1;
    const file = path.join(shots, `${prefix}${String(stepNumber).padStart(2, '0')}-${name}.png`);
    const started = Date.now();
    try {
      await action();
    } catch (err) {
      await page.screenshot({ path: file.replace('.png', '-FAILED.png'), fullPage: true });
      throw new Error(`step ${stepNumber} (${name}) failed: ${err.message}`);
    }
    if (beforeShot) await beforeShot();
    await screenshot(file);
    console.log(`ok ${stepNumber} ${name} (${((Date.now() - started) / 1000).toFixed(1)} s)`);
  };
}
