// The Retrain page on a running findmug-web (tests/integration/web_retrain_test.sh):
// cross-validate with a tiny forest and check the report's figures and confusion are
// shown, cancel a training, train again to the end, Install, and wait until findmugd's
// status says it runs the new model. Saves OUT/retrain.png.
//   node retrain_test.mjs --url http://127.0.0.1:PORT/ --out DIR
import path from 'node:path';
import { openPage, parseArgs } from './browser.mjs';

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
  await page.goto(new URL('static/retrain.html', args.url).href, { waitUntil: 'load' });
  await page.waitForSelector('#folders input');
  await page.click('#folders input');
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

  // Train to the end, then Install: findmugd reloads it.
  await page.click('#train');
  job = await waitState(['succeeded', 'failed'], 600000);
  check(job.state === 'succeeded' && job.model, 'findmug-train did not succeed');
  await page.waitForFunction(() => !document.getElementById('install').disabled, { timeout: 10000 });
  await page.click('#install');
  await page.waitForFunction(() => document.getElementById('install-result').dataset.reload,
                             { timeout: 60000, polling: 200 });
  const result = await page.$eval('#install-result', (p) => ({ how: p.dataset.reload, text: p.textContent }));
  check(result.how === 'ok', 'findmugd did not take the model: ' + result.text);
  await page.screenshot({ path: path.join(args.out, 'retrain.png'), fullPage: true });
  check(pageErrors.length === 0, 'page errors: ' + pageErrors.join('; '));
  console.log('retrain page: ' + figures.join(' | ') + ' — ' + result.text);
} finally {
  await close();
}
