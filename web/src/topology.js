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

/** Flat objects join neighbours whose normals differ by less than this (G.2). */
export const FLAT_JOIN_DEGREES = 10;

/** @param {number[]} a @param {number[]} b */
const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];

/**
 * @param {HceObject} o
 * @param {number} t
 * @returns {[number[], number]} the unit geometric normal (f64, zero when degenerate) and the
 *   area of coarse triangle t, from its POSN corners (G.2)
 */
export function coarseNormalArea(o, t) {
  const m = o.mesh;
  const p = (/** @type {number} */ c) => {
    const v = m.triangles[3 * t + c];
    return [m.positions[3 * v], m.positions[3 * v + 1], m.positions[3 * v + 2]];
  };
  const [p0, p1, p2] = [p(0), p(1), p(2)];
  const u = [p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]];
  const w = [p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]];
  const n = [u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]];
  const l = Math.sqrt(dot(n, n));
  return [l > 0 ? n.map((x) => x / l) : [0, 0, 0], 0.5 * l];
}

/**
 * Sides joined to their neighbour (G.2, geometry/src/split.rs `joined_sides`): the neighbour
 * exists, the side's spoke is not sharp and, on a flat object, the two triangles' geometric
 * normals are within FLAT_JOIN_DEGREES. The one definition the lighting table and the split
 * read.
 * @param {HceObject} o
 */
export function joinedSides(o) {
  const m = o.mesh;
  const F = m.triangles.length / 3;
  const normals = [];
  if (o.kind !== 'multiresolution') for (let t = 0; t < F; t++) normals.push(coarseNormalArea(o, t)[0]);
  const cosJoin = Math.cos((FLAT_JOIN_DEGREES * Math.PI) / 180);
  const joined = new Uint8Array(3 * F);
  for (let s = 0; s < 3 * F; s++) {
    const u = m.neighbours[s];
    if (u === undefined || u === NO_NEIGHBOUR || u >= F) continue;
    const spoke = m.spokeFlags[m.ringOffsets[m.triangles[s]] + m.cornerSpokes[s]];
    const smooth = spoke !== undefined && (spoke & SPOKE_SHARP) === 0;
    joined[s] = smooth && (o.kind === 'multiresolution' || dot(normals[Math.floor(s / 3)], normals[u]) >= cosJoin) ? 1 : 0;
  }
  return joined;
}

/**
 * The group of every triangle corner 3t + c: the smallest corner linked to it by a chain of
 * joined sides at the same vertex (union-find; the smaller root wins, split.rs `corner_groups`).
 * @param {HceObject} o
 * @param {Uint8Array} joined
 */
export function cornerGroups(o, joined) {
  const m = o.mesh;
  const F = m.triangles.length / 3;
  const up = new Uint32Array(3 * F);
  for (let i = 0; i < 3 * F; i++) up[i] = i;
  const find = (/** @type {number} */ a) => {
    while (up[a] !== a) {
      up[a] = up[up[a]];
      a = up[a];
    }
    return a;
  };
  for (let tr = 0; tr < F; tr++) {
    for (let e = 0; e < 3; e++) {
      if (!joined[3 * tr + e]) continue;
      const u = m.neighbours[3 * tr + e];
      for (const c of [e, (e + 1) % 3]) {
        const v = m.triangles[3 * tr + c];
        for (let cu = 0; cu < 3; cu++) {
          if (m.triangles[3 * u + cu] !== v) continue;
          const ra = find(3 * tr + c);
          const rb = find(3 * u + cu);
          if (ra < rb) up[rb] = ra;
          else if (rb < ra) up[ra] = rb;
          break;
        }
      }
    }
  }
  const group = new Uint32Array(3 * F);
  for (let i = 0; i < 3 * F; i++) group[i] = find(i);
  return group;
}

/**
 * The split where the surface folds (SPEC.md F.5, geometry/src/split.rs
 * `SplitTables::from_topology`), for both kinds of object: the regions of each control point
 * (the groups of its corners joined across edges, G.2), the copies appended for every region
 * but the owner's and for the far side of every split edge (an edge with a neighbour that is
 * not joined), and the slot lists that replace the vertex and edge incidence in the kernels'
 * topology (V + X corner slots, E + S edge slots).
 * @param {HceObject} o
 * @param {FlatTopology} t
 */
export function splitTables(o, t) {
  const m = o.mesh;
  const F = t.triangleCount;
  const V = t.vertexCount;
  const E = t.edgeCount;
  const NO_COPY = 0xffffffff;
  const joined = joinedSides(o);
  const group = cornerGroups(o, joined);
  const find = (/** @type {number} */ c) => group[c];
  const cornerCopy = new Uint32Array(3 * F).fill(NO_COPY);
  /** @type {number[][]} */
  const ownerLists = [];
  /** @type {number[][]} */
  const copyLists = [];
  const splitVertex = new Uint8Array(V);
  for (let v = 0; v < V; v++) {
    /** @type {number[]} */
    const own = [];
    /** @type {number[]} */
    const roots = [];
    /** @type {number[]} */
    const ranks = [];
    for (let q = t.vertexCornerOffsets[v]; q < t.vertexCornerOffsets[v + 1]; q++) {
      const c = t.vertexCorners[q];
      const g = find(c);
      let r = roots.indexOf(g);
      if (r < 0) {
        roots.push(g);
        r = roots.length - 1;
        if (r > 0) {
          ranks.push(copyLists.length);
          copyLists.push([]);
        }
      }
      if (r === 0) own.push(c);
      else {
        copyLists[ranks[r - 1]].push(c);
        cornerCopy[c] = ranks[r - 1];
      }
    }
    ownerLists.push(own);
    splitVertex[v] = roots.length > 1 ? 1 : 0;
  }
  const cornerSlotOffsets = [0];
  /** @type {number[]} */
  const cornerSlotCorners = [];
  for (const list of [...ownerLists, ...copyLists]) {
    cornerSlotCorners.push(...list);
    cornerSlotOffsets.push(cornerSlotCorners.length);
  }
  const edgeCopy = new Uint32Array(E).fill(NO_COPY);
  const edgeSlotOffsets = [0];
  /** @type {number[]} */
  const edgeSlotSides = [];
  /** @type {number[]} */
  const copySides = [];
  const splitEdge = new Uint8Array(E);
  for (let id = 0; id < E; id++) {
    const sides = t.edgeSides.subarray(t.edgeSideOffsets[id], t.edgeSideOffsets[id + 1]);
    const neighboured = sides.length === 2 && m.neighbours[sides[0]] === Math.floor(sides[1] / 3);
    if (neighboured && !joined[sides[0]]) {
      edgeCopy[id] = copySides.length;
      splitEdge[id] = 1;
      edgeSlotSides.push(sides[0]);
      copySides.push(sides[1]);
    } else {
      edgeSlotSides.push(...sides);
    }
    edgeSlotOffsets.push(edgeSlotSides.length);
  }
  for (const s of copySides) {
    edgeSlotSides.push(s);
    edgeSlotOffsets.push(edgeSlotSides.length);
  }
  const slotSplit = Uint32Array.from([
    ...splitVertex,
    ...copyLists.map(() => 1),
    ...splitEdge,
    ...copySides.map(() => 1),
  ]);
  return {
    copies: copyLists.length,
    splitEdges: copySides.length,
    cornerSlotOffsets: Uint32Array.from(cornerSlotOffsets),
    cornerSlotCorners: Uint32Array.from(cornerSlotCorners),
    edgeSlotOffsets: Uint32Array.from(edgeSlotOffsets),
    edgeSlotSides: Uint32Array.from(edgeSlotSides),
    cornerCopy,
    edgeCopy,
    slotSplit,
  };
}

/** @typedef {ReturnType<typeof splitTables>} SplitTables */
