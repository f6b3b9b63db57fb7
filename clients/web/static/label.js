// findmug-web Label page: a dataset frame's oversegmentation. A click or a drag gives the
// patches under the pointer the chosen class, the region tool fills a smooth surface
// (neighbouring patches with close normals and colours), keys choose the class and the
// tool, z/y undo and redo whole strokes, "start from prediction" takes the model's labels,
// s saves label8/NAME.png through POST /api/label (refused when the file changed since it
// was read). Every change is written to the server's draft (drafts/NAME.json) as it is
// made; a draft left by an earlier page is offered on opening the frame.
// window.findmugLabel holds what the tests and the effort benchmark read.
'use strict';

const VOID = 255;
const NO_PATCH = 0xFFFF;
const KEYS = { '0': 0, '1': 1, '2': 2, '3': 3, '4': 4, '5': 5, '6': 6, '7': 7, x: VOID };
const state = window.findmugLabel = {
  ready: false, width: 0, height: 0, chosen: 4, tool: 'paint', saves: 0, lastSave: null,
  error: null, strokes: 0, draftsWritten: 0, draftError: null, draft: null, prediction: null,
};
const el = (id) => document.getElementById(id);
const canvas = el('label-view');
const ctx = canvas.getContext('2d');
let names = [], colors = [];
let image = null;      // ImageBitmap of rgb/NAME.png
let patches = null;    // Uint16Array, NO_PATCH = in no patch
let labels = null;     // Uint8Array, what will be saved
let patchPixels = [];  // patch -> Int32Array of pixel indices
let graph = null;      // {rgb: Float32Array(3N), normal: Float32Array(3N), neighbours: [[...]]}
let undoStack = [];    // strokes: {pixels: Int32Array, before: Uint8Array, after: Uint8Array}
let redoStack = [];
let stroke = null;     // the drag in progress: {patches: Set, pixels: [], before: [], id, last}
let baseMtime = null;
let root = 0, frame = '';
let drawQueued = false;

function setStatus(text, cls) {
  const s = el('status');
  s.textContent = text;
  s.className = 'badge ' + (cls || '');
}

function drawClasses() {
  const list = el('classes');
  list.textContent = '';
  const add = (id, name, rgb, key) => {
    const li = document.createElement('li');
    li.textContent = `${key} ${name}`;
    li.style.background = `rgb(${rgb[0]},${rgb[1]},${rgb[2]})`;
    li.style.color = '#fff';
    if (id === state.chosen) li.className = 'chosen';
    li.addEventListener('click', () => { state.chosen = id; drawClasses(); });
    list.appendChild(li);
  };
  names.forEach((n, i) => add(i, n, colors[i], String(i)));
  add(VOID, 'void', [0, 0, 0], 'x');
}

function redraw() {
  drawQueued = false;
  const w = state.width, h = state.height;
  ctx.drawImage(image, 0, 0, w, h);
  const base = ctx.getImageData(0, 0, w, h);
  const px = base.data;
  for (let i = 0, j = 0; i < labels.length; ++i, j += 4) {
    const c = labels[i] === VOID ? null : colors[labels[i]];
    if (c) {
      px[j] = (px[j] + c[0] * 2) / 3; px[j + 1] = (px[j + 1] + c[1] * 2) / 3; px[j + 2] = (px[j + 2] + c[2] * 2) / 3;
    }
    // Patch borders in white, so that a person sees what a click takes.
    const p = patches[i];
    const x = i % w;
    if ((x + 1 < w && patches[i + 1] !== p) || (i + w < patches.length && patches[i + w] !== p)) {
      px[j] = 255; px[j + 1] = 255; px[j + 2] = 255;
    }
  }
  ctx.putImageData(base, 0, 0);
}

function queueRedraw() {
  if (drawQueued) return;
  drawQueued = true;
  requestAnimationFrame(redraw);
}

// --- the draft: the whole label image after every change, one write at a time ---
let draftBusy = false, draftDirty = false;

function runs() {
  const out = [];
  for (let i = 0; i < labels.length;) {
    let j = i;
    while (j < labels.length && labels[j] === labels[i]) ++j;
    out.push([labels[i], j - i]);
    i = j;
  }
  return out;
}

async function writeDraft() {
  if (draftBusy) { draftDirty = true; return; }
  draftBusy = true;
  try {
    do {
      draftDirty = false;
      const body = { width: state.width, height: state.height, runs: runs(), strokes: state.strokes,
                     author: el('author').value || 'findmug-web', base_mtime_ns: baseMtime || '' };
      const res = await fetch(`/api/label/draft?root=${root}&frame=${encodeURIComponent(frame)}`,
                              { method: 'POST', headers: { 'Content-Type': 'application/json' },
                                body: JSON.stringify(body) });
      if (!res.ok) {
        state.draftError = (await res.json()).error;
        setStatus('draft not kept: ' + state.draftError, 'down');
      } else {
        state.draftsWritten += 1;
      }
    } while (draftDirty);
  } finally {
    draftBusy = false;
  }
}

// A finished stroke (one undo step): the pixels it changed, their labels before and after.
function commit(pixels, before) {
  if (!pixels.length) return;
  const p = Int32Array.from(pixels);
  const after = new Uint8Array(p.length);
  for (let k = 0; k < p.length; ++k) after[k] = labels[p[k]];
  undoStack.push({ pixels: p, before: Uint8Array.from(before), after });
  redoStack = [];
  changed();
}

function changed() {
  state.strokes += 1;
  queueRedraw();
  writeDraft();
}

// Gives the pixels of `patchList` class `id` as one stroke.
function assignPatches(patchList, id) {
  const pixels = [], before = [];
  for (const p of patchList) {
    for (const i of patchPixels[p]) { pixels.push(i); before.push(labels[i]); labels[i] = id; }
  }
  commit(pixels, before);
}

function undo() {
  const last = undoStack.pop();
  if (!last) return;
  last.pixels.forEach((p, k) => { labels[p] = last.before[k]; });
  redoStack.push(last);
  changed();
}

function redo() {
  const next = redoStack.pop();
  if (!next) return;
  next.pixels.forEach((p, k) => { labels[p] = next.after[k]; });
  undoStack.push(next);
  changed();
}

// --- the region tool: grow from the seed over neighbours close to the seed ---
function regionOf(seed, maxAngleDeg, maxColour) {
  const cosMax = Math.cos(maxAngleDeg * Math.PI / 180);
  const n = graph.normal, c = graph.rgb;
  const close = (q) => {
    const dot = n[3 * seed] * n[3 * q] + n[3 * seed + 1] * n[3 * q + 1] + n[3 * seed + 2] * n[3 * q + 2];
    if (dot < cosMax) return false;
    const dr = c[3 * seed] - c[3 * q], dg = c[3 * seed + 1] - c[3 * q + 1], db = c[3 * seed + 2] - c[3 * q + 2];
    return dr * dr + dg * dg + db * db <= maxColour * maxColour;
  };
  const inRegion = new Uint8Array(graph.neighbours.length);
  inRegion[seed] = 1;
  const out = [seed];
  for (let k = 0; k < out.length; ++k) {
    for (const q of graph.neighbours[out[k]]) {
      if (!inRegion[q] && close(q)) { inRegion[q] = 1; out.push(q); }
    }
  }
  return out;
}
state.regionOf = (seed) => regionOf(seed, Number(el('region-angle').value), Number(el('region-colour').value));

// --- pointer: paint (a drag, each patch it crosses once) or region fill ---
function pixelAt(e) {
  const r = canvas.getBoundingClientRect();
  const x = Math.floor((e.clientX - r.left) * state.width / r.width);
  const y = Math.floor((e.clientY - r.top) * state.height / r.height);
  return [Math.min(Math.max(x, 0), state.width - 1), Math.min(Math.max(y, 0), state.height - 1)];
}

function paintPatchAt(x, y) {
  const p = patches[y * state.width + x];
  if (p === NO_PATCH || stroke.patches.has(p)) return;  // no depth there: no patch to label
  stroke.patches.add(p);
  for (const i of patchPixels[p]) { stroke.pixels.push(i); stroke.before.push(labels[i]); labels[i] = stroke.id; }
  queueRedraw();
}

// Every pixel of the straight line between two pointer positions (Bresenham), so that a
// fast drag skips no patch.
function paintLine(x0, y0, x1, y1) {
  const dx = Math.abs(x1 - x0), dy = -Math.abs(y1 - y0);
  const sx = x0 < x1 ? 1 : -1, sy = y0 < y1 ? 1 : -1;
  let err = dx + dy;
  for (;;) {
    paintPatchAt(x0, y0);
    if (x0 === x1 && y0 === y1) break;
    const e2 = 2 * err;
    if (e2 >= dy) { err += dy; x0 += sx; }
    if (e2 <= dx) { err += dx; y0 += sy; }
  }
}

canvas.addEventListener('pointerdown', (e) => {
  if (!state.ready || e.button !== 0) return;
  const [x, y] = pixelAt(e);
  if (state.tool === 'region') {
    const p = patches[y * state.width + x];
    if (p !== NO_PATCH) assignPatches(state.regionOf(p), state.chosen);
    return;
  }
  canvas.setPointerCapture(e.pointerId);
  stroke = { patches: new Set(), pixels: [], before: [], id: state.chosen, last: [x, y] };
  paintPatchAt(x, y);
});
canvas.addEventListener('pointermove', (e) => {
  if (!stroke) return;
  const [x, y] = pixelAt(e);
  paintLine(stroke.last[0], stroke.last[1], x, y);
  stroke.last = [x, y];
});
const endStroke = () => {
  if (!stroke) return;
  const done = stroke;
  stroke = null;
  commit(done.pixels, done.before);
};
canvas.addEventListener('pointerup', endStroke);
canvas.addEventListener('pointercancel', endStroke);

// --- the model's prediction as the starting point (one stroke, undoable) ---
async function startFromPrediction() {
  if (!state.ready) return;
  const res = await fetch(`/api/label/prediction?root=${root}&frame=${encodeURIComponent(frame)}`);
  const answer = await res.json();
  if (!res.ok) {
    state.error = answer.error;
    setStatus('no prediction: ' + answer.error, 'down');
    return;
  }
  const pixels = [], before = [];
  answer.labels.forEach((id, p) => {
    for (const i of patchPixels[p]) { pixels.push(i); before.push(labels[i]); labels[i] = id; }
  });
  state.prediction = answer.model;
  commit(pixels, before);
  setStatus('started from the prediction of ' + answer.model, 'live');
}

async function save() {
  const body = { root, frame, width: state.width, height: state.height, runs: runs(),
                 author: el('author').value || 'findmug-web', base_mtime_ns: baseMtime };
  const res = await fetch('/api/label', { method: 'POST', headers: { 'Content-Type': 'application/json' },
                                          body: JSON.stringify(body) });
  const answer = await res.json();
  if (!res.ok) {
    state.error = answer.error;
    setStatus('not saved: ' + answer.error, 'down');
    return;
  }
  baseMtime = answer.mtime_ns;
  state.saves += 1;
  state.lastSave = answer;
  el('draft-bar').hidden = true;
  setStatus('saved ' + answer.saved, 'live');
}

function setTool(tool) {
  state.tool = tool;
  for (const r of document.querySelectorAll('input[name=tool]')) r.checked = r.value === tool;
}

document.addEventListener('keydown', (e) => {
  if (e.target.tagName === 'INPUT' && e.target.type !== 'radio') return;
  const key = e.key.toLowerCase();
  if ((e.ctrlKey || e.metaKey) && key === 'z') { e.preventDefault(); (e.shiftKey ? redo : undo)(); }
  else if ((e.ctrlKey || e.metaKey) && key === 'y') { e.preventDefault(); redo(); }
  else if (e.ctrlKey || e.metaKey || e.altKey) return;
  else if (e.key in KEYS) { state.chosen = KEYS[e.key]; drawClasses(); }
  else if (key === 'z') undo();
  else if (key === 'y') redo();
  else if (key === 's') save();
  else if (key === 'r') setTool('region');
  else if (key === 'p') setTool('paint');
});
el('undo').addEventListener('click', undo);
el('redo').addEventListener('click', redo);
el('save').addEventListener('click', save);
el('predict').addEventListener('click', () => startFromPrediction().catch(fail));
for (const r of document.querySelectorAll('input[name=tool]')) r.addEventListener('change', () => setTool(r.value));

// --- a draft left by an earlier page (or a crash): offered, not taken silently ---
async function offerDraft(q) {
  const bar = el('draft-bar');
  bar.hidden = true;
  state.draft = null;
  const res = await fetch('/api/label/draft?' + q);
  const reply = await res.json();
  if (res.ok && !reply.draft) return;
  const answer = res.ok ? reply.draft : reply;
  el('draft-restore').hidden = !res.ok;
  bar.hidden = false;
  if (!res.ok) {
    state.draft = { error: answer.error };
    el('draft-text').textContent = 'The draft of this frame cannot be used: ' + answer.error;
    return;
  }
  state.draft = { strokes: answer.strokes, updated_utc: answer.updated_utc, author: answer.author };
  el('draft-text').textContent = `A draft of this frame (${answer.strokes} strokes, by ` +
    `${answer.author}, ${answer.updated_utc}) was not saved.`;
  el('draft-restore').onclick = () => {
    let i = 0;
    for (const [id, count] of answer.runs) { labels.fill(id, i, i + count); i += count; }
    baseMtime = answer.base_mtime_ns || null;
    state.strokes = answer.strokes;
    undoStack = []; redoStack = [];
    state.draft.restored = true;
    bar.hidden = true;
    queueRedraw();
    setStatus('draft restored', 'live');
  };
  el('draft-discard').onclick = async () => {
    await fetch('/api/label/draft?' + q, { method: 'DELETE' });
    state.draft.discarded = true;
    bar.hidden = true;
  };
}

async function load() {
  state.ready = false;
  setStatus('loading ' + frame + ' (oversegmenting)…');
  const q = `root=${root}&frame=${encodeURIComponent(frame)}`;
  const info = await (await fetch('/api/label/frame?' + q)).json();
  if (info.error) throw new Error(info.error);
  const [patchRes, rgbRes, labelRes, graphRes] = await Promise.all([
    fetch('/api/label/patches.bin?' + q),
    fetch(`/api/data/file?root=${root}&path=rgb/${encodeURIComponent(frame)}.png`),
    fetch('/api/label/labels.bin?' + q),
    fetch('/api/label/graph?' + q)]);
  patches = new Uint16Array(await patchRes.arrayBuffer());
  image = await createImageBitmap(await rgbRes.blob());
  state.width = info.width;
  state.height = info.height;
  labels = new Uint8Array(info.width * info.height).fill(VOID);
  baseMtime = null;
  if (labelRes.ok) {
    const saved = new Uint8Array(await labelRes.arrayBuffer());
    if (saved.length !== labels.length) {
      throw new Error(`label8/${frame}.png has ${saved.length} pixels, the frame ${labels.length}`);
    }
    labels.set(saved);
    // The mtime it was read at (text: nanoseconds do not fit a JavaScript number), so
    // that a save never overwrites a newer file.
    baseMtime = info.label_mtime_ns;
  }
  const counts = new Int32Array(info.patches);
  patches.forEach((p) => { if (p !== NO_PATCH) counts[p] += 1; });
  patchPixels = Array.from(counts, (n) => new Int32Array(n));
  counts.fill(0);
  patches.forEach((p, i) => { if (p !== NO_PATCH) patchPixels[p][counts[p]++] = i; });
  const g = await graphRes.json();
  if (g.error) throw new Error(g.error);
  graph = { rgb: Float32Array.from(g.rgb), normal: Float32Array.from(g.normal),
            neighbours: Array.from({ length: g.patches }, () => []) };
  for (let k = 0; k < g.edges.length; k += 2) {
    graph.neighbours[g.edges[k]].push(g.edges[k + 1]);
    graph.neighbours[g.edges[k + 1]].push(g.edges[k]);
  }
  undoStack = []; redoStack = [];
  state.strokes = 0;
  canvas.width = info.width;
  canvas.height = info.height;
  el('frame-name').textContent = frame;
  el('patch-count').textContent = `${info.patches} patches`;
  redraw();
  await offerDraft(q);
  state.ready = true;
  setStatus('ready', 'live');
}
// The labels on the page, and whether every change is in the draft on the server (for
// the tests and the effort benchmark).
state.labels = () => Array.from(labels);
state.draftIdle = () => !draftBusy;

async function start() {
  const params = new URLSearchParams(location.search);
  const live = await (await fetch('/api/live')).json();
  names = live.label_names;
  colors = live.label_colors;
  drawClasses();
  const folders = (await (await fetch('/api/data')).json()).folders;
  for (const f of folders) el('root').add(new Option(f.name, f.root));
  root = Number(params.get('root') || 0);
  el('root').value = String(root);
  const frames = (await (await fetch('/api/label/frames?root=' + root)).json()).frames || [];
  for (const f of frames) el('frame').add(new Option(f.name + (f.labelled ? ' ✓' : ''), f.name));
  frame = params.get('frame') || (frames[0] && frames[0].name) || '';
  el('frame').value = frame;
  el('frame').addEventListener('change', () => { frame = el('frame').value; load().catch(fail); });
  el('root').addEventListener('change', () => { location.search = '?root=' + el('root').value; });
  if (frame) await load();
}

function fail(e) {
  state.error = String(e);
  setStatus('error: ' + e.message, 'down');
}
start().catch(fail);
