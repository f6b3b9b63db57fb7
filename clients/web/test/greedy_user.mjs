// The greedy scripted user of findmug-web's Label page (issue 36, "Measured"), shared by
// the labelling-effort benchmark (label_effort.mjs), the retrain-loop benchmark
// (loop_bench.mjs) and the Retrain page's browser test: at every step it takes the page
// action that fixes the most labelled pixels still disagreeing with the reference labels
// (net: pixels fixed minus pixels broken):
//   - a patch click (paint tool) on any patch, in any class;
//   - a region fill (region tool, the page's default limits) from any patch as seed;
//   - a straight drag (paint tool) between two of the 30 patches with the largest gain;
// it presses the tool and class keys when they change (counted apart, not as actions).
// "Start from prediction" is the first action of a run from the prediction. Page time is
// the wall time from the first key of an action until the page has applied it and written
// its draft (window.findmugLabel: strokes, draftIdle), summed over the actions; the user's
// own search is not counted. The agreement is counted on the labelled (non-void)
// reference pixels inside NYU's valid border (rows 44..470, columns 40..600, 0-based, as
// findmug-train reads NYU frames); pixels without depth are in no patch and cannot be
// labelled on the page. This side keeps its own copy of the labels the actions must give.
import {
  VOID, canvasActions, differences, patchesOnLine, regionOf, settled,
} from './label_page.mjs';

export const CLASSES = 8;
const DRAG_CANDIDATES = 30;
export const BORDER = { top: 44, bottom: 470, left: 40, right: 600 };

// The greedy user's model of a frame (frameData's answer and the reference label8 pixels).
// Per patch: NYU's labelled pixels per class (inside the border), a pixel to click (well
// inside the patch, near its centre), and the regions a fill from it takes.
export function studyFrame(data, truth) {
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
export function bestAction(data, study, current) {
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

// One run on the Label page of `url` (findmug-web), frame `frame` of data folder `root`:
// the frame is opened with its draft removed, then the greedy user acts until `stopAt` of
// the labelled pixels agree, no action gains, or after `maxActions`. Returns the actions
// and page seconds at 90 % and 95 %, the kinds of action, and `mismatch`: pixels where
// this side's account and the page's labels differ at the end (0 when they agree).
export async function greedyRun(page, { url, root = 0, frame, data, study, fromPrediction,
                                        stopAt = 0.95, maxActions = 300 }) {
  await fetch(`${url}api/label/draft?root=${root}&frame=${frame}`, { method: 'DELETE' });
  await page.goto(`${url}label?root=${root}&frame=${frame}`, { waitUntil: 'load' });
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
    const predicted = (await (await fetch(`${url}api/label/prediction?root=${root}&frame=${frame}`)).json()).labels;
    const t0 = performance.now();
    await page.click('#predict');
    await settled(page, ++strokes);
    pageMs += performance.now() - t0;
    ++actions; ++kinds.prediction;
    predicted.forEach((c, p) => assign([p], c));
  }
  const startShare = note();
  let tool = 'paint', chosen = await page.evaluate(() => window.findmugLabel.chosen);
  while (note() < stopAt && actions < maxActions) {
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
