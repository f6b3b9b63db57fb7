// Browser test of findmug-web's live page: headless Debian chromium driven by
// puppeteer-core (no browser download). Run by web_browser_test.sh, which starts
// findmugd on a replayed dataset and findmug-web on the same bus first.
//
//   node live_test.mjs --url http://127.0.0.1:PORT/ --out DIR [--measure-s 10]
//
// Checks: the label overlay updates (several different frames drawn, canvas pixels in
// the label palette), a table hull is drawn over the camera image (an SVG polygon with
// finite points) and on the map; saves DIR/live.png (the README's picture) and prints
// the measured updates per second and delays as JSON on stdout. Exit 0 pass, 1 fail.
import path from 'node:path';
import { openPage, parseArgs } from './browser.mjs';

const args = parseArgs(process.argv.slice(2));
const url = args.url;
const out = args.out || '.';
const measureS = Number(args['measure-s'] || 10);
if (!url) {
  console.error('live_test: --url is required');
  process.exit(2);
}

function fail(message) {
  console.error('live_test: FAILED: ' + message);
  process.exitCode = 1;
}

const { page, pageErrors, close } = await openPage(1400, 1000);
try {
  page.on('console', (m) => { if (m.type() === 'error') pageErrors.push(m.text()); });
  await page.goto(url, { waitUntil: 'load', timeout: 30000 });

  // 1. The label overlay updates: at least three different frames drawn.
  await page.waitForFunction(() => window.findmugLive && window.findmugLive.draws >= 3,
                             { timeout: 120000, polling: 200 });
  const seqA = await page.evaluate(() => window.findmugLive.lastSeq);
  await page.waitForFunction((s) => window.findmugLive.lastSeq !== s, { timeout: 60000, polling: 100 }, seqA);
  // Canvas pixels: most of the image carries a label colour blended over the camera
  // image, not the black of an empty canvas.
  const pixels = await page.evaluate(() => {
    const c = document.getElementById('view');
    const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
    let lit = 0;
    for (let i = 0; i < d.length; i += 4) if (d[i] + d[i + 1] + d[i + 2] > 30) ++lit;
    return { width: c.width, height: c.height, lit: lit / (d.length / 4) };
  });
  if (pixels.width < 100 || pixels.lit < 0.3) fail(`label overlay looks empty: ${JSON.stringify(pixels)}`);

  // 2. A table hull over the camera image, and the same table on the map.
  await page.waitForFunction(() => {
    for (const p of document.querySelectorAll('#overlay polygon.hull')) {
      const pts = p.getAttribute('points').trim().split(/\s+/).map((xy) => xy.split(',').map(Number));
      if (pts.length >= 3 && pts.every(([x, y]) => Number.isFinite(x) && Number.isFinite(y))) return true;
    }
    return false;
  }, { timeout: 180000, polling: 100 });
  const hulls = await page.evaluate(() => ({
    camera: document.querySelectorAll('#overlay polygon.hull').length,
    map: document.querySelectorAll('#map polygon.hull').length,
    legend: document.querySelectorAll('#legend li').length,
    status: document.querySelector('#status').innerText,
  }));
  if (hulls.map < 1) fail('no table hull on the map');
  if (hulls.legend < 9) fail(`legend has ${hulls.legend} entries`);
  if (!/frames per second/.test(hulls.status)) fail('no status shown: ' + hulls.status);
  await page.screenshot({ path: path.join(out, 'live.png'), fullPage: true });

  // 3. Measured: updates per second and delays over measureS seconds.
  const before = await page.evaluate(() => ({ draws: window.findmugLive.draws, t: Date.now() }));
  await new Promise((r) => setTimeout(r, measureS * 1000));
  const after = await page.evaluate(() => ({
    draws: window.findmugLive.draws, t: Date.now(),
    publish: window.findmugLive.publishToPageMs.slice(-200),
    receive: window.findmugLive.receiveToPageMs.slice(-200),
    errors: window.findmugLive.errors,
  }));
  const median = (v) => { const s = [...v].sort((a, b) => a - b); return s.length ? s[Math.floor(s.length / 2)] : null; };
  const result = {
    updates_per_s: (after.draws - before.draws) / ((after.t - before.t) / 1000),
    publish_to_page_ms_median: median(after.publish),
    receive_to_page_ms_median: median(after.receive),
    poll_errors: after.errors,
    hulls,
    pixels,
  };
  console.log(JSON.stringify(result));
  if (pageErrors.length) fail('errors on the page: ' + pageErrors.join('; '));
} catch (e) {
  fail(e.stack || String(e));
} finally {
  await close();
}
