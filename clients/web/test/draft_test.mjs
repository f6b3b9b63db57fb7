// The Label page's autosave across a crash (headless Debian chromium, puppeteer-core), run
// by web_label_test.sh --script draft_test.mjs, which hands over findmug-web's command.
//
//   node draft_test.mjs --url http://127.0.0.1:PORT/ --data DIR --frame NAME --out DIR
//                       --log FILE --web-cmd "findmug-web\n--port\nPORT\n..."
//
// Starts findmug-web, paints two strokes on the page, kills findmug-web with SIGKILL right
// after the second stroke's draft is written, starts it again and reopens the frame: the
// page offers the draft, and restoring it gives both strokes, pixel for pixel (checked
// against the patches the clicks hit), which then save. Then a draft file that is not
// one: the server answers 422 naming the file, the page shows that message and offers no
// restore, and findmug-web keeps serving. Exit 0 pass.
import { spawn } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { openPage, parseArgs } from './browser.mjs';
import { decodeGrey8 } from './png.mjs';
import { VOID, NO_PATCH, canvasActions, differences, draftLabels, frameData, settled } from './label_page.mjs';

const args = parseArgs(process.argv.slice(2));
const command = args['web-cmd'].split('\n').filter((s) => s.length);
const log = fs.openSync(args.log, 'a');

function fail(message) {
  console.error('draft_test: FAILED: ' + message);
  process.exitCode = 1;
}

async function startWeb() {
  const child = spawn(command[0], command.slice(1), { stdio: ['ignore', log, log] });
  for (let i = 0; i < 100; ++i) {
    try {
      if ((await fetch(args.url + 'api/data')).ok) return child;
    } catch { /* not listening yet */ }
    await new Promise((r) => setTimeout(r, 100));
  }
  child.kill('SIGKILL');
  throw new Error('findmug-web did not start: ' + command.join(' '));
}

const killed = (child) => new Promise((resolve) => { child.once('exit', resolve); child.kill('SIGKILL'); });

let web = await startWeb();
const { page, pageErrors, close } = await openPage(1000, 1000);
try {
  const frame = args.frame;
  const open = async () => {
    await page.goto(`${args.url}label?root=0&frame=${frame}`, { waitUntil: 'load' });
    await page.waitForFunction(() => window.findmugLabel && window.findmugLabel.ready, { timeout: 120000 });
  };
  await open();
  const data = await frameData(args.url, 0, frame);
  const { width, height } = data;
  const act = await canvasActions(page, width, height);
  // Two big patches far apart, in classes 5 and 2.
  const picks = [];
  for (const [fx, fy] of [[0.4, 0.6], [0.6, 0.3]]) {
    let best = -1, at = null;
    for (let y = Math.round(fy * height) - 30; y <= fy * height + 30; y += 5) {
      for (let x = Math.round(fx * width) - 30; x <= fx * width + 30; x += 5) {
        const p = data.patches[y * width + x];
        if (p !== NO_PATCH && !picks.some((q) => q.patch === p) && data.patchPixels[p].length > best) {
          best = data.patchPixels[p].length; at = { x, y, patch: p };
        }
      }
    }
    if (!at) throw new Error('no patch near ' + fx + ',' + fy);
    picks.push(at);
  }
  const expected = new Uint8Array(width * height).fill(VOID);
  const ids = [5, 2];
  for (let k = 0; k < 2; ++k) {
    await page.keyboard.press(String(ids[k]));
    await act.click(picks[k].x, picks[k].y);
    await settled(page, k + 1);
    for (const i of data.patchPixels[picks[k].patch]) expected[i] = ids[k];
  }
  const onDisk = draftLabels(args.data, frame);
  if (!onDisk || onDisk.strokes !== 2) throw new Error('the draft does not hold both strokes');

  // The crash: no chance to save or clean up.
  await killed(web);
  web = await startWeb();
  await open();
  const offered = await page.evaluate(() => window.findmugLabel.draft);
  if (!offered || offered.strokes !== 2) fail('the reopened page does not offer the 2-stroke draft: ' + JSON.stringify(offered));
  if (await page.$eval('#draft-bar', (e) => e.hidden)) fail('the draft bar is hidden');
  const blank = Uint8Array.from(await page.evaluate(() => window.findmugLabel.labels()));
  if (blank.some((v) => v !== VOID)) fail('the page took the draft before it was asked to');
  await page.screenshot({ path: path.join(args.out, 'label-draft.png') });
  await page.click('#draft-restore');
  const restored = Uint8Array.from(await page.evaluate(() => window.findmugLabel.labels()));
  const d = differences(restored, expected);
  if (d.count) fail(`the restored draft differs from the two strokes in ${d.count} pixels`);
  await page.click('#save');
  await page.waitForFunction(() => window.findmugLabel.saves === 1 || window.findmugLabel.error, { timeout: 30000 });
  const error = await page.evaluate(() => window.findmugLabel.error);
  if (error) throw new Error('save: ' + error);
  const saved = decodeGrey8(path.join(args.data, 'label8', frame + '.png'));
  const d2 = differences(saved.pixels, expected);
  if (d2.count) fail(`the saved file differs from the two strokes in ${d2.count} pixels`);

  // A draft file that is not one.
  fs.writeFileSync(path.join(args.data, 'drafts', frame + '.json'), '{"format": "findmug-label-draft", "version": 1, "frame": "');
  const res = await fetch(`${args.url}api/label/draft?root=0&frame=${frame}`);
  const answer = await res.json();
  if (res.status !== 422 || !/drafts\/[^ ]+\.json: not a label draft/.test(answer.error)) {
    fail(`a bad draft answered ${res.status} ${JSON.stringify(answer)}`);
  }
  await open();
  const shown = await page.$eval('#draft-text', (e) => e.textContent);
  if (!shown.includes('cannot be used') || !shown.includes(frame + '.json')) fail('the page shows: ' + shown);
  if (!(await page.$eval('#draft-restore', (e) => e.hidden))) fail('a bad draft is offered for restoring');
  const still = await fetch(`${args.url}api/label/frame?root=0&frame=${frame}`);
  if (!still.ok) fail('findmug-web stopped answering after the bad draft');
  if (pageErrors.length) fail('errors on the page: ' + pageErrors.join('; '));
  console.log(JSON.stringify({ strokes: 2, restored_pixels: expected.filter((v) => v !== VOID).length }));
} catch (e) {
  fail(e.stack || String(e));
} finally {
  await close();
  await killed(web);
}
