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
// 127.0.0.1. The greedy user and how page time and agreement are counted:
// greedy_user.mjs. Each frame is labelled twice, from blank and from the prediction,
// each run stopping at 95 %, when no action gains, or after --max-actions; this side's
// account of the labels is checked against the page's at the end of each run (a
// mismatch is reported and fails the run).
import { spawn } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { openPage, parseArgs } from './browser.mjs';
import { decodeGrey8 } from './png.mjs';
import { greedyRun, studyFrame } from './greedy_user.mjs';
import { frameData } from './label_page.mjs';

const args = parseArgs(process.argv.slice(2));
const port = Number(args.port || 18291);
const url = `http://127.0.0.1:${port}/`;
const maxActions = Number(args['max-actions'] || 300);

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

const { page, pageErrors, close } = await openPage(1000, 1000);
const results = [];
let failed = false;
try {
  for (const frame of frames) {
    const t0 = performance.now();
    const data = await frameData(url, 0, frame);
    const truth = decodeGrey8(path.join(args.nyu, 'label8', frame + '.png')).pixels;
    const study = studyFrame(data, truth);
    const blank = await greedyRun(page, { url, frame, data, study, fromPrediction: false, maxActions });
    const predicted = await greedyRun(page, { url, frame, data, study, fromPrediction: true, maxActions });
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
