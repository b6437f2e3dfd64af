// Opens a satmesh job viewer in headless Chromium (Debian's, through puppeteer-core) and
// checks what a person would see: every tile loaded, no console error, no request off the
// page's origin (no network at run time), and shaded relief: the luminance spread of the
// city's pixels when lit, against the same view unlit (a flat silhouette).
//   node web/tools/viewer-check.mjs URL EXPECTED_TILES [SCREENSHOT.png]
// Prints one JSON line of measurements; exits 1 with the reason when a check fails.
import { createRequire } from 'node:module';

const puppeteer = createRequire(import.meta.url)('puppeteer-core');
const [url, expectedTiles, screenshot] = process.argv.slice(2);
if (!url || !expectedTiles) {
  console.error('usage: node viewer-check.mjs URL EXPECTED_TILES [SCREENSHOT.png]');
  process.exit(2);
}
const chromium = process.env.CHROMIUM || '/usr/bin/chromium';
const browser = await puppeteer.launch({
  executablePath: chromium,
  headless: true,
  // WebGL on the CPU (SwiftShader): no GPU on CI machines. --no-sandbox: CI runs as root.
  args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--window-size=1024,768'],
  defaultViewport: { width: 1024, height: 768 },
});
const problems = [];
const result = {};
try {
  const page = await browser.newPage();
  const origin = new URL(url).origin;
  const consoleErrors = [], offOrigin = [];
  page.on('console', (m) => { if (m.type() === 'error') consoleErrors.push(m.text()); });
  page.on('pageerror', (e) => consoleErrors.push(String(e)));
  await page.setRequestInterception(true);
  page.on('request', (r) => {
    const u = r.url();
    if (u.startsWith('data:') || u.startsWith('blob:') || u.startsWith(origin)) return r.continue();
    offOrigin.push(u);
    r.abort();
  });
  // Every status the page shows, in order (tiles appearing while the job runs).
  await page.evaluateOnNewDocument(() => {
    window.__states = [];
    const t0 = performance.now();
    document.addEventListener('DOMContentLoaded', () => {
      const el = document.getElementById('status');
      new MutationObserver(() => {
        const s = `${el.dataset.state} ${el.dataset.tilesLoaded}/${el.dataset.tilesTotal}`;
        if (window.__states[window.__states.length - 1]?.s !== s)
          window.__states.push({ s, t: ((performance.now() - t0) / 1000).toFixed(1) });
      }).observe(el, { attributes: true, childList: true, subtree: true, characterData: true });
    });
  });
  const t0 = Date.now();
  await page.goto(url + (url.includes('#') ? '&' : '#') + 'color=shaded', { waitUntil: 'load' });
  await page.waitForFunction(() => ['ready', 'error'].includes(document.getElementById('status').dataset.state),
                             { timeout: 240000, polling: 250 });
  result.load_s = (Date.now() - t0) / 1000;
  result.states = (await page.evaluate(() => window.__states)).map((e) => `${e.t}s ${e.s}`);
  const status = await page.$eval('#status', (e) => ({ ...e.dataset, text: e.textContent }));
  result.state = status.state;
  result.tiles_loaded = Number(status.tilesLoaded);
  result.tiles_total = Number(status.tilesTotal);
  if (status.state !== 'ready') problems.push(`viewer state ${status.state}: ${status.text}`);
  if (result.tiles_loaded !== Number(expectedTiles) || result.tiles_total !== Number(expectedTiles))
    problems.push(`tiles loaded ${result.tiles_loaded} of ${result.tiles_total}, expected ${expectedTiles}`);

  // Luminance of the city's pixels (those off the background colour) after the scene settles.
  const stats = (mode) => page.evaluate(async (mode) => {
    const select = document.getElementById('color');
    select.value = mode;
    select.dispatchEvent(new Event('change'));
    const scene = window.satmeshViewer.scene;
    for (let i = 0; i < 8; ++i) await new Promise((r) => scene.postRender.addEventListener(function once() {
      scene.postRender.removeEventListener(once); r(); }));
    const gl = scene.canvas, c = document.createElement('canvas');
    c.width = gl.width; c.height = gl.height;
    const ctx = c.getContext('2d');
    ctx.drawImage(gl, 0, 0);
    const px = ctx.getImageData(0, 0, c.width, c.height).data;
    const bg = [0x14, 0x18, 0x1e];
    let n = 0, sum = 0, sum2 = 0;
    for (let i = 0; i < px.length; i += 4) {
      if (Math.abs(px[i] - bg[0]) + Math.abs(px[i + 1] - bg[1]) + Math.abs(px[i + 2] - bg[2]) < 12) continue;
      const y = 0.299 * px[i] + 0.587 * px[i + 1] + 0.114 * px[i + 2];
      ++n; sum += y; sum2 += y * y;
    }
    const mean = n ? sum / n : 0;
    return { coverage: n / (px.length / 4), mean, std: n ? Math.sqrt(Math.max(0, sum2 / n - mean * mean)) : 0 };
  }, mode);
  result.lit = await stats('shaded');
  if (screenshot) await page.screenshot({ path: screenshot });
  result.unlit = await stats('unlit');
  result.height = await stats('height');
  result.console_errors = consoleErrors;
  result.off_origin_requests = offOrigin;
  if (result.lit.coverage < 0.05) problems.push(`the city covers ${(100 * result.lit.coverage).toFixed(1)}% of the view`);
  if (!(result.lit.std > 8 && result.lit.std > 3 * result.unlit.std))
    problems.push(`no shaded relief: luminance std ${result.lit.std.toFixed(1)} lit vs ${result.unlit.std.toFixed(1)} unlit`);
  if (consoleErrors.length) problems.push(`console errors: ${consoleErrors.join(' | ')}`);
  if (offOrigin.length) problems.push(`requests off ${origin}: ${offOrigin.join(', ')}`);
} catch (e) {
  problems.push(String(e && e.stack || e));
} finally {
  await browser.close();
}
console.log(JSON.stringify(result));
for (const p of problems) console.log('FAIL: ' + p);
process.exit(problems.length ? 1 : 0);
