// Browser test of teaching an object on findmug-web's live page and finding it: headless
// Debian chromium driven by puppeteer-core. Run by tests/integration/web_teach_test.sh,
// which starts findmugd on a replayed synthetic apartment (with a robot pose, a command
// input and daemon.objects_dir) and findmug-web on the same bus first.
//
//   node teach_test.mjs --url http://127.0.0.1:PORT/ --out DIR
//
// Waits until the live view draws the apartment's mug as a candidate (a box 9-11.5 cm tall
// with a footprint of a mug's size, not cut by the image border), types "mug" into the
// teach box and clicks the mug; waits for the daemon's "taught mug (1 view)"; then asks
// find "mug" with the Find box and waits for the answer "seen ... on table ...", then for
// the mug's box drawn with its name on the live view; saves DIR/teach.png (the README's picture). Prints what it saw as JSON. Exit 0 pass, 1 fail.
import path from 'node:path';
import { openPage, parseArgs } from './browser.mjs';

const args = parseArgs(process.argv.slice(2));
const url = args.url;
const out = args.out || '.';
if (!url) {
  console.error('teach_test: --url is required');
  process.exit(2);
}

const { page, pageErrors, close } = await openPage(1280, 1000);
const result = {};
try {
  await page.goto(url, { waitUntil: 'load' });
  // 1. The mug drawn as a candidate: the synthetic mug is 8.5-11 cm tall, 7.4-9 cm across
  //    (handle included); boxes and books of the apartment are wider or lower. Its box's
  //    middle in page coordinates, as it is drawn now.
  await page.evaluate(() => {
    window.testMugTarget = () => {
      const c = window.findmugLive.candidates.find((k) =>
        !k.cut && k.height > 0.085 && k.height < 0.115 &&
        Math.max(k.extents[0], k.extents[1]) < 0.065 && Math.min(k.extents[0], k.extents[1]) > 0.03);
      if (!c) return null;
      const canvas = document.getElementById('view');
      const r = canvas.getBoundingClientRect();
      return { x: r.left + r.width / canvas.width * (c.box[0] + c.box[2]) / 2,
               y: r.top + r.height / canvas.height * (c.box[1] + c.box[3]) / 2,
               seq: c.seq, index: c.index, height: c.height, box: c.box };
    };
  });
  await page.type('#teach-name', 'mug');
  // The click lands on the mug's box as it is drawn at that moment: computed and dispatched
  // in one turn of the page's event loop, so no new frame is drawn in between (with
  // page.mouse.click the page may draw the next frame first, and the boxes move).
  await page.waitForFunction(() => window.testMugTarget(), { timeout: 120000, polling: 50 });
  result.clicked = await page.evaluate(() => {
    const at = window.testMugTarget();
    if (!at) return null;
    document.getElementById('camera').dispatchEvent(
      new MouseEvent('click', { clientX: at.x, clientY: at.y, bubbles: true }));
    return at;
  });
  if (!result.clicked) throw new Error('the mug left the view before the click');
  // 2. The daemon's answer in the status: taught.
  await page.waitForFunction(() => window.findmugLive.teachResult !== null,
                             { timeout: 30000, polling: 100 });
  result.teach = await page.evaluate(() => window.findmugLive.teachResult);
  result.teach_note = await page.$eval('#teach-note', (n) => n.textContent);
  if (!result.teach.ok || !/^taught mug \(1 view\)/.test(result.teach.text)) {
    throw new Error('teach: ' + JSON.stringify(result.teach));
  }
  // 3. Find it: the daemon reads the new model within a second or two, names the mug in
  //    the next frames that show it and answers (and answers again when that changes).
  await page.type('#find-name', 'mug');
  await page.click('#find-send');
  await page.waitForFunction(() => window.findmugLive.findResult &&
                             window.findmugLive.findResult.result === 'seen',
                             { timeout: 120000, polling: 100 });
  result.find = await page.evaluate(() => window.findmugLive.findResult);
  result.find_note = await page.$eval('#find-note', (n) => n.textContent);
  if (!/mug seen at .* on table \d+/.test(result.find_note)) throw new Error('find note: ' + result.find_note);
  // The picture: the camera view with the found mug named on it, the two answers under it.
  await page.waitForFunction(() => {
    const f = window.findmugLive.foundDrawn;
    return f && f.seq === window.findmugLive.lastSeq && f.box[1] > 20;  // in view, its name too
  }, { timeout: 60000, polling: 50 });
  result.found_drawn = await page.evaluate(() => window.findmugLive.foundDrawn);
  const panel = await page.$('#camera-panel');
  await panel.screenshot({ path: path.join(out, 'teach.png') });
  if (pageErrors.length) throw new Error('script errors on the page: ' + pageErrors.join('; '));
  console.log(JSON.stringify(result));
} catch (e) {
  console.error('teach_test: FAILED: ' + e.message);
  console.error('teach_test: seen so far: ' + JSON.stringify(result));
  process.exitCode = 1;
} finally {
  await close();
}
