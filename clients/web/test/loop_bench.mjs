// The page half of the retrain loop (issue 36, "Measured": label 5 of the extra NYU
// frames in the page, retrain from the page; loop_bench.sh runs it and evaluates): on a
// running findmug-web, the greedy user (greedy_user.mjs) labels each of the user's frames
// on the Label page from the model's prediction until `--target` of the labelled pixels
// agree with the reference labels, and saves through the page (key s); then the Retrain
// page trains on the chosen data folders with the page's settings field, waits for the
// job, presses Install and waits for findmugd's answer.
//
//   node loop_bench.mjs --url http://127.0.0.1:PORT/ --user-root I --frames 0029,0056 \
//     --truth DIR/label8 --train-roots 0,1 [--sets 'forest.seed=42'] [--target 0.9]
//     [--max-actions 300] [--json OUT.json] [--screenshots DIR]
//
// --user-root is the index of the user's folder among findmug-web's --data folders,
// --train-roots the folders ticked on the Retrain page, --sets the page's extra settings
// (comma-separated). The reference labels (--truth) are read by this side only, to
// choose the actions and count the agreement; the page never sees them. Each frame must
// reach the target (else exit 1). Prints a JSON summary (and writes it to --json):
// per frame actions, keys, page seconds, agreement at start and when saved; the training
// job's seconds (Train pressed to the page showing it finished) and Install's answer.
import fs from 'node:fs';
import path from 'node:path';
import { openPage, parseArgs } from './browser.mjs';
import { greedyRun, studyFrame } from './greedy_user.mjs';
import { frameData } from './label_page.mjs';
import { decodeGrey8 } from './png.mjs';

const args = parseArgs(process.argv.slice(2));
for (const key of ['url', 'user-root', 'frames', 'truth', 'train-roots']) {
  if (!args[key]) { console.error(`loop_bench: --${key} is required`); process.exit(2); }
}
const url = args.url.endsWith('/') ? args.url : args.url + '/';
const userRoot = Number(args['user-root']);
const target = Number(args.target || 0.9);
const maxActions = Number(args['max-actions'] || 300);
const trainRoots = args['train-roots'].split(',').map(Number);
const sets = args.sets ? args.sets.split(',') : [];
const check = (ok, what) => { if (!ok) throw new Error(what); };

// Labels `frame` greedily from the prediction to the target and saves it on the page.
async function labelAndSave(page, frame) {
  const data = await frameData(url, userRoot, frame);
  const truth = decodeGrey8(path.join(args.truth, frame + '.png')).pixels;
  const study = studyFrame(data, truth);
  const run = await greedyRun(page, { url, root: userRoot, frame, data, study, fromPrediction: true,
                                      stopAt: target, maxActions });
  check(run.mismatch === 0, `${frame}: the page's labels differ from this side's in ${run.mismatch} pixels`);
  check(run.final >= target, `${frame}: ${(100 * run.final).toFixed(1)} % after ${run.actions} actions, ` +
        `below the target ${(100 * target).toFixed(0)} %`);
  const t0 = performance.now();
  await page.$eval('#author', (a) => { a.value = 'loop-bench'; });
  await page.keyboard.press('s');
  await page.waitForFunction((n) => window.findmugLabel.saves === n || window.findmugLabel.error,
                             { timeout: 30000 }, 1);
  const error = await page.evaluate(() => window.findmugLabel.error);
  check(!error, `${frame}: save: ${error}`);
  const saveSeconds = (performance.now() - t0) / 1000;
  return { frame, patches: data.count, labelled: study.labelled, oracle: study.oracle,
           start: run.start, saved_agreement: run.final, actions: run.actions, keys: run.keys,
           kinds: run.kinds, page_seconds: run.seconds + saveSeconds };
}

async function retrain(page) {
  await page.goto(new URL('static/retrain.html', url).href, { waitUntil: 'load' });
  await page.waitForSelector('#folders input');
  for (const root of trainRoots) await page.click(`#folders input[data-root="${root}"]`);
  await page.$eval('#sets', (t, v) => { t.value = v; }, sets.join('\n'));
  const t0 = performance.now();
  await page.click('#train');  // the first job of this findmug-web: the state was idle
  await page.waitForFunction(() => window.findmugRetrain && ['succeeded', 'failed'].includes(window.findmugRetrain.state),
                             { timeout: 3600000, polling: 500 });
  const jobSeconds = (performance.now() - t0) / 1000;
  const job = await page.evaluate(() => window.findmugRetrain);
  check(job.state === 'succeeded' && job.model, 'findmug-train did not succeed: ' +
        await page.$eval('#output', (o) => o.textContent.slice(-2000)));
  const command = await page.$eval('#output', (o) => o.textContent.split('\n')[0]);
  await page.waitForFunction(() => !document.getElementById('install').disabled, { timeout: 10000 });
  const t1 = performance.now();
  await page.click('#install');
  await page.waitForFunction(() => document.getElementById('install-result').dataset.reload,
                             { timeout: 120000, polling: 200 });
  const installSeconds = (performance.now() - t1) / 1000;
  const result = await page.$eval('#install-result', (p) => ({ how: p.dataset.reload, text: p.textContent }));
  check(result.how === 'ok', 'findmugd did not take the model: ' + result.text);
  return { command, job_seconds: jobSeconds, trained_model: job.model, install_seconds: installSeconds,
           install_answer: result.text };
}

const { page, pageErrors, close } = await openPage(1200, 1000);
const summary = { target, frames: [] };
try {
  for (const frame of args.frames.split(',')) {
    const row = await labelAndSave(page, frame);
    summary.frames.push(row);
    console.error(`loop_bench: ${frame} ${(100 * row.start).toFixed(1)} % -> ${(100 * row.saved_agreement).toFixed(1)} % ` +
                  `in ${row.actions} actions (${JSON.stringify(row.kinds)}), ${row.page_seconds.toFixed(1)} s, saved`);
    if (args.screenshots) await page.screenshot({ path: path.join(args.screenshots, `label-${frame}.png`) });
  }
  summary.total_actions = summary.frames.reduce((a, f) => a + f.actions, 0);
  summary.total_page_seconds = summary.frames.reduce((a, f) => a + f.page_seconds, 0);
  summary.retrain = await retrain(page);
  console.error('loop_bench: ' + summary.retrain.install_answer);
  if (args.screenshots) await page.screenshot({ path: path.join(args.screenshots, 'retrain.png'), fullPage: true });
  check(pageErrors.length === 0, 'page errors: ' + pageErrors.join('; '));
} finally {
  await close();
}
console.log(JSON.stringify(summary));
if (args.json) fs.writeFileSync(args.json, JSON.stringify(summary, null, 1) + '\n');
