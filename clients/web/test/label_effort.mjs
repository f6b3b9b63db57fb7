// Labelling effort on findmug-web's Label page (issue 36, "Measured"): a scripted greedy
// user drives the real page in headless Debian chromium (puppeteer-core) on NYU frames
// and counts page actions and seconds of page time until 90 % and 95 % of the labelled
// pixels agree with NYU's label8/, from a blank frame and from the model's prediction.
//
//   node clients/web/test/label_effort.mjs --web build/clients/web/findmug-web \
//     --nyu DATA/nyuv2_labeled --nyu-rotations DATA/nyuv2_meta/camera_rotations_NYU.txt \
//     --model models/findmug.fmf [--set KEY=VALUE,...] [--frames 0001,0002 | --count N] \
//     [--max-actions 300] [--port 18291] [--json OUT.json]
//
// --set defaults to the shipped model's settings (models/README.md):
// ground.source=gravity,features.regions=true,features.scene=true,learner.classes=nyu13,
// features.objects=true,features.objects_columns=context.
//
//   node clients/web/test/label_effort.mjs --merge A.json,B.json,... [--json OUT.json]
//
// joins the frames of several runs (e.g. one per cross-validation fold, each with the
// model that did not see its frames) and prints their table and means.
//
// The frames' rgb/ and depth/ are copied to a scratch dataset folder (no labels, so the
// page starts blank and nothing is written to the data); findmug-web serves it on
// 127.0.0.1. At every step the user takes the page action that fixes the most labelled
// pixels still disagreeing with NYU (net: pixels fixed minus pixels broken):
//   - a patch click (paint tool) on any patch, in any class;
//   - a region fill (region tool, the page's default limits) from any patch as seed;
//   - a straight drag (paint tool) between two of the 30 patches with the largest gain;
// it presses the tool and class keys when they change (counted apart, not as actions).
// "Start from prediction" is the first action of a run from the prediction. It stops at
// 95 %, when no action gains, or after --max-actions. Page time is the wall time from
// the first key of an action until the page has applied it and written its draft
// (window.findmugLabel: strokes, draftIdle), summed over the actions; the user's own
// search is not counted. The agreement is counted on the labelled (non-void) NYU pixels
// inside NYU's valid border (rows 44..470, columns 40..600, 0-based, as findmug-train
// reads NYU frames); pixels without depth are in no patch and cannot be labelled on the
// page. This side keeps its own copy of the labels the actions must give, and checks it
// against the page's at the end of each run (a mismatch is reported and fails the run).
import { spawn } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { openPage, parseArgs } from './browser.mjs';
import { decodeGrey8 } from './png.mjs';
import {
  VOID, canvasActions, differences, frameData, patchesOnLine, regionOf, settled,
} from './label_page.mjs';

const args = parseArgs(process.argv.slice(2));
const port = Number(args.port || 18291);
const url = `http://127.0.0.1:${port}/`;
const maxActions = Number(args['max-actions'] || 300);
const CLASSES = 8;
const DRAG_CANDIDATES = 30;
const BORDER = { top: 44, bottom: 470, left: 40, right: 600 };

function usage(message) {
  console.error('label_effort: ' + message);
  process.exit(2);
}
if (args.merge) {
  const parts = args.merge.split(',').map((f) => JSON.parse(fs.readFileSync(f, 'utf8')));
  const frames = parts.flatMap((p) => p.frames).sort((a, b) => a.frame.localeCompare(b.frame));
  const r = report(frames, parts.flatMap((p) => p.commands));
  printReport(r);
  if (args.json) fs.writeFileSync(args.json, JSON.stringify(r, null, 1) + '\n');
  process.exit(0);
}
for (const key of ['web', 'nyu', 'model']) if (!args[key]) usage(`--${key} is required`);
const settings = (args.set || 'ground.source=gravity,features.regions=true,features.scene=true,' +
  'learner.classes=nyu13,features.objects=true,features.objects_columns=context').split(',');
let frames = fs.readdirSync(path.join(args.nyu, 'label8')).filter((n) => n.endsWith('.png'))
  .map((n) => n.slice(0, -4)).sort();
if (args.frames) frames = args.frames.split(',');
if (args.count) frames = frames.slice(0, Number(args.count));

// --- the scratch dataset folder and findmug-web ---
const work = fs.mkdtempSync(path.join(os.tmpdir(), 'findmug-label-effort-'));
for (const part of ['rgb', 'depth']) {
  fs.mkdirSync(path.join(work, part));
  for (const f of frames) fs.copyFileSync(path.join(args.nyu, part, f + '.png'), path.join(work, part, f + '.png'));
}
const command = [args.web, '--lcm-url', 'memq://', '--port', String(port), '--data', work,
  '--static-dir', path.join(path.dirname(new URL(import.meta.url).pathname), '..', 'static'),
  '--model', args.model, ...settings.flatMap((s) => ['--set', s])];
if (args['nyu-rotations']) command.push('--nyu-rotations', args['nyu-rotations']);
const webLog = path.join(work, 'web.log');
const web = spawn(command[0], command.slice(1), { stdio: ['ignore', fs.openSync(webLog, 'a'), fs.openSync(webLog, 'a')] });
for (let i = 0; ; ++i) {
  try { if ((await fetch(url + 'api/data')).ok) break; } catch { /* not yet */ }
  if (i > 100 || web.exitCode !== null) usage('findmug-web did not start: ' + fs.readFileSync(webLog, 'utf8'));
  await new Promise((r) => setTimeout(r, 100));
}

// --- the greedy user's model of a frame ---
// Per patch: NYU's labelled pixels per class (inside the border), a pixel to click (well
// inside the patch, near its centre), and the regions a fill from it takes.
function studyFrame(data, truth) {
  const { width, height, count } = data;
  const inside = (i) => {
    const x = i % width, y = Math.floor(i / width);
    return y >= BORDER.top && y <= BORDER.bottom && x >= BORDER.left && x <= BORDER.right;
  };
  const counted = new Uint8Array(width * height);
  let labelled = 0;
  for (let i = 0; i < counted.length; ++i) if (truth[i] !== VOID && truth[i] < CLASSES && inside(i)) { counted[i] = 1; ++labelled; }
  const hist = Array.from({ length: count }, () => new Int32Array(CLASSES));
  const click = [];
  for (let p = 0; p < count; ++p) {
    const px = data.patchPixels[p];
    let sx = 0, sy = 0;
    for (const i of px) { if (counted[i]) hist[p][truth[i]] += 1; sx += i % width; sy += Math.floor(i / width); }
    const cx = sx / px.length, cy = sy / px.length;
    const own = (x, y) => x >= 0 && y >= 0 && x < width && y < height && data.patches[y * width + x] === p;
    let best = null, bestScore = Infinity;
    for (const i of px) {
      const x = i % width, y = Math.floor(i / width);
      const interior = own(x - 3, y) && own(x + 3, y) && own(x, y - 3) && own(x, y + 3);
      const score = (x - cx) ** 2 + (y - cy) ** 2 + (interior ? 0 : 1e9);
      if (score < bestScore) { bestScore = score; best = [x, y]; }
    }
    click.push(best);
  }
  const regions = Array.from({ length: count }, (_, s) => Int32Array.from(regionOf(data.graph, s)));
  let oracle = 0;
  for (const h of hist) oracle += Math.max(...h);
  return { labelled, hist, click, regions, counted, oracle: labelled ? oracle / labelled : 0 };
}

// The best action for the current patch labels (`current[p]`: the label of all its pixels).
function bestAction(data, study, current) {
  const { hist, regions, click } = study;
  const have = (p) => (current[p] === VOID ? 0 : hist[p][current[p]]);
  const gain = (p, c) => hist[p][c] - have(p);
  let best = { gain: 0 };
  const consider = (a) => { if (a.gain > best.gain) best = a; };
  // Patch clicks.
  const top = [];
  for (let p = 0; p < data.count; ++p) {
    let c = 0;
    for (let k = 1; k < CLASSES; ++k) if (hist[p][k] > hist[p][c]) c = k;
    const g = gain(p, c);
    if (g > 0) { consider({ kind: 'click', gain: g, cls: c, at: click[p] }); top.push({ p, c, g }); }
  }
  // Region fills.
  const sums = new Float64Array(CLASSES);
  for (let s = 0; s < data.count; ++s) {
    sums.fill(0);
    let lose = 0;
    for (const p of regions[s]) { const h = hist[p]; for (let c = 0; c < CLASSES; ++c) sums[c] += h[c]; lose += have(p); }
    for (let c = 0; c < CLASSES; ++c) {
      if (sums[c] - lose > best.gain) best = { kind: 'region', gain: sums[c] - lose, cls: c, at: click[s] };
    }
  }
  // Straight drags between the patches with the largest gains, in the first one's class.
  top.sort((a, b) => b.g - a.g);
  const ends = top.slice(0, DRAG_CANDIDATES);
  for (const a of ends) {
    for (const b of ends) {
      if (a.p >= b.p || a.c !== b.c) continue;
      const line = patchesOnLine(data, click[a.p], click[b.p]);
      let g = 0;
      for (const p of line) g += gain(p, a.c);
      consider({ kind: 'drag', gain: g, cls: a.c, at: click[a.p], to: click[b.p] });
    }
  }
  return best;
}

// One run on the page: returns the actions and page seconds at 90 % and 95 %.
async function run(page, frame, data, study, fromPrediction) {
  await fetch(`${url}api/label/draft?root=0&frame=${frame}`, { method: 'DELETE' });
  await page.goto(`${url}label?root=0&frame=${frame}`, { waitUntil: 'load' });
  await page.waitForFunction(() => window.findmugLabel && window.findmugLabel.ready, { timeout: 120000 });
  const act = await canvasActions(page, data.width, data.height);
  const current = new Uint8Array(data.count).fill(VOID);
  let agree = 0, actions = 0, keys = 0, pageMs = 0, strokes = 0;
  const reached = {};
  const kinds = { prediction: 0, click: 0, region: 0, drag: 0 };
  const note = () => {
    const share = study.labelled ? agree / study.labelled : 0;
    for (const t of [0.9, 0.95]) {
      if (share >= t && !(t in reached)) reached[t] = { actions, seconds: pageMs / 1000 };
    }
    return share;
  };
  const assign = (patchList, c) => {
    for (const p of patchList) {
      agree += study.hist[p][c] - (current[p] === VOID ? 0 : study.hist[p][current[p]]);
      current[p] = c;
    }
  };
  if (fromPrediction) {
    const predicted = (await (await fetch(`${url}api/label/prediction?root=0&frame=${frame}`)).json()).labels;
    const t0 = performance.now();
    await page.click('#predict');
    await settled(page, ++strokes);
    pageMs += performance.now() - t0;
    ++actions; ++kinds.prediction;
    predicted.forEach((c, p) => assign([p], c));
  }
  const startShare = note();
  let tool = 'paint', chosen = await page.evaluate(() => window.findmugLabel.chosen);
  while (note() < 0.95 && actions < maxActions) {
    const a = bestAction(data, study, current);
    if (!(a.gain > 0)) break;
    const t0 = performance.now();
    const wantTool = a.kind === 'region' ? 'region' : 'paint';
    if (wantTool !== tool) { await page.keyboard.press(wantTool === 'region' ? 'r' : 'p'); tool = wantTool; ++keys; }
    if (a.cls !== chosen) { await page.keyboard.press(String(a.cls)); chosen = a.cls; ++keys; }
    if (a.kind === 'drag') await act.drag(a.at, a.to);
    else await act.click(a.at[0], a.at[1]);
    await settled(page, ++strokes);
    pageMs += performance.now() - t0;
    ++actions; ++kinds[a.kind];
    const seed = data.patches[a.at[1] * data.width + a.at[0]];
    if (a.kind === 'click') assign([seed], a.cls);
    else if (a.kind === 'region') assign(study.regions[seed], a.cls);
    else assign(patchesOnLine(data, a.at, a.to), a.cls);
  }
  const finalShare = note();
  // This side's account against the page's labels.
  const mine = new Uint8Array(data.width * data.height).fill(VOID);
  current.forEach((c, p) => { for (const i of data.patchPixels[p]) mine[i] = c; });
  const onPage = Uint8Array.from(await page.evaluate(() => window.findmugLabel.labels()));
  const mismatch = differences(mine, onPage).count;
  return { start: startShare, final: finalShare, actions, keys, kinds, seconds: pageMs / 1000,
           at90: reached[0.9] || null, at95: reached[0.95] || null, mismatch };
}

const { page, pageErrors, close } = await openPage(1000, 1000);
const results = [];
let failed = false;
try {
  for (const frame of frames) {
    const t0 = performance.now();
    const data = await frameData(url, 0, frame);
    const truth = decodeGrey8(path.join(args.nyu, 'label8', frame + '.png')).pixels;
    const study = studyFrame(data, truth);
    const blank = await run(page, frame, data, study, false);
    const predicted = await run(page, frame, data, study, true);
    const row = { frame, patches: data.count, labelled: study.labelled, oracle: study.oracle, blank, predicted,
                  wall_s: (performance.now() - t0) / 1000 };
    results.push(row);
    if (blank.mismatch || predicted.mismatch) failed = true;
    const fmt = (r) => `${(100 * r.start).toFixed(1)}%→${(100 * r.final).toFixed(1)}% ` +
      `90%:${r.at90 ? r.at90.actions + 'a/' + r.at90.seconds.toFixed(1) + 's' : '—'} ` +
      `95%:${r.at95 ? r.at95.actions + 'a/' + r.at95.seconds.toFixed(1) + 's' : '—'} ` +
      `(${r.actions}a ${JSON.stringify(r.kinds)}${r.mismatch ? ' MISMATCH ' + r.mismatch : ''})`;
    console.log(`${frame} patches ${data.count} oracle ${(100 * study.oracle).toFixed(1)}% | blank ${fmt(blank)} | prediction ${fmt(predicted)}`);
  }
} catch (e) {
  console.error('label_effort: ' + (e.stack || e));
  failed = true;
} finally {
  await close();
  web.kill('SIGTERM');
}

// Means over frames; a frame that never reached a threshold counts with the actions it
// took (a lower bound) and is listed.
function summary(results, key, t) {
  const rows = results.map((r) => r[key][t]);
  const reachedRows = rows.filter(Boolean);
  const mean = (xs) => xs.reduce((a, b) => a + b, 0) / Math.max(1, xs.length);
  const sorted = reachedRows.map((x) => x.actions).sort((a, b) => a - b);
  return {
    reached: reachedRows.length, of: rows.length,
    mean_actions: mean(results.map((r) => (r[key][t] ? r[key][t].actions : r[key].actions))),
    mean_seconds: mean(results.map((r) => (r[key][t] ? r[key][t].seconds : r[key].seconds))),
    median_actions: sorted.length ? sorted[Math.floor(sorted.length / 2)] : null,
  };
}

function report(results, commands) {
  return {
    commands,
    frames: results,
    summary: {
      blank: { at90: summary(results, 'blank', 'at90'), at95: summary(results, 'blank', 'at95') },
      prediction: { at90: summary(results, 'predicted', 'at90'), at95: summary(results, 'predicted', 'at95') },
      mean_prediction_start: results.reduce((a, r) => a + r.predicted.start, 0) / Math.max(1, results.length),
    },
  };
}

// The per-frame table (Markdown) and the means.
function printReport(r) {
  const cell = (x) => (x ? `${x.actions} / ${x.seconds.toFixed(1)} s` : 'not reached');
  console.log('| frame | patches | oracle | blank: 90 % | blank: 95 % | prediction alone | ' +
              'prediction: 90 % | prediction: 95 % | from prediction: click/region/drag |');
  console.log('|---|---|---|---|---|---|---|---|---|');
  for (const f of r.frames) {
    const k = f.predicted.kinds;
    console.log(`| ${f.frame} | ${f.patches} | ${(100 * f.oracle).toFixed(1)} % | ${cell(f.blank.at90)} | ` +
                `${cell(f.blank.at95)} | ${(100 * f.predicted.start).toFixed(1)} % | ${cell(f.predicted.at90)} | ` +
                `${cell(f.predicted.at95)} | ${k.click}/${k.region}/${k.drag} |`);
  }
  const s = r.summary;
  for (const [name, key] of [['blank', 'blank'], ['prediction', 'prediction']]) {
    for (const t of ['at90', 'at95']) {
      const x = s[key][t];
      console.log(`- from ${name} to ${t.slice(2)} %: reached in ${x.reached} of ${x.of} frames; mean ` +
                  `${x.mean_actions.toFixed(1)} actions, ${x.mean_seconds.toFixed(2)} s of page time; median ` +
                  `${x.median_actions} actions over the frames that reached it`);
    }
  }
  console.log(`- the prediction alone: ${(100 * s.mean_prediction_start).toFixed(1)} % of the labelled pixels (mean)`);
}

const r = report(results, [process.argv.slice(1).join(' ')]);
r.page_errors = pageErrors;
printReport(r);
if (args.json) fs.writeFileSync(args.json, JSON.stringify(r, null, 1) + '\n');
fs.rmSync(work, { recursive: true, force: true });
if (failed || pageErrors.length) {
  console.error('label_effort: the page and this side disagree, or the page failed: ' + pageErrors.join('; '));
  process.exitCode = 1;
}
