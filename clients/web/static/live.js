// findmug-web live page: polls /api/live, draws the label image over the camera image,
// the tables (hulls, numbered search positions) over it and from above, the fused semantic
// map from above under the table map (when findmugd publishes it), the table-top object
// candidates over the camera image (click one to teach it: the command teach), the answer
// to a find, and the status.
// Plain browser JavaScript, no libraries. window.findmugLive holds what the tests read.
'use strict';

const SVG_NS = 'http://www.w3.org/2000/svg';
const POLL_MS = 50;          // ask for news 20 times a second; draw only what changed
const STALE_MS = 3000;       // no new label image for this long: "stale"

const live = window.findmugLive = {
  draws: 0,            // label images drawn
  lastSeq: null,
  drawTimes: [],       // Date.now() of the last draws
  publishToPageMs: [], // page time of a draw minus the daemon's publish time (utime + latency)
  receiveToPageMs: [], // page time of a draw minus findmug-web's receive time
  hullsDrawn: 0,       // table hulls on the camera view in the last drawing
  candidates: [],      // candidates drawn over the camera view: {seq, index, box: [x0, y0, x1, y1] (image
                       // pixels), cut (by the image border), height (above the top, m), extents (m)}
  teachResult: null,   // the daemon's answer to the page's last teach: {ok, text}
  foundDrawn: null,    // the found object drawn named on the camera view: {seq, index}
  findResult: null,    // the daemon's answer to the page's last find (GET /api/live's "find")
  semanticMapSeq: null,     // the semantic map drawn under the map panel (its seq)
  semanticMapCells: 0,      // its floor cells with a label
  semanticMapCanvas: null,  // its raster, one pixel per cell (row 0 = highest y)
  errors: 0,
};

const el = (id) => document.getElementById(id);
const view = el('view');
const viewCtx = view.getContext('2d');
const labelCanvas = document.createElement('canvas');
let palette = null;
let legendDone = false;
let lastLive = null;
let lastDrawMs = 0;
let lastStatusStamp, lastBadCount, lastTableMapSeq;

function svg(tag, attrs, parent) {
  const node = document.createElementNS(SVG_NS, tag);
  for (const [k, v] of Object.entries(attrs || {})) node.setAttribute(k, v);
  if (parent) parent.appendChild(node);
  return node;
}

function keep(list, value, n = 300) {
  list.push(value);
  if (list.length > n) list.shift();
}

function drawLegend(names, colors) {
  const legend = el('legend');
  legend.textContent = '';
  const add = (name, rgb) => {
    const li = document.createElement('li');
    const sw = document.createElement('span');
    sw.className = 'swatch';
    sw.style.background = `rgb(${rgb[0]},${rgb[1]},${rgb[2]})`;
    li.appendChild(sw);
    li.appendChild(document.createTextNode(name));
    legend.appendChild(li);
  };
  names.forEach((name, i) => add(name, colors[i]));
  add('void (no depth)', [0, 0, 0]);
  for (const [cls, text] of [['reachable', 'search position (visiting order)'],
                             ['unreachable', 'unreachable position']]) {
    const li = document.createElement('li');
    const s = svg('svg', { width: 16, height: 16, class: 'search-position ' + cls });
    svg('circle', { cx: 8, cy: 8, r: 6 }, s);
    li.appendChild(s);
    li.appendChild(document.createTextNode(text));
    legend.appendChild(li);
  }
  legendDone = true;
}

// Base-frame point -> image pixel with the camera the daemon used for this frame.
function projector(camera) {
  const m = camera.camera_to_base;  // rows of [R | t]
  return (x, y, z) => {
    const d = [x - m[0][3], y - m[1][3], z - m[2][3]];
    // p_camera = R^T (p_base - t)
    const cx = m[0][0] * d[0] + m[1][0] * d[1] + m[2][0] * d[2];
    const cy = m[0][1] * d[0] + m[1][1] * d[1] + m[2][1] * d[2];
    const cz = m[0][2] * d[0] + m[1][2] * d[1] + m[2][2] * d[2];
    if (cz < 0.1) return null;
    return [camera.fx * cx / cz + camera.cx, camera.fy * cy / cz + camera.cy];
  };
}

function drawPosition(parent, x, y, p, radius) {
  const g = svg('g', { class: 'search-position ' + (p.reachable ? 'reachable' : 'unreachable') }, parent);
  svg('circle', { cx: x, cy: y, r: radius }, g);
  if (p.order > 0) {
    const t = svg('text', { x: x, y: y }, g);
    t.textContent = String(p.order);
  } else {
    const title = svg('title', {}, g);
    title.textContent = p.reason || 'unreachable';
  }
  return g;
}

// The image box of a candidate: its footprint box from the top of its table to its top,
// projected; null when behind the camera.
function candidateBox(project, o, topHeight) {
  const [ax, ay] = o.major_axis;
  const corners = [];
  for (const [s, t] of [[1, 1], [1, -1], [-1, 1], [-1, -1]]) {
    const x = o.center[0] + s * o.extents[0] * ax - t * o.extents[1] * ay;
    const y = o.center[1] + s * o.extents[0] * ay + t * o.extents[1] * ax;
    for (const z of [topHeight, topHeight + o.height_above_top]) {
      const p = project(x, y, z);
      if (!p) return null;
      corners.push(p);
    }
  }
  const xs = corners.map((p) => p[0]), ys = corners.map((p) => p[1]);
  return [Math.min(...xs) - 2, Math.min(...ys) - 2, Math.max(...xs) + 2, Math.max(...ys) + 2];
}

// The frame's object candidates (FINDMUG_OBJECTS of the same seq) as dashed boxes; those
// cut by the image border grey (the daemon refuses to teach them).
function drawCameraObjects(state, project, overlay) {
  live.candidates = [];
  const objects = state.objects, tables = state.tables;
  if (!objects || objects.seq !== state.labels.seq || !tables || tables.seq !== objects.seq) return;
  // The object the page asked to find, in the frame the answer saw it in: the candidate
  // nearest that place on the map floor (within 10 cm), drawn with the name and the
  // daemon's score. (objects_t does not carry the names the daemon gives.)
  const f = live.findResult;
  let found = null;
  if (f && f.result === 'seen' && f.seen.utime === objects.utime) {
    let best = 0.1;
    for (const o of objects.objects) {
      if (!o.map_centroid) continue;
      const d = Math.hypot(o.map_centroid[0] - f.seen.position[0], o.map_centroid[1] - f.seen.position[1]);
      if (d < best) { best = d; found = o; }
    }
  }
  for (const o of objects.objects) {
    const table = tables.tables[o.table];
    if (!table) continue;
    const box = candidateBox(project, o, table.top_height);
    if (!box) continue;
    const cut = (o.truncation & 2) !== 0;
    const isFound = o === found;
    const rect = svg('rect', { class: 'candidate' + (cut ? ' cut' : '') + (isFound ? ' found' : ''), x: box[0],
                               y: box[1], width: box[2] - box[0], height: box[3] - box[1], 'data-index': o.index }, overlay);
    svg('title', {}, rect).textContent =
      `candidate ${o.index}: ${fmt(100 * o.height_above_top, 0)} cm tall, ${o.point_count} points` +
      (cut ? ', cut by the image border (cannot be taught from this frame)' : '');
    // The label above the box, or inside it at the image's top edge.
    const t = svg('text', { class: 'candidate-label' + (isFound ? ' found' : ''), x: Math.max(2, box[0]),
                            y: box[1] > 16 ? box[1] - 3 : Math.max(box[1], 0) + 14 }, overlay);
    t.textContent = isFound ? `${f.name} (${fmt(f.seen.score, 2)})` : String(o.index) + (cut ? ' cut' : '');
    if (isFound) live.foundDrawn = { seq: objects.seq, index: o.index, box };
    live.candidates.push({ seq: objects.seq, index: o.index, box, cut, height: o.height_above_top,
                           extents: o.extents });
  }
  live.objectsSeq = objects.seq;
}

function drawCameraTables(state) {
  const overlay = el('overlay');
  overlay.textContent = '';
  const labels = state.labels;
  let hulls = 0;
  const tables = state.tables;
  live.candidates = [];
  if (!labels || !tables || tables.seq !== labels.seq) {
    live.hullsDrawn = 0;
    return;
  }
  overlay.setAttribute('viewBox', `0 0 ${labels.width} ${labels.height}`);
  if (!labels.camera) {
    el('camera-note').textContent = `${tables.tables.length} tables not drawn: no floor for this frame`;
    live.hullsDrawn = 0;
    return;
  }
  const project = projector(labels.camera);
  for (const table of tables.tables) {
    const points = [];
    for (const [x, y] of table.hull) {
      const p = project(x, y, table.top_height);
      if (p) points.push(p);
    }
    if (points.length >= 2) {
      const text = points.map((p) => `${p[0].toFixed(1)},${p[1].toFixed(1)}`).join(' ');
      svg('polygon', { class: 'hull-shadow', points: text }, overlay);
      svg('polygon', { class: 'hull', points: text, 'data-table': table.id }, overlay);
      hulls += 1;
    }
    const c = project(table.center[0], table.center[1], table.top_height);
    if (c) {
      const name = 'T' + table.id;
      svg('rect', { class: 'table-id-box', x: c[0] - 3, y: c[1] - 15, width: 12 * name.length + 6, height: 20 }, overlay);
      const t = svg('text', { class: 'table-id', x: c[0], y: c[1] }, overlay);
      t.textContent = name;
    }
    for (const p of table.search_positions) {
      const q = project(p.x, p.y, 0);
      if (q) drawPosition(overlay, q[0], q[1], p, 9);
    }
  }
  live.hullsDrawn = hulls;
  drawCameraObjects(state, project, overlay);
}

async function drawLabels(state) {
  const labels = state.labels;
  const requests = [fetch('/api/labels.bin', { cache: 'no-store' })];
  if (labels.has_color) requests.push(fetch('/api/color.jpg', { cache: 'no-store' }));
  const [labelRes, colorRes] = await Promise.all(requests);
  if (!labelRes.ok) throw new Error('labels: HTTP ' + labelRes.status);
  const w = Number(labelRes.headers.get('X-Findmug-Width'));
  const h = Number(labelRes.headers.get('X-Findmug-Height'));
  const seq = Number(labelRes.headers.get('X-Findmug-Seq'));
  const ids = new Uint8Array(await labelRes.arrayBuffer());
  if (ids.length !== w * h) throw new Error('labels: size mismatch');
  let image = null;
  if (colorRes && colorRes.ok && Number(colorRes.headers.get('X-Findmug-Seq')) === seq) {
    image = await createImageBitmap(await colorRes.blob());
  }
  if (view.width !== w || view.height !== h) {
    view.width = w;
    view.height = h;
  }
  labelCanvas.width = w;
  labelCanvas.height = h;
  const lctx = labelCanvas.getContext('2d');
  const data = lctx.createImageData(w, h);
  // One 32-bit RGBA word per id (little-endian byte order, as every browser host has):
  // over a camera image, void pixels let the image through; without one they are black.
  const pal32 = new Uint32Array(256).fill(image ? 0 : 0xff000000);
  palette.forEach((c, id) => { pal32[id] = (0xff000000 | (c[2] << 16) | (c[1] << 8) | c[0]) >>> 0; });
  const out32 = new Uint32Array(data.data.buffer);
  for (let i = 0; i < ids.length; ++i) out32[i] = pal32[ids[i]];
  lctx.putImageData(data, 0, 0);
  viewCtx.globalAlpha = 1;
  viewCtx.fillStyle = '#000';
  viewCtx.fillRect(0, 0, w, h);
  if (image) viewCtx.drawImage(image, 0, 0, w, h);
  viewCtx.globalAlpha = image ? Number(el('alpha').value) : 1;
  viewCtx.drawImage(labelCanvas, 0, 0);
  viewCtx.globalAlpha = 1;
  el('camera-note').textContent = image ? '' : 'no camera image (findmugd: daemon.publish_color)';
  return seq;
}

function fmt(v, digits = 1) {
  return typeof v === 'number' && isFinite(v) ? v.toFixed(digits) : '–';
}

function drawStatus(state) {
  const s = state.status;
  const body = el('status').tBodies[0];
  body.textContent = '';
  const row = (k, v) => {
    const tr = body.insertRow();
    tr.insertCell().textContent = k;
    tr.insertCell().textContent = v;
  };
  if (!s) {
    row('daemon', 'no status received yet');
  } else {
    el('source').textContent = `${s.source} — ${s.source_state}`;
    row('source', `${s.source} (${s.source_state}, ${s.source_reconnects} reconnects)`);
    row('frames per second', `in ${fmt(s.input_fps)}, out ${fmt(s.output_fps)} (last ${fmt(s.window_s, 0)} s)`);
    row('frames', `${s.frames_received} received, ${s.frames_processed} published, ${s.frames_rejected} rejected, ${s.frames_lost_in_transit} lost in transit`);
    row('dropped', `${s.frames_dropped}: ${s.dropped_at_door} at the door, ${s.dropped_in_pipeline} in the pipeline, ${s.dropped_at_shutdown} at shutdown`);
    const budget = s.cpu_budget_cores > 0 ? ` of a budget of ${fmt(s.cpu_budget_cores, 2)}` : ' (no budget)';
    row('CPU', `${fmt(s.cpu_used_cores, 2)} cores${budget}, ${s.processing_threads} processing threads`);
    row('model', s.model_id);
    if (s.model_reloads || s.model_reloads_refused) {
      row('last model reload', `${s.last_reload_ok ? 'ok' : 'refused'} (request ${s.last_reload_request_id}): ${s.last_reload_result}`);
    }
    if (s.frames_collected || s.frames_collect_refused) {
      row('frames saved for labelling', `${s.frames_collected} (last ${s.last_collected_frame}), ${s.frames_collect_refused} refused`);
    }
    const o = s.objects;
    if (o && (o.frames || o.files_refused || o.find_requests)) {
      const r = o.refused;
      row('objects', `${o.frames} frames (${o.skipped} skipped), ${o.candidates} candidates matched, ${o.named} named; ` +
          `refused: ${r.too_big} too big, ${r.too_small} too small, ${r.colour} colour, ${r.not_round} not round, ` +
          `${r.shape} shape, ${r.few_points} too few points; ${o.mapped} mapped, ${o.files_refused} object files refused, ` +
          `find: ${o.find_requests} asked, ${o.find_answers} answers`);
    }
    if (s.last_error) row('last error', s.last_error);
    const stages = el('stages').tBodies[0];
    stages.textContent = '';
    for (const st of s.stages) {
      const tr = stages.insertRow();
      for (const v of [st.name, fmt(st.p50_ms), fmt(st.p95_ms), fmt(st.max_ms)]) tr.insertCell().textContent = v;
    }
  }
  const bad = Object.entries(state.bad_messages || {});
  if (bad.length) row('bad messages', bad.map(([c, n]) => `${c}: ${n}`).join(', ') + ' — ' + state.last_bad_message);
  drawPlots(state);
}

function plot(id, history, tEnd, span, series, dashedIndex) {
  const c = el(id);
  const ctx = c.getContext('2d');
  ctx.clearRect(0, 0, c.width, c.height);
  ctx.fillStyle = '#fafafa';
  ctx.fillRect(0, 0, c.width, c.height);
  let max = 0;
  for (const h of history) for (const s of series) max = Math.max(max, h[s.index] || 0);
  max = max > 0 ? max * 1.1 : 1;
  ctx.fillStyle = '#666';
  ctx.font = '10px sans-serif';
  ctx.fillText(fmt(max, max < 10 ? 2 : 0), 2, 10);
  for (const s of series) {
    ctx.strokeStyle = s.color;
    ctx.setLineDash(s.index === dashedIndex ? [4, 3] : []);
    ctx.beginPath();
    let first = true;
    for (const h of history) {
      const x = c.width * (1 - (tEnd - h[0]) / span);
      const y = c.height - (c.height - 12) * ((h[s.index] || 0) / max);
      if (first) ctx.moveTo(x, y); else ctx.lineTo(x, y);
      first = false;
    }
    ctx.stroke();
  }
  ctx.setLineDash([]);
}

function drawPlots(state) {
  const h = state.history || [];
  if (!h.length) return;
  const tEnd = h[h.length - 1][0];
  // The window the data fills, at least a minute, at most the history kept.
  const span = Math.min(state.history_s || 300, Math.max(60, tEnd - h[0][0]));
  // fields: t, input_fps, output_fps, cpu_used, cpu_budget, latency_p50_ms, latency_p95_ms, dropped, rejected
  plot('plot-fps', h, tEnd, span, [{ index: 1, color: '#999' }, { index: 2, color: '#1565c0' }]);
  plot('plot-latency', h, tEnd, span, [{ index: 5, color: '#1565c0' }, { index: 6, color: '#ef6c00' }]);
  plot('plot-cpu', h, tEnd, span, [{ index: 3, color: '#1565c0' }, { index: 4, color: '#c62828' }], 4);
  plot('plot-drops', h, tEnd, span, [{ index: 7, color: '#c62828' }, { index: 8, color: '#6a1b9a' }]);
}

// The semantic map from above (GET /api/semantic_map.bin: label plane, confidence plane;
// clients/semantic_map_picture.hpp): one pixel per floor cell in its label's colour, faded
// towards white by how little the map is sure of it, as findmug-label-viewer draws it.
async function fetchSemanticMap(meta) {
  const res = await fetch('/api/semantic_map.bin', { cache: 'no-store' });
  if (!res.ok) throw new Error('semantic map: HTTP ' + res.status);
  const bytes = new Uint8Array(await res.arrayBuffer());
  const w = Number(res.headers.get('X-Findmug-Width')), h = Number(res.headers.get('X-Findmug-Height'));
  if (bytes.length !== 2 * w * h) throw new Error('semantic map: ' + bytes.length + ' bytes for ' + w + 'x' + h);
  const canvas = document.createElement('canvas');
  canvas.width = Math.max(1, w);
  canvas.height = Math.max(1, h);
  const ctx = canvas.getContext('2d');
  const image = ctx.createImageData(canvas.width, canvas.height);
  let cells = 0;
  for (let i = 0; i < w * h; ++i) {
    const label = bytes[i];
    if (label >= palette.length) continue;
    const keep = 0.25 + 0.75 * bytes[w * h + i] / 255;
    const c = palette[label];
    for (let k = 0; k < 3; ++k) image.data[4 * i + k] = Math.round(255 - keep * (255 - c[k]));
    image.data[4 * i + 3] = 255;
    ++cells;
  }
  ctx.putImageData(image, 0, 0);
  live.semanticMapCanvas = canvas;
  live.semanticMapCells = cells;
  live.semanticMapSeq = Number(res.headers.get('X-Findmug-Seq'));
  live.semanticMapUrl = canvas.toDataURL();
  live.semanticMapMeta = { ...meta, width: w, height: h };
}

function drawMap(state) {
  const map = el('map');
  map.textContent = '';
  const mode = el('map-frame').value;
  const useMap = mode === 'auto' && state.table_map && state.table_map.map_pose;
  const message = useMap ? state.table_map : state.tables;
  if (!message) {
    el('map-note').textContent = 'no tables received yet';
    return;
  }
  const semantic = useMap && live.semanticMapUrl && live.semanticMapMeta.width > 0 ? live.semanticMapMeta : null;
  el('map-note').textContent = useMap
    ? `persistent table map: ${message.tables.length} confirmed tables (map frame)` +
      (semantic ? `; semantic map of ${semantic.frames} frames, ${semantic.voxels} voxels: ` +
                  'the label on top in each floor cell, faded where the map is unsure' : '')
    : `tables of frame ${message.seq} around the robot (base frame: x forward, y left)`;
  const tables = message.tables.map((t) => (useMap && t.map ? { id: t.id, ...t.map, viewpoints: t.viewpoints, sightings: t.sightings } : t));
  const robot = useMap ? message.map_pose : { x: 0, y: 0, yaw: 0 };
  let xs = [robot.x], ys = [robot.y];
  for (const t of tables) for (const [x, y] of t.hull) { xs.push(x); ys.push(y); }
  let raster = null;
  if (semantic) {
    // Cell (i, j) covers [(i - 0.5) v, (i + 0.5) v] x [(j - 0.5) v, (j + 0.5) v].
    const v = semantic.voxel_size_m;
    raster = { x0: (semantic.min_i - 0.5) * v, y1: (semantic.max_j + 0.5) * v,
               w: semantic.width * v, h: semantic.height * v };
    xs.push(raster.x0, raster.x0 + raster.w);
    ys.push(raster.y1 - raster.h, raster.y1);
  }
  const minX = Math.min(...xs) - 1, maxX = Math.max(...xs) + 1;
  const minY = Math.min(...ys) - 1, maxY = Math.max(...ys) + 1;
  const size = Math.max(4, maxX - minX, maxY - minY);
  const cx = (minX + maxX) / 2, cy = (minY + maxY) / 2;
  // SVG y grows downwards: a point (x, y) is drawn at (x, -y).
  map.setAttribute('viewBox', `${cx - size / 2} ${-cy - size / 2} ${size} ${size}`);
  for (let g = Math.floor(cx - size / 2); g <= cx + size / 2; ++g) {
    svg('line', { class: g === 0 ? 'axis' : 'grid', x1: g, x2: g, y1: -cy - size / 2, y2: -cy + size / 2 }, map);
  }
  for (let g = Math.floor(cy - size / 2); g <= cy + size / 2; ++g) {
    svg('line', { class: g === 0 ? 'axis' : 'grid', y1: -g, y2: -g, x1: cx - size / 2, x2: cx + size / 2 }, map);
  }
  if (raster) {
    svg('image', { class: 'semantic-map', href: live.semanticMapUrl, x: raster.x0, y: -raster.y1,
                   width: raster.w, height: raster.h, preserveAspectRatio: 'none' }, map);
  }
  for (const t of tables) {
    const pts = t.hull.map(([x, y]) => `${x.toFixed(3)},${(-y).toFixed(3)}`).join(' ');
    svg('polygon', { class: raster ? 'hull over-map' : 'hull', points: pts, 'data-table': t.id }, map);
    const label = svg('text', { class: 'table-id', x: t.center[0], y: -t.center[1] }, map);
    label.textContent = 'T' + t.id;
    if (t.viewpoints > 0) {
      // From the semantic map: how many frames and viewpoints saw this table.
      const support = svg('text', { class: 'table-support', x: t.center[0], y: -t.center[1] + 0.3 }, map);
      support.textContent = `${t.sightings} frames, ${t.viewpoints} views`;
    }
    for (const p of t.search_positions) drawPosition(map, p.x, -p.y, p, 0.12);
  }
  // The robot: a triangle pointing along its heading.
  const r = 0.25, a = robot.yaw;
  const tip = [robot.x + r * Math.cos(a), robot.y + r * Math.sin(a)];
  const left = [robot.x + r * 0.6 * Math.cos(a + 2.5), robot.y + r * 0.6 * Math.sin(a + 2.5)];
  const right = [robot.x + r * 0.6 * Math.cos(a - 2.5), robot.y + r * 0.6 * Math.sin(a - 2.5)];
  svg('polygon', { class: 'robot', points: [tip, left, right].map(([x, y]) => `${x},${-y}`).join(' ') }, map);
}

function setConnection(text, cls) {
  const c = el('connection');
  c.textContent = text;
  c.className = 'badge ' + cls;
}

async function poll() {
  let drew = false;
  try {
    const res = await fetch('/api/live', { cache: 'no-store' });
    if (!res.ok) throw new Error('HTTP ' + res.status);
    const state = await res.json();
    lastLive = state;
    if (!palette) palette = state.label_colors;
    if (!legendDone) drawLegend(state.label_names, state.label_colors);
    if (state.labels && state.labels.seq !== live.lastSeq) {
      const seq = await drawLabels(state);
      drew = true;
      const now = Date.now();
      live.lastSeq = seq;
      live.draws += 1;
      keep(live.drawTimes, now);
      keep(live.publishToPageMs, now - (state.labels.utime + state.labels.latency_us) / 1000);
      keep(live.receiveToPageMs, now - state.labels.received_us / 1000);
      lastDrawMs = now;
      el('frame-info').textContent = `frame ${seq}, ${state.labels.width}×${state.labels.height}, daemon latency ${fmt(state.labels.latency_us / 1000)} ms`;
      drawCameraTables(state);
      drawMap(state);
    } else if (state.tables && state.labels && state.tables.seq === state.labels.seq && live.hullsDrawn === 0 &&
               state.tables.tables.length > 0) {
      drawCameraTables(state);  // the tables came after their labels
      drawMap(state);
    } else if (state.objects && state.labels && state.objects.seq === state.labels.seq &&
               live.objectsSeq !== state.objects.seq && live.hullsDrawn > 0) {
      drawCameraTables(state);  // the candidates came after their tables
    }
    showFind(state);
    // A new semantic map (a few seconds apart at most): fetch its raster, draw the map panel.
    if (state.semantic_map && state.semantic_map.seq !== live.semanticMapSeq && palette) {
      await fetchSemanticMap(state.semantic_map);
      drawMap(state);
    } else if (state.table_map && state.table_map.seq !== lastTableMapSeq) {
      drawMap(state);  // the table map changed while the labels did not
    }
    lastTableMapSeq = state.table_map ? state.table_map.seq : null;
    // The status comes twice a second at most: redraw its table and plots only then.
    const statusStamp = state.status ? state.status.utime : null;
    if (statusStamp !== lastStatusStamp || state.bad_messages_count !== lastBadCount) {
      drawStatus(state);
      lastStatusStamp = statusStamp;
      lastBadCount = state.bad_messages_count;
    }
    const stale = Date.now() - lastDrawMs > STALE_MS;
    if (state.bus === 'failed') setConnection('bus failed', 'down');
    else if (!state.labels) setConnection('waiting for findmugd', 'stale');
    else setConnection(stale ? (state.bus === 'ended' ? 'log ended' : 'no new frames') : 'live', stale ? 'stale' : 'live');
  } catch (e) {
    live.errors += 1;
    setConnection('no connection: ' + e.message, 'down');
  }
  // After a new frame, ask again at once (the next one may be waiting); else in a while.
  setTimeout(poll, drew ? 0 : POLL_MS);
}

el('map-frame').addEventListener('change', () => lastLive && drawMap(lastLive));

async function sendCommand(command, argument) {
  const res = await fetch('/api/command', {
    method: 'POST', headers: { 'Content-Type': 'application/json' },
    body: JSON.stringify({ command, argument }),
  });
  const answer = await res.json();
  if (!res.ok) throw new Error(answer.error || 'HTTP ' + res.status);
  return answer.request_id;
}

function setNote(id, text, cls) {
  const note = el(id);
  note.textContent = text;
  note.className = cls || 'muted';
}

// Teaching: a click on a candidate's box sends "teach NAME SEQ INDEX" at once (findmugd
// holds the last 30 frames' candidates), and the status then says what became of it.
el('camera').addEventListener('click', async (event) => {
  const rect = view.getBoundingClientRect();
  const x = (event.clientX - rect.left) * view.width / rect.width;
  const y = (event.clientY - rect.top) * view.height / rect.height;
  const hits = live.candidates.filter((c) => x >= c.box[0] && x <= c.box[2] && y >= c.box[1] && y <= c.box[3]);
  if (!hits.length) return;
  // Of overlapping boxes, the one whose middle is nearest the pointer.
  const away = (c) => Math.hypot((c.box[0] + c.box[2]) / 2 - x, (c.box[1] + c.box[3]) / 2 - y);
  const hit = hits.reduce((a, b) => (away(b) < away(a) ? b : a));
  const name = el('teach-name').value.trim();
  if (!name) {
    setNote('teach-note', 'type the object\'s name first, then click it', 'refused');
    el('teach-name').focus();
    return;
  }
  setNote('teach-note', `teaching ${name}: candidate ${hit.index} of frame ${hit.seq}…`);
  try {
    const id = await sendCommand('teach', `${name} ${hit.seq} ${hit.index}`);
    for (let i = 0; i < 100; ++i) {
      await new Promise((r) => setTimeout(r, 100));
      const s = lastLive && lastLive.status;
      if (s && s.last_teach_request_id === id) {
        live.teachResult = { ok: s.last_teach_ok, text: s.last_teach_result };
        setNote('teach-note', s.last_teach_result, s.last_teach_ok ? 'ok' : 'refused');
        return;
      }
    }
    setNote('teach-note', `teach request ${id} sent; no answer in the daemon's status yet`, 'refused');
  } catch (e) {
    live.teachResult = { ok: false, text: e.message };
    setNote('teach-note', 'not sent: ' + e.message, 'refused');
  }
});

// Find: "find NAME"; the daemon answers on FINDMUG_FIND_RESULT, again whenever the answer
// changes, and /api/live carries the latest.
let findRequestId = null;
function showFind(state) {
  const f = state.find;
  if (findRequestId === null || !f || f.request_id !== findRequestId) return;
  if (live.findResult === null || live.findResult.utime !== f.utime) {
    live.findResult = f;
    drawCameraTables(state);  // the sighting may be of the frame on view
  }
  let text = f.summary;
  if (f.result === 'look_at' && f.places.length) {
    text += ': ' + f.places.slice(0, 5).map((p) => `table ${p.table_id}` + (p.searched ? ' (searched)' : '')).join(', ');
  }
  setNote('find-note', text, f.result === 'seen' ? 'ok' : f.result === 'look_at' ? 'muted' : 'refused');
}

el('find-form').addEventListener('submit', async (event) => {
  event.preventDefault();
  const name = el('find-name').value.trim();
  setNote('find-note', `asking findmugd where ${name} is…`);
  try {
    findRequestId = await sendCommand('find', name);
    live.findResult = null;
  } catch (e) {
    setNote('find-note', 'not sent: ' + e.message, 'refused');
  }
});

// "Save this frame": findmug-web sends save_frame to findmugd (daemon.collect_dir), which
// saves the next frame it publishes; the status then names it.
el('save-frame').addEventListener('click', async () => {
  const note = el('save-note');
  const before = lastLive && lastLive.status ? lastLive.status.frames_collected : 0;
  note.textContent = 'asking findmugd…';
  try {
    const res = await fetch('/api/command', {
      method: 'POST', headers: { 'Content-Type': 'application/json' },
      body: JSON.stringify({ command: 'save_frame', argument: '' }),
    });
    const answer = await res.json();
    if (!res.ok) throw new Error(answer.error || 'HTTP ' + res.status);
    note.textContent = `request ${answer.request_id} sent`;
    for (let i = 0; i < 50; ++i) {
      await new Promise((r) => setTimeout(r, 200));
      const s = lastLive && lastLive.status;
      if (s && s.frames_collected > before) {
        note.textContent = `saved ${s.last_collected_frame}`;
        return;
      }
    }
    note.textContent = `request ${answer.request_id} sent; no frame saved yet (is daemon.collect_dir set?)`;
  } catch (e) {
    note.textContent = 'not sent: ' + e.message;
  }
});
poll();
