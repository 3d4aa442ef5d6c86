// Usage: node test/check_report.mjs REPORT.html SCREENSHOT.png [viewport]
// Opens the report in headless Chromium (software WebGL), waits for the viewer,
// checks that it draws something and that the animation changes the picture.
// Prints one JSON line; exit 0 only when every check passes.
import { resolve } from 'node:path';
import { pathToFileURL } from 'node:url';
import { chromium } from 'playwright-core';
import { CHROMIUM_ARGS } from './chromium.mjs';

// Luminance variance of the frame at t=0 (0-255 scale). A canvas cleared to the
// flat background gives exactly 0; the test fixture gives ~830, and a face over
// 15% of the frame, 30 levels off the background, still gives ~100. 25 (σ = 5
// levels) rejects blank or near-blank frames without depending on the texture.
const MIN_VARIANCE = 25;
// Mean absolute RGB difference (0-255) between t=0 and the most different of
// t = 0.25, 0.5, 0.75 × duration. Identical frames give 0 exactly (deterministic
// software rendering); a head that turns or a jaw that opens moves thousands of
// pixels, giving several levels. 0.5 means "clearly more than noise".
const MIN_DIFFERENCE = 0.5;
const READY_TIMEOUT_MS = 60_000;

const [reportPath, screenshotPath, screenshotMode] = process.argv.slice(2);
// 'viewport': only the first screenful (for the README); default: the whole page.
const fullPage = screenshotMode !== 'viewport';
if (!reportPath || !screenshotPath) {
  console.error('usage: node test/check_report.mjs REPORT.html SCREENSHOT.png [viewport]');
  process.exit(2);
}

const consoleErrors = [];
const pageErrors = [];
const failedRequests = [];
const result = { consoleErrors, pageErrors, failedRequests };
const problems = [];
const started = Date.now();

// playwright-core passes its own fresh temporary --user-data-dir per launch.
const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
  args: CHROMIUM_ARGS,
  timeout: 60_000,
});
try {
  const page = await browser.newPage({ viewport: { width: 1280, height: 800 }, deviceScaleFactor: 1 });
  page.on('console', (msg) => {
    if (msg.type() === 'error') consoleErrors.push(msg.text());
  });
  page.on('pageerror', (err) => pageErrors.push(String(err && err.stack ? err.stack : err)));
  page.on('requestfailed', (req) =>
    failedRequests.push(`${req.url().slice(0, 120)}: ${req.failure()?.errorText}`),
  );

  await page.goto(pathToFileURL(resolve(reportPath)).href, { waitUntil: 'load' });
  // Boolean, not the promise itself: waitForFunction would await a promise.
  await page.waitForFunction(() => !!(window.visageViewer && window.visageViewer.ready), null, {
    timeout: 10_000,
  });
  // Await the viewer's own promise in the page; a rejection comes back as an error.
  await page.evaluate(
    (ms) =>
      Promise.race([
        window.visageViewer.ready.then(() => undefined),
        new Promise((_, rej) => setTimeout(() => rej(new Error(`viewer not ready after ${ms} ms`)), ms)),
      ]),
    READY_TIMEOUT_MS,
  );
  result.readyMs = Date.now() - started;

  Object.assign(
    result,
    await page.evaluate(() => {
      const v = window.visageViewer;
      const src = v.canvas;
      const grab = () => {
        // Copy the WebGL canvas (preserveDrawingBuffer) into a 2-D canvas to read it.
        const c = document.createElement('canvas');
        c.width = src.width;
        c.height = src.height;
        const ctx = c.getContext('2d', { willReadFrequently: true });
        ctx.drawImage(src, 0, 0);
        return ctx.getImageData(0, 0, c.width, c.height).data;
      };
      const variance = (px) => {
        let sum = 0;
        let sum2 = 0;
        const n = px.length / 4;
        for (let i = 0; i < px.length; i += 4) {
          const y = 0.2126 * px[i] + 0.7152 * px[i + 1] + 0.0722 * px[i + 2];
          sum += y;
          sum2 += y * y;
        }
        const mean = sum / n;
        return sum2 / n - mean * mean;
      };
      const meanAbsDiff = (a, b) => {
        let d = 0;
        let n = 0;
        for (let i = 0; i < a.length; i += 4) {
          d += Math.abs(a[i] - b[i]) + Math.abs(a[i + 1] - b[i + 1]) + Math.abs(a[i + 2] - b[i + 2]);
          n += 3;
        }
        return d / n;
      };
      v.setTime(0);
      const first = grab();
      const differences = [0.25, 0.5, 0.75].map((f) => {
        v.setTime(v.duration * f);
        return meanAbsDiff(first, grab());
      });
      v.setTime(v.duration * 0.5); // screenshot shows mid-animation
      return {
        variance: variance(first),
        difference: Math.max(...differences),
        differences,
        duration: v.duration,
        width: src.width,
        height: src.height,
      };
    }),
  );
} catch (err) {
  problems.push(`viewer failed: ${err && err.message ? err.message.split('\n')[0] : err}`);
}
try {
  // Also on failure: the picture shows the viewer's red error message.
  const [page] = browser.contexts().flatMap((c) => c.pages());
  if (page) await page.screenshot({ path: screenshotPath, fullPage });
  else problems.push('no page to screenshot');
} catch (err) {
  problems.push(`screenshot failed: ${err && err.message ? err.message.split('\n')[0] : err}`);
} finally {
  await browser.close();
}

result.elapsedMs = Date.now() - started;
if (consoleErrors.length) problems.push(`${consoleErrors.length} console error(s)`);
if (pageErrors.length) problems.push(`${pageErrors.length} uncaught page error(s)`);
if (failedRequests.length) problems.push(`${failedRequests.length} failed request(s)`);
if (result.variance !== undefined && !(result.variance > MIN_VARIANCE))
  problems.push(`canvas looks blank: luminance variance ${result.variance.toFixed(2)} <= ${MIN_VARIANCE}`);
if (result.difference !== undefined && !(result.difference > MIN_DIFFERENCE))
  problems.push(`animation does not change the picture: difference ${result.difference.toFixed(3)} <= ${MIN_DIFFERENCE}`);

console.log(JSON.stringify(result));
if (problems.length) {
  console.error(`check_report: FAIL: ${problems.join('; ')}`);
  process.exit(1);
}
