// Browser test of findmug-web's Label page: headless Debian chromium (puppeteer-core).
// Run by web_label_test.sh, which starts findmug-web over a dataset folder holding one
// unlabelled frame.
//
//   node label_test.mjs --url http://127.0.0.1:PORT/ --data DIR --frame NAME --out DIR
//
// Labels the frame by clicks (keys pick the class, one click undone), saves, labels one
// more patch and saves again, and checks
// DIR/label8/NAME.png pixel for pixel against what the clicks must give: each clicked
// patch (from the server's oversegmentation) in its class, everything else void. The
// PNG is decoded here (zlib + PNG filters), not by findmug's own reader. Exit 0 pass.
import fs from 'node:fs';
import path from 'node:path';
import { openPage, parseArgs } from './browser.mjs';
import { decodeGrey8 } from './png.mjs';

const args = parseArgs(process.argv.slice(2));
const VOID = 255;

function fail(message) {
  console.error('label_test: FAILED: ' + message);
  process.exitCode = 1;
}

const { page, pageErrors, close } = await openPage(1000, 900);
try {
  await page.goto(`${args.url}label?root=0&frame=${args.frame}`, { waitUntil: 'load' });
  await page.waitForFunction(() => window.findmugLabel && window.findmugLabel.ready, { timeout: 60000 });
  const q = `root=0&frame=${args.frame}`;
  const patches = new Uint16Array(await (await fetch(`${args.url}api/label/patches.bin?${q}`)).arrayBuffer());
  const { width, height } = await page.evaluate(() => ({ width: window.findmugLabel.width, height: window.findmugLabel.height }));
  if (patches.length !== width * height) throw new Error('patch map size');

  // Four patches at spread-out places, distinct, each big enough to hit.
  const clicks = [];
  const used = new Set();
  for (const [fx, fy] of [[0.5, 0.5], [0.25, 0.8], [0.75, 0.25], [0.3, 0.3]]) {
    let found = null;
    for (let r = 0; r < 60 && !found; r += 3) {
      for (const [dx, dy] of [[r, 0], [-r, 0], [0, r], [0, -r]]) {
        const x = Math.round(fx * width) + dx, y = Math.round(fy * height) + dy;
        const p = patches[y * width + x];
        if (p !== 0xffff && !used.has(p)) { found = { x, y, patch: p }; break; }
      }
    }
    if (!found) throw new Error('no patch near ' + fx + ',' + fy);
    used.add(found.patch);
    clicks.push(found);
  }
  const box = await (await page.$('#label-view')).boundingBox();
  const clickAt = async ({ x, y }) => page.mouse.click(box.x + (x + 0.5) * box.width / width,
                                                       box.y + (y + 0.5) * box.height / height);
  const classes = ['4', '1', '2', '7'];
  for (let i = 0; i < clicks.length; ++i) {
    await page.keyboard.press(classes[i]);
    await clickAt(clicks[i]);
  }
  await page.keyboard.press('z');  // the object click is undone
  await page.type('#author', 'label-test');
  await page.click('#label-view', { offset: { x: -5, y: -5 } }).catch(() => {});
  await page.keyboard.press('s');
  await page.waitForFunction(() => window.findmugLabel.saves === 1 || window.findmugLabel.error,
                             { timeout: 30000 });
  let error = await page.evaluate(() => window.findmugLabel.error);
  if (error) throw new Error('save: ' + error);
  // A second stroke and save from the same page: the file it wrote itself is not "newer".
  await page.keyboard.press('3');
  await clickAt(clicks[3]);
  await page.keyboard.press('s');
  await page.waitForFunction(() => window.findmugLabel.saves === 2 || window.findmugLabel.error,
                             { timeout: 30000 });
  error = await page.evaluate(() => window.findmugLabel.error);
  if (error) throw new Error('second save: ' + error);
  await page.screenshot({ path: path.join(args.out, 'label.png') });

  const expected = new Uint8Array(width * height).fill(VOID);
  const final = [...classes.slice(0, 3), '3'];
  for (let i = 0; i < 4; ++i) {
    for (let k = 0; k < patches.length; ++k) if (patches[k] === clicks[i].patch) expected[k] = Number(final[i]);
  }
  const file = path.join(args.data, 'label8', args.frame + '.png');
  const written = decodeGrey8(file);
  if (written.width !== width || written.height !== height) throw new Error('written size');
  let diff = 0, first = -1;
  for (let k = 0; k < expected.length; ++k) {
    if (written.pixels[k] !== expected[k]) { if (first < 0) first = k; ++diff; }
  }
  if (diff) fail(`${diff} pixels differ from the clicks, first at ${first}: ${written.pixels[first]} != ${expected[first]}`);
  const labelled = expected.filter((v) => v !== VOID).length;
  if (labelled < 50) fail('the clicked patches cover only ' + labelled + ' pixels');
  const sidecar = JSON.parse(fs.readFileSync(path.join(args.data, 'label8', args.frame + '.json'), 'utf8'));
  if (sidecar.author !== 'label-test') fail('sidecar author ' + sidecar.author);
  // A second page that read the file before it changed may not overwrite it.
  const stale = await fetch(`${args.url}api/label`, { method: 'POST', headers: { 'Content-Type': 'application/json' },
    body: JSON.stringify({ root: 0, frame: args.frame, width, height, runs: [[1, width * height]], author: 'x', base_mtime_ns: null }) });
  if (stale.status !== 409) fail('an overwrite of a newer file was not refused: ' + stale.status);
  if (pageErrors.length) fail('errors on the page: ' + pageErrors.join('; '));
  console.log(JSON.stringify({ labelled_pixels: labelled, patches: used.size, clicks: clicks.length }));
} catch (e) {
  fail(e.stack || String(e));
} finally {
  await close();
}
