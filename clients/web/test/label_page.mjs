// What the Label page's browser tests and the labelling-effort benchmark share: a frame's
// patches and patch graph as findmug-web serves them, this side's own account of what a
// drag and a region fill must take (computed here, not by the page), and the mouse and
// keyboard actions on the page's canvas.
import fs from 'node:fs';
import path from 'node:path';

export const VOID = 255;
export const NO_PATCH = 0xffff;
// The page's default region limits (label.html: #region-angle, #region-colour).
export const REGION_ANGLE_DEG = 15;
export const REGION_COLOUR = 40;

async function getJson(url) {
  const res = await fetch(url);
  const body = await res.json();
  if (!res.ok) throw new Error(`${url}: ${res.status} ${body.error}`);
  return body;
}

// {width, height, patches: Uint16Array per pixel, patchPixels: [Int32Array], graph}.
export async function frameData(url, root, frame) {
  const q = `root=${root}&frame=${encodeURIComponent(frame)}`;
  const info = await getJson(`${url}api/label/frame?${q}`);
  const patches = new Uint16Array(await (await fetch(`${url}api/label/patches.bin?${q}`)).arrayBuffer());
  if (patches.length !== info.width * info.height) throw new Error('patch map size');
  const lists = Array.from({ length: info.patches }, () => []);
  patches.forEach((p, i) => { if (p !== NO_PATCH) lists[p].push(i); });
  const g = await getJson(`${url}api/label/graph?${q}`);
  const neighbours = Array.from({ length: g.patches }, () => []);
  for (let k = 0; k < g.edges.length; k += 2) {
    neighbours[g.edges[k]].push(g.edges[k + 1]);
    neighbours[g.edges[k + 1]].push(g.edges[k]);
  }
  return {
    width: info.width, height: info.height, count: info.patches, patches,
    patchPixels: lists.map((l) => Int32Array.from(l)),
    graph: { rgb: Float32Array.from(g.rgb), normal: Float32Array.from(g.normal), neighbours },
  };
}

export async function prediction(url, root, frame) {
  return getJson(`${url}api/label/prediction?root=${root}&frame=${encodeURIComponent(frame)}`);
}

// The patches a region fill from `seed` must take: the seed, then breadth first every
// neighbour whose normal is within angleDeg of the seed's and whose mean colour is within
// `colour` (Euclidean, 0..255 per channel) of the seed's.
export function regionOf(graph, seed, angleDeg = REGION_ANGLE_DEG, colour = REGION_COLOUR) {
  const n = graph.normal, c = graph.rgb;
  const cosMax = Math.cos(angleDeg * Math.PI / 180);
  const taken = new Set([seed]);
  const queue = [seed];
  while (queue.length) {
    const p = queue.shift();
    for (const q of graph.neighbours[p]) {
      if (taken.has(q)) continue;
      const dot = n[3 * seed] * n[3 * q] + n[3 * seed + 1] * n[3 * q + 1] + n[3 * seed + 2] * n[3 * q + 2];
      const d = [0, 1, 2].map((a) => c[3 * seed + a] - c[3 * q + a]);
      if (dot >= cosMax && d[0] * d[0] + d[1] * d[1] + d[2] * d[2] <= colour * colour) {
        taken.add(q);
        queue.push(q);
      }
    }
  }
  return [...taken];
}

// The pixels of the straight line from (x0, y0) to (x1, y1), ends included (Bresenham).
export function linePixels(x0, y0, x1, y1) {
  const out = [];
  const dx = Math.abs(x1 - x0), dy = -Math.abs(y1 - y0);
  const sx = x0 < x1 ? 1 : -1, sy = y0 < y1 ? 1 : -1;
  let err = dx + dy;
  for (;;) {
    out.push([x0, y0]);
    if (x0 === x1 && y0 === y1) break;
    const e2 = 2 * err;
    if (e2 >= dy) { err += dy; x0 += sx; }
    if (e2 <= dx) { err += dx; y0 += sy; }
  }
  return out;
}

// The patches a straight drag from a to b ([x, y] pixels) paints, in order, each once.
export function patchesOnLine(data, a, b) {
  const seen = new Set();
  for (const [x, y] of linePixels(a[0], a[1], b[0], b[1])) {
    const p = data.patches[y * data.width + x];
    if (p !== NO_PATCH) seen.add(p);
  }
  return [...seen];
}

// Mouse actions at frame pixels on the page's canvas (shown 1:1 or scaled).
export async function canvasActions(page, width, height) {
  const box = await (await page.$('#label-view')).boundingBox();
  const at = (x, y) => [box.x + (x + 0.5) * box.width / width, box.y + (y + 0.5) * box.height / height];
  return {
    click: async (x, y) => { const [cx, cy] = at(x, y); await page.mouse.click(cx, cy); },
    // One move event from a to b: the page paints every pixel of the line between them.
    drag: async (a, b) => {
      const [ax, ay] = at(a[0], a[1]);
      const [bx, by] = at(b[0], b[1]);
      await page.mouse.move(ax, ay);
      await page.mouse.down();
      await page.mouse.move(bx, by, { steps: 1 });
      await page.mouse.up();
    },
  };
}

// Waits until the page has applied `strokes` changes and written its draft of them.
export async function settled(page, strokes, timeout = 30000) {
  await page.waitForFunction((n) => {
    const s = window.findmugLabel;
    return s.strokes >= n && s.draftIdle();
  }, { timeout, polling: 20 }, strokes);
}

// A draft file's labels as a Uint8Array (null when there is none).
export function draftLabels(dataDir, frame) {
  const file = path.join(dataDir, 'drafts', frame + '.json');
  if (!fs.existsSync(file)) return null;
  const d = JSON.parse(fs.readFileSync(file, 'utf8'));
  const out = new Uint8Array(d.width * d.height);
  let i = 0;
  for (const [id, count] of d.runs) { out.fill(id, i, i + count); i += count; }
  return { strokes: d.strokes, labels: out };
}

// Pixels where two label images differ: {count, first}.
export function differences(a, b) {
  let count = 0, first = -1;
  for (let k = 0; k < a.length; ++k) if (a[k] !== b[k]) { if (first < 0) first = k; ++count; }
  return { count, first };
}
