// Usage: node test/check_live.mjs PAGE_URL OTHER_ORIGIN_URL SCREENSHOT.png
// Opens the page of a running `visage live --listen` in headless Chromium (software WebGL),
// waits for frames, checks that the face's canvas changes between two moments and that the
// page reports a frame rate; then, from a page of another origin (the same server under
// another name: http://localhost:PORT/ against http://127.0.0.1:PORT/), opens a WebSocket to
// the first origin's socket, which the server must refuse.
// Prints one JSON line; exit 0 only when every check passes.
import { chromium } from 'playwright-core';
import { CHROMIUM_ARGS } from './chromium.mjs';

const FRAMES_TIMEOUT_MS = 60_000;
// Mean absolute grey-level difference (0-255) between two 64×48 pictures of the face's canvas
// taken a second apart: a moving face changes hundreds of pixels; identical pictures give 0.
const MIN_DIFFERENCE = 0.2;
const MIN_VARIANCE = 25;

const [pageUrl, otherUrl, screenshotPath] = process.argv.slice(2);
if (!pageUrl || !otherUrl || !screenshotPath) {
  console.error('usage: node test/check_live.mjs PAGE_URL OTHER_ORIGIN_URL SCREENSHOT.png');
  process.exit(2);
}

const consoleErrors = [];
const pageErrors = [];
const result = { consoleErrors, pageErrors };
const problems = [];

const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
  args: CHROMIUM_ARGS,
  timeout: 60_000,
});
try {
  const page = await browser.newPage({ viewport: { width: 900, height: 900 }, deviceScaleFactor: 1 });
  page.on('console', (msg) => {
    if (msg.type() === 'error') consoleErrors.push(msg.text());
  });
  page.on('pageerror', (err) => pageErrors.push(String(err && err.stack ? err.stack : err)));
  await page.goto(pageUrl, { waitUntil: 'load' });
  await page.waitForFunction(() => window.visageLive && window.visageLive.frames >= 10 && window.visageLive.face, null, {
    timeout: FRAMES_TIMEOUT_MS,
  });
  const first = await page.evaluate(() => window.visageLive.snapshot());
  await page.waitForTimeout(1000);
  const second = await page.evaluate(() => window.visageLive.snapshot());
  const mean = first.reduce((a, b) => a + b, 0) / first.length;
  result.variance = first.reduce((a, b) => a + (b - mean) ** 2, 0) / first.length;
  result.difference = first.reduce((a, b, i) => a + Math.abs(b - second[i]), 0) / first.length;
  result.stats = await page.evaluate(() => document.getElementById('stats').textContent);
  const fps = /([0-9.]+) fps/.exec(result.stats);
  result.fps = fps ? Number(fps[1]) : null;
  result.frames = await page.evaluate(() => window.visageLive.frames);
  await page.screenshot({ path: screenshotPath, fullPage: true });
  if (result.variance < MIN_VARIANCE) problems.push(`the face's canvas looks blank (variance ${result.variance})`);
  if (result.difference < MIN_DIFFERENCE) problems.push(`the face's canvas did not change (${result.difference})`);
  if (!(result.fps > 0)) problems.push(`no frame rate on the page: "${result.stats}"`);

  // Another origin asks for the first one's socket.
  const other = await browser.newPage();
  await other.goto(otherUrl, { waitUntil: 'load' });
  const target = new URL(pageUrl);
  result.crossOrigin = await other.evaluate(
    (url) =>
      new Promise((resolve) => {
        const socket = new WebSocket(url);
        socket.onopen = () => resolve('opened');
        socket.onerror = () => resolve('refused');
        setTimeout(() => resolve('no answer'), 10_000);
      }),
    `ws://${target.host}/socket`,
  );
  if (result.crossOrigin !== 'refused') problems.push(`a cross-origin WebSocket was ${result.crossOrigin}`);
  if (consoleErrors.length) problems.push('console errors');
  if (pageErrors.length) problems.push('page errors');
} catch (err) {
  problems.push(String(err && err.message ? err.message : err));
} finally {
  await browser.close();
}
result.problems = problems;
console.log(JSON.stringify(result));
process.exit(problems.length ? 1 : 0);
