// Browser test of the Label page's tools (headless Debian chromium, puppeteer-core), run
// by web_label_test.sh --script label_tools_test.mjs over a findmug-web with a model.
//
//   node label_tools_test.mjs --url http://127.0.0.1:PORT/ --data DIR --frame NAME --out DIR
//
// On an unlabelled frame: "start from prediction", a drag in class 1, a region fill in
// class 2, a click in class 7, undo twice (the click, the region), redo once (the region).
// Checks the draft on disk after the strokes and then the saved label8/NAME.png pixel for
// pixel against what these actions must give, computed here from the server's patches,
// patch graph and prediction (the drag's line and the region's growth by this side's own
// code); the draft is gone after the save. Exit 0 pass.
import fs from 'node:fs';
import path from 'node:path';
import { openPage, parseArgs } from './browser.mjs';
import { decodeGrey8 } from './png.mjs';
import {
  VOID, NO_PATCH, canvasActions, differences, draftLabels, frameData, patchesOnLine, prediction,
  regionOf, settled,
} from './label_page.mjs';

const args = parseArgs(process.argv.slice(2));

function fail(message) {
  console.error('label_tools_test: FAILED: ' + message);
  process.exitCode = 1;
}

const { page, pageErrors, close } = await openPage(1000, 1000);
try {
  const frame = args.frame;
  await page.goto(`${args.url}label?root=0&frame=${frame}`, { waitUntil: 'load' });
  await page.waitForFunction(() => window.findmugLabel && window.findmugLabel.ready, { timeout: 120000 });
  const data = await frameData(args.url, 0, frame);
  const { width, height } = data;
  const predicted = await prediction(args.url, 0, frame);
  if (predicted.labels.length !== data.count) throw new Error('prediction is not per patch');
  const expected = new Uint8Array(width * height).fill(VOID);
  const give = (patchList, id) => { for (const p of patchList) for (const i of data.patchPixels[p]) expected[i] = id; };
  const act = await canvasActions(page, width, height);
  let strokes = 0;

  // 1. The model's prediction as the starting point.
  await page.click('#predict');
  await settled(page, ++strokes);
  predicted.labels.forEach((id, p) => give([p], id));
  const predictedPixels = expected.filter((v) => v !== VOID).length;
  if (predictedPixels < width * height / 4) fail('the prediction labels only ' + predictedPixels + ' pixels');

  // 2. A drag across the middle of the frame in class 1 (floor).
  await page.keyboard.press('p');
  await page.keyboard.press('1');
  const a = [Math.round(width * 0.3), Math.round(height * 0.62)];
  const b = [Math.round(width * 0.7), Math.round(height * 0.55)];
  const dragged = patchesOnLine(data, a, b);
  if (dragged.length < 4) throw new Error('the drag line crosses only ' + dragged.length + ' patches');
  await act.drag(a, b);
  await settled(page, ++strokes);
  give(dragged, 1);
  const afterDrag = Uint8Array.from(expected);

  // 3. A region fill in class 2 (wall) from a seed whose region has several patches.
  let seed = null, region = null;
  for (let y = Math.round(height * 0.15); y < height * 0.5 && !seed; y += 7) {
    for (let x = Math.round(width * 0.15); x < width * 0.85; x += 11) {
      const p = data.patches[y * width + x];
      if (p === NO_PATCH || dragged.includes(p)) continue;
      const r = regionOf(data.graph, p);
      if (r.length >= 5 && r.length <= data.count / 3) { seed = [x, y]; region = r; break; }
    }
  }
  if (!seed) throw new Error('no seed with a region of 5 or more patches');
  await page.keyboard.press('r');
  await page.keyboard.press('2');
  await act.click(seed[0], seed[1]);
  await settled(page, ++strokes);
  give(region, 2);
  const afterRegion = Uint8Array.from(expected);

  // 4. A click in class 7 on a patch of neither, then undo, undo, redo.
  let clicked = null;
  for (let k = 0; k < width * height && !clicked; k += 97) {
    const p = data.patches[k];
    if (p !== NO_PATCH && !dragged.includes(p) && !region.includes(p) && data.patchPixels[p].length > 200) {
      clicked = [k % width, Math.floor(k / width)];
    }
  }
  await page.keyboard.press('p');
  await page.keyboard.press('7');
  await act.click(clicked[0], clicked[1]);
  await settled(page, ++strokes);
  const onPage = Uint8Array.from(await page.evaluate(() => window.findmugLabel.labels()));
  const clickedPatch = data.patches[clicked[1] * width + clicked[0]];
  for (const i of data.patchPixels[clickedPatch]) {
    if (onPage[i] !== 7) { fail('the clicked patch is not in class 7 on the page'); break; }
  }
  await page.keyboard.press('z');
  await settled(page, ++strokes);
  await page.keyboard.press('z');
  await settled(page, ++strokes);
  const undone = Uint8Array.from(await page.evaluate(() => window.findmugLabel.labels()));
  const d1 = differences(undone, afterDrag);
  if (d1.count) fail(`after two undos ${d1.count} pixels differ from prediction + drag`);
  await page.keyboard.press('y');
  await settled(page, ++strokes);
  await page.screenshot({ path: path.join(args.out, 'label-tools.png') });

  // The draft on disk holds every stroke.
  const draft = draftLabels(args.data, frame);
  if (!draft) throw new Error('no draft written');
  if (draft.strokes !== strokes) fail(`the draft says ${draft.strokes} strokes, the page made ${strokes}`);
  const d2 = differences(draft.labels, afterRegion);
  if (d2.count) fail(`the draft differs from the actions in ${d2.count} pixels, first at ${d2.first}`);

  // Saved: label8/NAME.png pixel for pixel, the sidecar, and no draft left.
  await page.type('#author', 'tools-test');
  await page.click('#save');
  await page.waitForFunction(() => window.findmugLabel.saves === 1 || window.findmugLabel.error, { timeout: 30000 });
  const error = await page.evaluate(() => window.findmugLabel.error);
  if (error) throw new Error('save: ' + error);
  const written = decodeGrey8(path.join(args.data, 'label8', frame + '.png'));
  if (written.width !== width || written.height !== height) throw new Error('written size');
  const d3 = differences(written.pixels, afterRegion);
  if (d3.count) fail(`${d3.count} saved pixels differ from the actions, first at ${d3.first}: ${written.pixels[d3.first]} != ${afterRegion[d3.first]}`);
  if (fs.existsSync(path.join(args.data, 'drafts', frame + '.json'))) fail('the draft is still there after the save');
  const sidecar = JSON.parse(fs.readFileSync(path.join(args.data, 'label8', frame + '.json'), 'utf8'));
  if (sidecar.author !== 'tools-test') fail('sidecar author ' + sidecar.author);
  if (pageErrors.length) fail('errors on the page: ' + pageErrors.join('; '));
  console.log(JSON.stringify({ predicted_pixels: predictedPixels, dragged_patches: dragged.length,
                               region_patches: region.length, strokes }));
} catch (e) {
  fail(e.stack || String(e));
} finally {
  await close();
}
