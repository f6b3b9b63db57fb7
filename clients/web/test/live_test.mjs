// Browser test of findmug-web's live page: headless Debian chromium driven by
// puppeteer-core (no browser download). Run by web_browser_test.sh, which starts
// findmugd on a replayed dataset and findmug-web on the same bus first.
//
//   node live_test.mjs --url http://127.0.0.1:PORT/ --out DIR [--measure-s 10]
//                      [--map-log-cmd 'CMD']
//
// Checks: the label overlay updates (several different frames drawn, canvas pixels in
// the label palette), a table hull is drawn over the camera image (an SVG polygon with
// finite points) and on the map; saves DIR/live.png (the README's picture) and prints
// the measured updates per second and delays as JSON on stdout. With --map-log-cmd, then
// runs CMD (a shell command that replays a log with a semantic map and a table map into
// the bus: web_browser_test.sh) and checks the map panel draws the semantic map under the
// table: its raster has a pixel per floor cell in the label colours, the table's cells
// under the table's hull; saves DIR/live-map.png. Exit 0 pass, 1 fail.
import { spawn } from 'node:child_process';
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

// 4. The semantic map in the map panel, from the replayed log (findmug-test-spy-log: a 3 x
// 2.5 m floor at 5 cm, 60 x 50 cells, with the table map's table top on it).
async function checkSemanticMap(command) {
  const player = spawn('sh', ['-c', command], { stdio: 'ignore', detached: true });
  try {
    await page.waitForFunction(() => window.findmugLive.semanticMapCells > 0 &&
                               document.querySelector('#map image.semantic-map'),
                               { timeout: 60000, polling: 200 });
    const m = await page.evaluate(() => {
      const live = window.findmugLive;
      const c = live.semanticMapCanvas;
      const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
      const fade = (rgb, conf) => rgb.map((v) => Math.round(255 - (0.25 + 0.75 * conf / 255) * (255 - v)));
      return fetch('/api/live').then((r) => r.json()).then((state) => {
        const floor = fade(state.label_colors[1], 230), table = fade(state.label_colors[4], 200);
        let floorPx = 0, tablePx = 0, other = 0, tableSumX = 0, tableSumY = 0;
        for (let y = 0; y < c.height; ++y) {
          for (let x = 0; x < c.width; ++x) {
            const i = 4 * (y * c.width + x);
            const px = [d[i], d[i + 1], d[i + 2]];
            if (d[i + 3] === 0) continue;
            if (px.every((v, k) => v === floor[k])) ++floorPx;
            else if (px.every((v, k) => v === table[k])) { ++tablePx; tableSumX += x; tableSumY += y; }
            else ++other;
          }
        }
        const image = document.querySelector('#map image.semantic-map').getBoundingClientRect();
        const hull = document.querySelector('#map polygon.hull').getBoundingClientRect();
        // The table's cells, as drawn: their mean raster position on the screen.
        const tx = image.left + (tableSumX / Math.max(1, tablePx) + 0.5) / c.width * image.width;
        const ty = image.top + (tableSumY / Math.max(1, tablePx) + 0.5) / c.height * image.height;
        return {
          width: c.width, height: c.height, cells: live.semanticMapCells, floor: floorPx,
          table: tablePx, other,
          table_centre_in_hull: tx > hull.left && tx < hull.right && ty > hull.top && ty < hull.bottom,
          image_holds_hull: image.left <= hull.left && image.right >= hull.right &&
                            image.top <= hull.top && image.bottom >= hull.bottom,
          support: [...document.querySelectorAll('#map text.table-support')].map((t) => t.textContent),
          note: document.getElementById('map-note').textContent,
        };
      });
    });
    if (m.width !== 60 || m.height !== 50 || m.cells !== 3000) fail(`semantic map raster: ${JSON.stringify(m)}`);
    if (m.table < 300 || m.floor < 2000 || m.other !== 0 || m.floor + m.table !== 3000) {
      fail(`semantic map colours: ${JSON.stringify(m)}`);
    }
    if (!m.table_centre_in_hull || !m.image_holds_hull) fail(`semantic map not under the table: ${JSON.stringify(m)}`);
    if (!m.support.includes('3 frames, 2 views')) fail(`table support not shown: ${JSON.stringify(m.support)}`);
    if (!/semantic map of 3 frames/.test(m.note)) fail('map note: ' + m.note);
    await page.screenshot({ path: path.join(out, 'live-map.png'), fullPage: true });
    return m;
  } finally {
    try { process.kill(-player.pid, 'SIGTERM'); } catch (e) { /* already ended */ }
  }
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
  // Read for up to 10 s: on a busy host headless Chromium has once read back a black canvas
  // right after a redraw; a page that never draws stays black and fails.
  const readPixels = () => {
    const c = document.getElementById('view');
    const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
    let lit = 0;
    for (let i = 0; i < d.length; i += 4) if (d[i] + d[i + 1] + d[i + 2] > 30) ++lit;
    return { width: c.width, height: c.height, lit: lit / (d.length / 4) };
  };
  let pixels = await page.evaluate(readPixels);
  for (let tries = 0; tries < 50 && (pixels.width < 100 || pixels.lit < 0.3); ++tries) {
    await new Promise((r) => setTimeout(r, 200));
    pixels = await page.evaluate(readPixels);
  }
  if (pixels.width < 100 || pixels.lit < 0.3) fail(`label overlay looks empty: ${JSON.stringify(pixels)}`);

  // 2. A table hull over the camera image, and the same table on the map. The map's hull
  // comes from FINDMUG_TABLE_MAP, which the daemon publishes after the frame's tables and the
  // page draws on its own message: on a loaded host it can follow the camera's hull by a frame
  // or more, so wait for both (a page that never draws the map still fails, at the timeout).
  await page.waitForFunction(() => {
    const drawn = (selector) => {
      for (const p of document.querySelectorAll(selector)) {
        const pts = p.getAttribute('points').trim().split(/\s+/).map((xy) => xy.split(',').map(Number));
        if (pts.length >= 3 && pts.every(([x, y]) => Number.isFinite(x) && Number.isFinite(y))) return true;
      }
      return false;
    };
    return drawn('#overlay polygon.hull') && drawn('#map polygon.hull');
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
  const mapCheck = args['map-log-cmd'] ? await checkSemanticMap(args['map-log-cmd']) : null;
  const median = (v) => { const s = [...v].sort((a, b) => a - b); return s.length ? s[Math.floor(s.length / 2)] : null; };
  const result = {
    updates_per_s: (after.draws - before.draws) / ((after.t - before.t) / 1000),
    publish_to_page_ms_median: median(after.publish),
    receive_to_page_ms_median: median(after.receive),
    poll_errors: after.errors,
    hulls,
    pixels,
    semantic_map: mapCheck,
  };
  console.log(JSON.stringify(result));
  if (pageErrors.length) fail('errors on the page: ' + pageErrors.join('; '));
} catch (e) {
  fail(e.stack || String(e));
} finally {
  await close();
}
