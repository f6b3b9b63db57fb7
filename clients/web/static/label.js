// findmug-web Label page: a dataset frame's oversegmentation; a click gives the clicked
// patch the chosen class, keys choose the class, z undoes, s saves label8/NAME.png
// through POST /api/label (refused when the file changed since it was read).
// window.findmugLabel holds what the tests read.
'use strict';

const VOID = 255;
const KEYS = { '0': 0, '1': 1, '2': 2, '3': 3, '4': 4, '5': 5, '6': 6, '7': 7, x: VOID };
const state = window.findmugLabel = {
  ready: false, width: 0, height: 0, chosen: 4, saves: 0, lastSave: null, error: null,
};
const el = (id) => document.getElementById(id);
const canvas = el('label-view');
const ctx = canvas.getContext('2d');
let names = [], colors = [];
let image = null;      // ImageBitmap of rgb/NAME.png
let patches = null;    // Uint16Array, 65535 = in no patch
let labels = null;     // Uint8Array, what will be saved
let patchPixels = [];  // patch -> pixel indices
let history = [];      // [{pixels, before}] for undo
let baseMtime = null;
let root = 0, frame = '';

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

function assign(pixels, id) {
  const before = new Uint8Array(pixels.length);
  pixels.forEach((p, k) => { before[k] = labels[p]; labels[p] = id; });
  history.push({ pixels, before });
  redraw();
}

function undo() {
  const last = history.pop();
  if (!last) return;
  last.pixels.forEach((p, k) => { labels[p] = last.before[k]; });
  redraw();
}

// Row-major runs [[id, count], ...] as POST /api/label takes them.
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
  setStatus('saved ' + answer.saved, 'live');
}

canvas.addEventListener('click', (e) => {
  if (!state.ready) return;
  const r = canvas.getBoundingClientRect();
  const x = Math.floor((e.clientX - r.left) * state.width / r.width);
  const y = Math.floor((e.clientY - r.top) * state.height / r.height);
  if (x < 0 || y < 0 || x >= state.width || y >= state.height) return;
  const p = patches[y * state.width + x];
  if (p === 0xFFFF) return;  // no depth there: no patch to label
  assign(patchPixels[p], state.chosen);
});

document.addEventListener('keydown', (e) => {
  if (e.target.tagName === 'INPUT') return;
  if (e.key in KEYS) { state.chosen = KEYS[e.key]; drawClasses(); }
  else if (e.key === 'z') undo();
  else if (e.key === 's') save();
});
el('undo').addEventListener('click', undo);
el('save').addEventListener('click', save);

async function load() {
  state.ready = false;
  setStatus('loading ' + frame + ' (oversegmenting)…');
  const q = `root=${root}&frame=${encodeURIComponent(frame)}`;
  const info = await (await fetch('/api/label/frame?' + q)).json();
  if (info.error) throw new Error(info.error);
  const [patchRes, rgbRes, labelRes] = await Promise.all([
    fetch('/api/label/patches.bin?' + q),
    fetch(`/api/data/file?root=${root}&path=rgb/${encodeURIComponent(frame)}.png`),
    fetch('/api/label/labels.bin?' + q)]);
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
  patchPixels = Array.from({ length: info.patches }, () => []);
  patches.forEach((p, i) => { if (p !== 0xFFFF) patchPixels[p].push(i); });
  history = [];
  canvas.width = info.width;
  canvas.height = info.height;
  el('frame-name').textContent = frame;
  el('patch-count').textContent = `${info.patches} patches`;
  redraw();
  state.ready = true;
  setStatus('ready', 'live');
}

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
