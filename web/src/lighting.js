// The lighting table of the smooth reconstruction (SPEC.md Appendix G), a port of
// geometry/src/lighting.rs `LightingTable::build_with` and `to_words`: per leaf corner point
// one linear model of colour over normals, fitted to the samples of every leaf meeting there,
// T-vertices resolved, corrected once towards the leaves' colours, T-vertices resolved again,
// in the word layout `hce_light.wgsl` reads. Fits in f64, rounded once to f32, as G.3 says.
import { coarseNormalArea, cornerGroups, joinedSides } from './topology.js';

/** @typedef {import('./container.js').HceObject} HceObject */

const TREE_LATTICE = 1 << 12;
/** Ridge weight of the normal fit (G.3). */
export const RIDGE = 1e-4;
const MODEL_FLOATS = 12;
const LEAF = 0x80000000;

/**
 * Decodes an RGB9E5 colour (2.4) to f32 values, as `rgb9e5::decode`.
 * @param {number} v
 * @returns {[number, number, number]}
 */
export function rgb9e5(v) {
  const scale = Math.fround(2 ** ((v >>> 27) - 15 - 9));
  return [Math.fround((v & 0x1ff) * scale), Math.fround(((v >>> 9) & 0x1ff) * scale), Math.fround(((v >>> 18) & 0x1ff) * scale)];
}

/** @param {number[]} a @param {number[]} b */
const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];

/**
 * The surface facts point identities need (lighting.rs `Surface`): which edges join their
 * triangles, and the group of each triangle corner's vertex.
 * @param {HceObject} o
 */
function surface(o) {
  const m = o.mesh;
  const F = m.triangles.length / 3;
  // Joined sides and corner groups: the one definition the split shares (topology.js, G.2).
  const joined = joinedSides(o);
  const group = cornerGroups(o, joined);
  /**
   * The key of lattice point (x, y) (denominator 4096) of coarse triangle t (G.2).
   * @param {number} t @param {number} x @param {number} y
   */
  const key = (t, x, y) => {
    const n = TREE_LATTICE;
    const a = n - x - y;
    let corner = -1;
    let edge = -1;
    let k = 0;
    if (x === 0 && y === 0) corner = 0;
    else if (a === 0 && y === 0) corner = 1;
    else if (a === 0 && x === 0) corner = 2;
    else if (y === 0) [edge, k] = [0, x];
    else if (a === 0) [edge, k] = [1, y];
    else if (x === 0) [edge, k] = [2, a];
    if (corner >= 0) return `v${m.triangles[3 * t + corner]}/${group[3 * t + corner]}`;
    if (edge >= 0 && joined[3 * t + edge]) {
      const va = m.triangles[3 * t + edge];
      const vb = m.triangles[3 * t + (edge + 1) % 3];
      return `e${m.edges[3 * t + edge]}/${va < vb ? k : n - k}`;
    }
    return `f${t}/${x}/${y}`;
  };
  return key;
}

/** Weighted moments of the samples at one point (G.3). */
class Moments {
  constructor() {
    this.w = 0;
    this.n = [0, 0, 0];
    this.nn = [0, 0, 0, 0, 0, 0, 0, 0, 0];
    this.b = [0, 0, 0];
    this.bn = [0, 0, 0, 0, 0, 0, 0, 0, 0];
  }

  /**
   * Adds a leaf of area weight `w` with its samples (lighting.rs `Moments::add`): each weighs
   * `w / count`, so a leaf counts by its area alone.
   * @param {number} w the leaf's area weight
   * @param {number[]} normals x, y, z per sample
   * @param {number[]} colours decoded r, g, b per sample
   * @param {number} at the leaf's first sample
   * @param {number} count how many it has
   */
  add(w, normals, colours, at, count) {
    const ws = w / count;
    for (let j = at; j < at + count; j++) {
      const n = [normals[3 * j], normals[3 * j + 1], normals[3 * j + 2]];
      const rgb = [colours[3 * j], colours[3 * j + 1], colours[3 * j + 2]];
      this.w += ws;
      for (let a = 0; a < 3; a++) {
        this.n[a] += ws * n[a];
        this.b[a] += ws * rgb[a];
        for (let b = 0; b < 3; b++) {
          this.nn[3 * a + b] += ws * n[a] * n[b];
          this.bn[3 * a + b] += ws * rgb[a] * n[b];
        }
      }
    }
  }

  /** @param {boolean} flat @returns {number[]} */
  fit(flat) {
    const w = this.w;
    const out = new Array(MODEL_FLOATS).fill(0);
    if (w <= 0) return out;
    const nbar = this.n.map((x) => x / w);
    const bbar = this.b.map((x) => x / w);
    if (flat) {
      out[0] = bbar[0];
      out[1] = bbar[1];
      out[2] = bbar[2];
      return out;
    }
    const m = [0, 1, 2].map((a) => [0, 1, 2].map((b) => this.nn[3 * a + b] / w - nbar[a] * nbar[b] + (a === b ? RIDGE : 0)));
    const c = (/** @type {number} */ r0, /** @type {number} */ c0, /** @type {number} */ r1, /** @type {number} */ c1) => m[r0][c0] * m[r1][c1] - m[r0][c1] * m[r1][c0];
    const adj = [
      [c(1, 1, 2, 2), -c(0, 1, 2, 2), c(0, 1, 1, 2)],
      [-c(1, 0, 2, 2), c(0, 0, 2, 2), -c(0, 0, 1, 2)],
      [c(1, 0, 2, 1), -c(0, 0, 2, 1), c(0, 0, 1, 1)],
    ];
    const det = m[0][0] * adj[0][0] + m[0][1] * adj[1][0] + m[0][2] * adj[2][0];
    const inv = adj.map((row) => row.map((x) => x / det));
    for (let ch = 0; ch < 3; ch++) {
      const cov = [0, 1, 2].map((a) => this.bn[3 * ch + a] / w - bbar[ch] * nbar[a]);
      const g = inv.map((row) => dot(row, cov));
      out[ch] = bbar[ch] - dot(g, nbar);
      out[3 + 3 * ch] = g[0];
      out[4 + 3 * ch] = g[1];
      out[5 + 3 * ch] = g[2];
    }
    return out;
  }
}

/**
 * Corners of the lattice triangle (origin, sigma, side) (lattice.rs `LatticeTriangle`).
 * @param {number[]} cell [x, y, sigma, side]
 * @returns {number[][]}
 */
function corners(cell) {
  const [x, y, s, side] = cell;
  const d = s * side;
  return [[x, y], [x + d, y], [x, y + d]];
}

/** @param {number[]} cell @param {number} c */
function child(cell, c) {
  const [x, y, s, side] = cell;
  const h = side / 2;
  if (c === 0) return [x, y, s, h];
  if (c === 1) return [x + s * h, y, s, h];
  if (c === 2) return [x + s * h, y + s * h, -s, h];
  return [x, y + s * h, s, h];
}

/**
 * Model `v`'s channel `ch` for normal `n` (lighting.rs `model_at`).
 * @param {number[]} v @param {number[]} n @param {number} ch
 */
const modelAt = (v, n, ch) => v[ch] + ((v[3 + 3 * ch] * n[0] + v[4 + 3 * ch] * n[1]) + v[5 + 3 * ch] * n[2]);

/**
 * The correction step of G.3 (lighting.rs `correct`): every point's constant term moves by the
 * weighted mean of its leaves' residuals, limited so that its model at its mean normal stays
 * between the least and greatest colour of its samples; all residuals found first.
 * @param {{ corners: number[], sampleWeight: number, sampleAt: number, sampleCount: number }[]} leaves
 * @param {number[]} normals three per sample
 * @param {number[]} colours three per sample
 * @param {Moments[]} moments
 * @param {number[][]} values
 */
function correct(leaves, normals, colours, moments, values) {
  const n = values.length;
  const sum = new Float64Array(3 * n);
  const lo = new Float64Array(3 * n).fill(Infinity);
  const hi = new Float64Array(3 * n).fill(-Infinity);
  for (const leaf of leaves) {
    const [c0, c1, c2] = leaf.corners;
    for (let j = leaf.sampleAt; j < leaf.sampleAt + leaf.sampleCount; j++) {
      const normal = normals.slice(3 * j, 3 * j + 3);
      for (let ch = 0; ch < 3; ch++) {
        const colour = colours[3 * j + ch];
        const m = modelAt(values[c0], normal, ch) + modelAt(values[c1], normal, ch) + modelAt(values[c2], normal, ch);
        const residual = colour - m / 3;
        for (const c of leaf.corners) {
          sum[3 * c + ch] += leaf.sampleWeight * residual;
          lo[3 * c + ch] = Math.min(lo[3 * c + ch], colour);
          hi[3 * c + ch] = Math.max(hi[3 * c + ch], colour);
        }
      }
    }
  }
  for (let p = 0; p < n; p++) {
    const w = moments[p].w;
    if (!(w > 0)) continue;
    const nbar = moments[p].n.map((x) => x / w);
    for (let ch = 0; ch < 3; ch++) {
      const v = modelAt(values[p], nbar, ch);
      const delta = Math.min(Math.max(sum[3 * p + ch] / w, lo[3 * p + ch] - v), hi[3 * p + ch] - v);
      values[p][ch] += delta;
    }
  }
}

/**
 * The `hce_light` words of `hce_light.wgsl` for `object` (`LightingTable::build_with` then
 * `to_words`). `gouraud` builds the table of the geometric normals' colours without slopes.
 * @param {HceObject} o an object that passed tables.js
 * @param {{ gouraud?: boolean }} [options]
 * @returns {Uint32Array}
 */
export function lightingWords(o, options = {}) {
  const gouraud = options.gouraud ?? false;
  const key = surface(o);
  /** @type {Map<string, number>} */
  const pointIndex = new Map();
  /** @type {Moments[]} */
  const moments = [];
  /** @type {{ triangle: number, depth: number, cell: number[], corners: number[], sampleWeight: number, sampleAt: number, sampleCount: number }[]} */
  const leaves = [];
  // Every leaf's samples (G.3), three numbers each: the normals and the decoded colours.
  /** @type {number[]} */
  const sampleNormals = [];
  /** @type {number[]} */
  const sampleColours = [];
  const F = o.records.length / 4;
  const nodeStart = new Uint32Array(F);
  /** @type {number[]} */
  const nodes = [];
  for (let t = 0; t < F; t++) {
    nodeStart[t] = nodes.length;
    const [bitsStart, colourStart, normalStart, nc] = o.records.subarray(4 * t, 4 * t + 4);
    const normals = o.normals.subarray(3 * normalStart, 3 * (normalStart + nc));
    const area = coarseNormalArea(o, t)[1];
    /** @type {number[][]} */
    const cells = [[0, 0, 1, TREE_LATTICE]];
    let subdividedSeen = 0;
    let count = 1;
    let depth = 0;
    let levelEnd = 1;
    let nextLevel = 0;
    for (let k = 0; k < count; k++) {
      if (k === levelEnd) {
        depth += 1;
        levelEnd += nextLevel;
        nextLevel = 0;
      }
      const i = bitsStart + k;
      const subdivided = ((o.bits[Math.floor(i / 32)] >>> (i % 32)) & 1) === 1;
      const cell = cells[k];
      if (subdivided) {
        count += 4;
        nextLevel += 4;
        const first = 1 + 4 * subdividedSeen;
        subdividedSeen += 1;
        nodes.push(first);
        for (let c = 0; c < 4; c++) cells[first + c] = child(cell, c);
        continue;
      }
      const w = area / 4 ** depth;
      const slots = [];
      const samples = gouraud ? 1 : nc;
      const colours = o.colours.subarray(colourStart + k * nc, colourStart + k * nc + nc);
      const sampleAt = sampleNormals.length / 3;
      for (let j = 0; j < samples; j++) {
        sampleNormals.push(normals[3 * j], normals[3 * j + 1], normals[3 * j + 2]);
        sampleColours.push(...rgb9e5(colours[j]));
      }
      for (const p of corners(cell)) {
        const id = key(t, p[0], p[1]);
        let index = pointIndex.get(id);
        if (index === undefined) {
          index = moments.length;
          pointIndex.set(id, index);
          moments.push(new Moments());
        }
        moments[index].add(w, sampleNormals, sampleColours, sampleAt, samples);
        slots.push(index);
      }
      nodes.push((LEAF | leaves.length) >>> 0);
      leaves.push({ triangle: t, depth, cell, corners: slots, sampleWeight: w / samples, sampleAt, sampleCount: samples });
    }
  }
  const flat = gouraud || o.kind === 'flat';
  const values = moments.map((m) => m.fit(flat));
  // T-vertices: from the largest leaves down (a stable sort keeps triangle and node order).
  const order = leaves.map((_, i) => i).sort((a, b) => leaves[a].depth - leaves[b].depth || a - b);
  /**
   * @param {number} t
   * @param {number[]} pa @param {number} ia
   * @param {number[]} pb @param {number} ib
   */
  const resolve = (t, pa, ia, pb, ib) => {
    if (Math.abs(pa[0] - pb[0]) < 2 && Math.abs(pa[1] - pb[1]) < 2) return;
    const pm = [Math.trunc((pa[0] + pb[0]) / 2), Math.trunc((pa[1] + pb[1]) / 2)];
    const im = pointIndex.get(key(t, pm[0], pm[1]));
    if (im === undefined) return;
    const va = values[ia];
    const vb = values[ib];
    values[im] = va.map((x, i) => 0.5 * (x + vb[i]));
    resolve(t, pa, ia, pm, im);
    resolve(t, pm, im, pb, ib);
  };
  const resolveTVertices = () => {
    for (const i of order) {
      const leaf = leaves[i];
      const pts = corners(leaf.cell);
      for (let e = 0; e < 3; e++) {
        const b = (e + 1) % 3;
        resolve(leaf.triangle, pts[e], leaf.corners[e], pts[b], leaf.corners[b]);
      }
    }
  };
  resolveTVertices();
  // Gouraud, classic radiosity shading for comparison, keeps the corner means.
  if (!gouraud) {
    correct(leaves, sampleNormals, sampleColours, moments, values);
    resolveTVertices();
  }
  const nodesAt = 2 + F;
  const pointsAt = nodesAt + nodes.length;
  const modelsAt = pointsAt + 3 * leaves.length;
  const total = modelsAt + MODEL_FLOATS * values.length;
  if (total > 0xffffffff) throw new Error('the lighting table is too large for 32-bit word indices');
  const words = new Uint32Array(total);
  words[0] = pointsAt;
  words[1] = modelsAt;
  for (let t = 0; t < F; t++) words[2 + t] = nodesAt + nodeStart[t];
  words.set(nodes, nodesAt);
  for (let l = 0; l < leaves.length; l++) words.set(leaves[l].corners, pointsAt + 3 * l);
  const models = new Float32Array(words.buffer, 4 * modelsAt, MODEL_FLOATS * values.length);
  for (let p = 0; p < values.length; p++) models.set(values[p], MODEL_FLOATS * p);
  return words;
}
