// The derived tables the kernels read beside the file's own (flat.rs `FlatTopology`, and what
// loop_kernel.rs `upload_with` packs: owners, flags, crease spokes, weights), built from an
// object that passed tables.js.
import { NO_NEIGHBOUR, SPOKE_SHARP } from './container.js';

/**
 * @typedef {import('./container.js').HceObject} HceObject
 * @typedef {import('./tables.js').CheckedObject} CheckedObject
 */

/** Bits of the per-triangle flags word (`OWNS_EDGE` … in `loop.wgsl`). */
const OWNS_EDGE = 1;
const OWNS_VERTEX = 8;
const INTERIOR = 64;
const SHARP = 512;

/** @param {number[]} counts @returns {Uint32Array} */
function prefix(counts) {
  const out = new Uint32Array(counts.length + 1);
  for (let i = 0; i < counts.length; i++) out[i + 1] = out[i] + counts[i];
  return out;
}

/**
 * For each edge and vertex the triangle sides and corners touching it (`FlatTopology::new`).
 * @param {HceObject} o
 * @param {CheckedObject} checked
 */
export function flatTopology(o, checked) {
  const m = o.mesh;
  const V = m.positions.length / 3;
  const F = m.triangles.length / 3;
  const edgeSideOffsets = prefix(checked.edges.sides);
  const fill = edgeSideOffsets.slice();
  const edgeSides = new Uint32Array(3 * F);
  for (let s = 0; s < m.edges.length; s++) edgeSides[fill[m.edges[s]]++] = s;
  const cornerCount = new Array(V).fill(0);
  for (const x of m.triangles) cornerCount[x] += 1;
  const vertexCornerOffsets = prefix(cornerCount);
  const fill2 = vertexCornerOffsets.slice();
  const vertexCorners = new Uint32Array(3 * F);
  for (let s = 0; s < m.triangles.length; s++) vertexCorners[fill2[m.triangles[s]]++] = s;
  return {
    vertexCount: V,
    triangleCount: F,
    edgeCount: checked.edges.sides.length,
    edgeVerts: Uint32Array.from(checked.edges.verts),
    edgeSideOffsets,
    edgeSides,
    vertexCornerOffsets,
    vertexCorners,
  };
}

/** @typedef {ReturnType<typeof flatTopology>} FlatTopology */

/**
 * Loop's correction factor of valence `n` (subdivide.rs `correction_factor`), rounded to f32.
 * @param {number} n
 */
function correctionFactor(n) {
  const a = 0.375 + 0.25 * Math.cos((2 * Math.PI) / n);
  return Math.fround(5 / 3 - (8 / 3) * a * a);
}

/**
 * The Loop kernel's extra sections (`LoopKernel::upload_with`): per-triangle flags, crease
 * spokes and per-valence weights, with the largest valence and ring sum.
 * @param {HceObject} o
 * @param {CheckedObject} checked
 */
export function loopTables(o, checked) {
  const m = o.mesh;
  const loop = checked.loop;
  if (!loop) throw new Error('loopTables needs a multiresolution object');
  const V = m.positions.length / 3;
  const F = m.triangles.length / 3;
  // Owners (subdivide.rs `prepare`): first appearance in scan order.
  const vertexOwner = new Uint32Array(V).fill(0xffffffff);
  const ownsEdge = new Uint8Array(3 * F);
  let next = 0;
  for (let t = 0; t < F; t++) {
    for (let c = 0; c < 3; c++) {
      const v = m.triangles[3 * t + c];
      if (vertexOwner[v] === 0xffffffff) vertexOwner[v] = 3 * t + c;
      if (m.edges[3 * t + c] === next) {
        ownsEdge[3 * t + c] = 1;
        next += 1;
      }
    }
  }
  let maxValence = 0;
  const valence = (/** @type {number} */ v) => m.ringOffsets[v + 1] - m.ringOffsets[v];
  for (let v = 0; v < V; v++) maxValence = Math.max(maxValence, valence(v));
  let ringSum = 0;
  const triFlags = new Uint32Array(F);
  for (let t = 0; t < F; t++) {
    const tri = m.triangles.subarray(3 * t, 3 * t + 3);
    ringSum = Math.max(ringSum, valence(tri[0]) + valence(tri[1]) + valence(tri[2]));
    let flags = 0;
    for (let e = 0; e < 3; e++) {
      const s = 3 * t + e;
      if (ownsEdge[s]) flags |= OWNS_EDGE << e;
      if (vertexOwner[tri[e]] === s) flags |= OWNS_VERTEX << e;
      if (m.neighbours[s] !== NO_NEIGHBOUR) flags |= INTERIOR << e;
      const spoke = m.ringOffsets[tri[e]] + m.cornerSpokes[s];
      if (m.spokeFlags[spoke] & SPOKE_SHARP) flags |= SHARP << e;
    }
    triFlags[t] = flags;
  }
  const ringPoints = Math.max(8, Math.ceil(ringSum / 8) * 8);
  // Per valence k: cf(k) and 0.75 / k, both rounded to f32 as subdivide.rs rounds them.
  const kmax = Math.max(maxValence, 6);
  const weights = new Float32Array(2 * (kmax + 1));
  for (let k = 0; k <= kmax; k++) {
    const cfMax = loop.maxValence;
    weights[2 * k] = k < 2 || k > cfMax ? 0 : correctionFactor(k);
    weights[2 * k + 1] = k < 2 ? 0 : Math.fround(0.75 / k);
  }
  return {
    triFlags,
    crease: loop.creaseSpokes,
    weights: new Uint32Array(weights.buffer),
    maxValence,
    ringPoints,
  };
}
