// Prints the retrain loop's result (loop_bench.sh) as Markdown: the page's labelling per
// frame, the training job, and findmug-eval's figures on the held-out frames per model.
//   node loop_report.mjs PAGE.json NAME=EVAL.json [NAME=EVAL.json ...]
import fs from 'node:fs';

const [pageFile, ...evals] = process.argv.slice(2);
const page = JSON.parse(fs.readFileSync(pageFile, 'utf8'));
const pct = (x) => (typeof x === 'number' ? (100 * x).toFixed(1) + ' %' : '–');

console.log(`Labelling on the Label page, from the prediction to ${pct(page.target)} agreement:\n`);
console.log('| frame | patches | prediction alone | saved at | actions (click/region/drag) | keys | page s |');
console.log('|---|---|---|---|---|---|---|');
for (const f of page.frames) {
  const k = f.kinds;
  console.log(`| ${f.frame} | ${f.patches} | ${pct(f.start)} | ${pct(f.saved_agreement)} | ` +
              `${f.actions} (${k.click}/${k.region}/${k.drag}, +1 prediction) | ${f.keys} | ${f.page_seconds.toFixed(1)} |`);
}
console.log(`\nTotal ${page.total_actions} actions, ${page.total_page_seconds.toFixed(1)} s of page time.`);
const r = page.retrain;
console.log(`Retrain page: \`${r.command.replace(/^\$ /, '')}\`\n` +
            `job ${r.job_seconds.toFixed(1)} s (Train pressed to finished on the page); Install ` +
            `${r.install_seconds.toFixed(1)} s to findmugd's answer: "${r.install_answer}"\n`);

const reports = evals.map((e) => {
  const [name, file] = e.split('=');
  return { name, report: JSON.parse(fs.readFileSync(file, 'utf8')) };
});
const labels = Object.keys(reports[0].report.mrf.per_class);
console.log('| model | MRF global | MRF class avg | forest global | forest class avg | ' +
            labels.map((l) => `MRF ${l}`).join(' | ') + ' |');
console.log('|---|---|---|---|---|' + labels.map(() => '---').join('|') + '|');
for (const { name, report } of reports) {
  console.log(`| ${name} | ${pct(report.mrf.global)} | ${pct(report.mrf.class_average)} | ` +
              `${pct(report.forest.global)} | ${pct(report.forest.class_average)} | ` +
              labels.map((l) => pct(report.mrf.per_class[l])).join(' | ') + ' |');
}
