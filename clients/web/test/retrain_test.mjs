// The loop on a running findmug-web (tests/integration/web_retrain_test.sh): the greedy
// user (greedy_user.mjs) labels the user's frame on the Label page from the prediction
// with a few actions and saves it (the written label8/ PNG checked against the page's
// labels pixel for pixel); on the Retrain page, cross-validate the shared folder with a
// tiny forest and check the report's figures and confusion are shown, cancel a training,
// train on the shared folder and the user's, Install, and wait until findmugd's status
// says it runs the new model. Prints the trained model's id (from findmug-train's output
// on the page) and findmugd's answer; saves OUT/retrain.png.
//   node retrain_test.mjs --url http://127.0.0.1:PORT/ --out DIR --user-dir DIR
//     --user-frame NAME --truth DIR/label8 [--max-actions 6]
import path from 'node:path';
import { openPage, parseArgs } from './browser.mjs';
import { greedyRun, studyFrame } from './greedy_user.mjs';
import { differences, frameData } from './label_page.mjs';
import { decodeGrey8 } from './png.mjs';

const args = parseArgs(process.argv.slice(2));
const { page, pageErrors, close } = await openPage(1200, 1000);
const check = (ok, what) => {
  if (!ok) throw new Error(what);
};
const waitState = async (states, timeoutMs) => {
  await page.waitForFunction((s) => window.findmugRetrain && s.includes(window.findmugRetrain.state),
                             { timeout: timeoutMs, polling: 200 }, states);
  return page.evaluate(() => window.findmugRetrain);
};
try {
  // The user's frame (data folder 1), labelled and saved on the Label page.
  const url = new URL('/', args.url).href;
  const frame = args['user-frame'];
  const data = await frameData(url, 1, frame);
  const study = studyFrame(data, decodeGrey8(path.join(args.truth, frame + '.png')).pixels);
  const run = await greedyRun(page, { url, root: 1, frame, data, study, fromPrediction: true,
                                      stopAt: 1, maxActions: Number(args['max-actions'] || 6) });
  check(run.mismatch === 0, `the page's labels differ from the greedy user's in ${run.mismatch} pixels`);
  check(run.final > run.start, `${run.actions} actions did not raise the agreement from ${run.start}`);
  await page.keyboard.press('s');
  await page.waitForFunction(() => window.findmugLabel.saves === 1 || window.findmugLabel.error, { timeout: 30000 });
  check(!(await page.evaluate(() => window.findmugLabel.error)), 'the save failed');
  const onPage = Uint8Array.from(await page.evaluate(() => window.findmugLabel.labels()));
  const written = decodeGrey8(path.join(args['user-dir'], 'label8', frame + '.png')).pixels;
  const diff = differences(onPage, written);
  check(diff.count === 0, `label8/${frame}.png differs from the page in ${diff.count} pixels (first ${diff.first})`);
  console.log(`label page: ${frame} from the prediction ${(100 * run.start).toFixed(1)} % -> ` +
              `${(100 * run.final).toFixed(1)} % in ${run.actions} actions, saved`);

  await page.goto(new URL('static/retrain.html', args.url).href, { waitUntil: 'load' });
  await page.waitForSelector('#folders input');
  await page.click('#folders input[data-root="0"]');
  await page.$eval('#sets', (t) => { t.value = 'forest.num_trees=3\nforest.max_depth=6\nforest.seed=7'; });

  // Cross-validation: findmug-eval's report on the page.
  await page.click('#eval');
  let job = await waitState(['succeeded', 'failed'], 600000);
  check(job.state === 'succeeded' && job.tool === 'eval', 'findmug-eval did not succeed: ' +
        await page.$eval('#output', (o) => o.textContent.slice(-2000)));
  const figures = await page.$$eval('#figures tbody tr', (rows) => rows.map((r) => r.textContent));
  check(figures.length >= 2 && figures.every((f) => f.includes('%')), 'no figures: ' + figures);
  const confusionRows = await page.$$eval('#confusion tr', (rows) => rows.length);
  check(confusionRows === 9, `confusion has ${confusionRows} rows, expected a header and 8 classes`);
  const reportGlobal = job.report.mrf.global;
  check(figures.some((f) => f.includes((100 * reportGlobal).toFixed(1))), 'the MRF figure is not the report\'s');

  // Cancel: a training stopped on request (a forest big enough to be still running).
  const tiny = await page.$eval('#sets', (t) => t.value);
  await page.$eval('#sets', (t) => { t.value = 'forest.num_trees=500\nforest.max_depth=30'; });
  await page.click('#train');
  await page.waitForFunction(() => window.findmugRetrain && window.findmugRetrain.state === 'running',
                             { timeout: 30000, polling: 100 });
  await page.click('#cancel');
  job = await waitState(['cancelled', 'succeeded', 'failed'], 60000);
  check(job.state === 'cancelled', 'cancel gave ' + job.state);
  check(await page.$eval('#install', (b) => b.disabled), 'Install enabled without a trained model');
  await page.$eval('#sets', (t, v) => { t.value = v; }, tiny);

  // Train on both folders to the end, then Install: findmugd reloads it.
  await page.click('#folders input[data-root="1"]');
  await page.click('#train');
  job = await waitState(['succeeded', 'failed'], 600000);
  check(job.state === 'succeeded' && job.model, 'findmug-train did not succeed');
  const output = await page.$eval('#output', (o) => o.textContent);
  check(output.split('\n')[0].includes(`--data ${args['user-dir']}`), 'the user folder is not in the training: ' +
        output.split('\n')[0]);
  const trainedId = (output.match(/\(id ([0-9a-f]{8})\)/) || [])[1];
  check(trainedId, 'no model id in findmug-train\'s output on the page');
  await page.waitForFunction(() => !document.getElementById('install').disabled, { timeout: 10000 });
  await page.click('#install');
  await page.waitForFunction(() => document.getElementById('install-result').dataset.reload,
                             { timeout: 60000, polling: 200 });
  const result = await page.$eval('#install-result', (p) => ({ how: p.dataset.reload, text: p.textContent }));
  check(result.how === 'ok', 'findmugd did not take the model: ' + result.text);
  check(result.text.includes(`:${trainedId} `), `findmugd's answer does not name the trained model ${trainedId}: ${result.text}`);
  await page.screenshot({ path: path.join(args.out, 'retrain.png'), fullPage: true });
  check(pageErrors.length === 0, 'page errors: ' + pageErrors.join('; '));
  console.log('retrain page: ' + figures.join(' | ') + ' — ' + result.text);
  console.log('trained model id ' + trainedId);
} finally {
  await close();
}
