// What the kernels index, checked before anything is uploaded (SPEC.md Appendix C, the rules
// geometry/src/tables.rs checks for the Rust runtime, plus the content rules that keep a
// damaged file from drawing garbage): a malformed table is an HceError here, never an
// out-of-bounds read on the GPU, a lost device or a hung tab.
import { HceError } from './errors.js';
import {
  NO_NEIGHBOUR, RULE_CREASE, SPOKE_BOUNDARY, SPOKE_SHARP, VERTEX_BOUNDARY, geometryHash,
} from './container.js';

/** A node of depth 12 must be a leaf (B.2). */
export const MAX_TREE_DEPTH = 12;
/** Loop subdivision's deepest level, CPU and GPU alike. */
export const MAX_LOOP_LEVEL = 6;
/** The deepest level a subtriangle path can name (the flat kernel's). */
export const MAX_PATH_LEVEL = 15;

/**
 * @typedef {import('./container.js').HceObject} HceObject
 * @typedef {import('./container.js').ControlMesh} ControlMesh
 */

/**
 * The shape of the tree starting at bit `start` (B.2), as format/src/tree.rs `decode_shape`.
 * @param {Uint32Array} bits
 * @param {number} bitLen
 * @param {number} start
 * @returns {{ nodeCount: number, depth: number }}
 */
export function treeShape(bits, bitLen, start) {
  const limit = Math.min(bitLen, bits.length * 32);
  let nodes = 1;
  let depth = 0;
  let levelEnd = 1;
  let nextLevel = 0;
  for (let k = 0; k < nodes; k++) {
    if (k === levelEnd) {
      depth += 1;
      levelEnd += nextLevel;
      nextLevel = 0;
    }
    const i = start + k;
    if (i >= limit) throw new Error(`bitstream ends inside node ${k} (bit ${i} of ${limit}) (SPEC.md B.2)`);
    if ((bits[Math.floor(i / 32)] >>> (i % 32)) & 1) {
      if (depth >= MAX_TREE_DEPTH) throw new Error(`node ${k} at depth ${depth} is subdivided; the maximum depth is ${MAX_TREE_DEPTH} (SPEC.md B.2)`);
      nodes += 4;
      nextLevel += 4;
    }
  }
  return { nodeCount: nodes, depth };
}

/** @param {ControlMesh} m @param {number} v */
const ruleOf = (m, v) => (m.vertexFlags[v] >>> 1) & 3;

/**
 * The triangle and edge-id tables every refinement reads (`check_triangles`): indices in
 * range, no degenerate triangle, edge ids dense in order of first appearance and joining the
 * same two vertices wherever they appear.
 * @param {ControlMesh} m
 * @returns {{ verts: number[], sides: number[] }}
 */
export function checkTriangles(m) {
  const V = m.positions.length / 3;
  const F = m.triangles.length / 3;
  /** @type {number[]} */
  const verts = [];
  /** @type {number[]} */
  const sides = [];
  for (let t = 0; t < F; t++) {
    const tri = [m.triangles[3 * t], m.triangles[3 * t + 1], m.triangles[3 * t + 2]];
    for (let c = 0; c < 3; c++) {
      if (tri[c] >= V) throw new Error(`triangle ${t} corner ${c}: vertex ${tri[c]} >= ${V}`);
    }
    if (tri[0] === tri[1] || tri[1] === tri[2] || tri[2] === tri[0]) throw new Error(`triangle ${t} is degenerate: [${tri}]`);
    for (let e = 0; e < 3; e++) {
      const id = m.edges[3 * t + e];
      const a = tri[e];
      const b = tri[(e + 1) % 3];
      if (id === sides.length) {
        verts.push(a, b);
        sides.push(1);
      } else if (id < sides.length) {
        const oa = verts[2 * id];
        const ob = verts[2 * id + 1];
        if (!((oa === a && ob === b) || (oa === b && ob === a))) {
          throw new Error(`triangle ${t} edge ${e}: edge id ${id} joins (${oa}, ${ob}) elsewhere but (${a}, ${b}) here`);
        }
        sides[id] += 1;
      } else {
        throw new Error(`triangle ${t} edge ${e}: edge id ${id} skips ids (next new id is ${sides.length}); ids must be numbered in order of first appearance`);
      }
    }
  }
  return { verts, sides };
}

/**
 * Every other table Loop subdivision reads (`check_loop_tables`): rings, crease vertices,
 * corner spokes, neighbours, boundary edges, every vertex used.
 * @param {ControlMesh} m
 * @returns {{ maxValence: number, creaseSpokes: Uint32Array }}
 */
export function checkLoopTables(m) {
  const V = m.positions.length / 3;
  const F = m.triangles.length / 3;
  if (F === 0) throw new Error('no triangles');
  if (m.ringOffsets[0] !== 0 || m.ringOffsets[V] !== m.ring.length) throw new Error('ring_offsets do not span the ring array');
  let maxValence = 6;
  const creaseSpokes = new Uint32Array(2 * V);
  for (let v = 0; v < V; v++) {
    const a = m.ringOffsets[v];
    const b = m.ringOffsets[v + 1];
    if (b < a + 2) throw new Error(`vertex ${v}: ring shorter than 2`);
    if (b > m.ring.length) throw new Error(`vertex ${v}: ring_offsets run past the ring array`);
    maxValence = Math.max(maxValence, b - a);
    for (let k = a; k < b; k++) {
      if (m.ring[k] >= V) throw new Error(`vertex ${v}: spoke ${m.ring[k]} out of range`);
    }
    if (ruleOf(m, v) === RULE_CREASE) {
      const sharp = [];
      for (let k = 0; k < b - a; k++) if (m.spokeFlags[a + k] & SPOKE_SHARP) sharp.push(k);
      if (sharp.length !== 2) throw new Error(`vertex ${v}: crease rule with ${sharp.length} sharp spokes`);
      creaseSpokes[2 * v] = sharp[0];
      creaseSpokes[2 * v + 1] = sharp[1];
    }
  }
  for (let t = 0; t < F; t++) {
    for (let c = 0; c < 3; c++) {
      const v = m.triangles[3 * t + c];
      const off = m.ringOffsets[v];
      const len = m.ringOffsets[v + 1] - off;
      const k = m.cornerSpokes[3 * t + c];
      const closed = (m.vertexFlags[v] & VERTEX_BOUNDARY) === 0;
      const k1 = closed ? (k + 1) % len : k + 1;
      if (k >= len || k1 >= len || m.ring[off + k] !== m.triangles[3 * t + (c + 1) % 3] || m.ring[off + k1] !== m.triangles[3 * t + (c + 2) % 3]) {
        throw new Error(`triangle ${t} corner ${c}: corner_spokes does not point at the triangle's edges`);
      }
      const nb = m.neighbours[3 * t + c];
      if (nb !== NO_NEIGHBOUR) {
        if (nb >= F) throw new Error(`triangle ${t} edge ${c}: neighbour out of range`);
        if (!closed && k === 0) throw new Error(`triangle ${t} edge ${c}: interior edge on the first (boundary) spoke`);
      } else if (closed || (m.spokeFlags[off + k] & SPOKE_SHARP) === 0) {
        throw new Error(`triangle ${t} edge ${c}: boundary edge that is not marked sharp at an interior vertex`);
      }
    }
    for (let c = 0; c < 3; c++) {
      const nb = m.neighbours[3 * t + c];
      const v1 = m.triangles[3 * t + (c + 1) % 3];
      const len = m.ringOffsets[v1 + 1] - m.ringOffsets[v1];
      const k = m.cornerSpokes[3 * t + (c + 1) % 3];
      const closed = (m.vertexFlags[v1] & VERTEX_BOUNDARY) === 0;
      if (nb !== NO_NEIGHBOUR && !closed && k + 2 >= len) throw new Error(`triangle ${t} edge ${c}: interior edge on the last (boundary) spoke`);
    }
  }
  const used = new Uint8Array(V);
  for (const v of m.triangles) used[v] = 1;
  const unused = used.indexOf(0);
  if (unused >= 0) throw new Error(`vertex ${unused} is used by no triangle`);
  return { maxValence, creaseSpokes };
}

/**
 * Appendix C rules 2 and 3 that the refinement does not index but that change what it draws:
 * every spoke has its reverse, with the same sharp bit; flags only in their bits; boundary
 * spokes exactly at the ends of a boundary vertex's ring; the rule the sharp spokes call for.
 * @param {ControlMesh} m
 */
function checkSpokes(m) {
  const V = m.positions.length / 3;
  for (let v = 0; v < V; v++) {
    const a = m.ringOffsets[v];
    const b = m.ringOffsets[v + 1];
    const flags = m.vertexFlags[v];
    if (flags & ~7 || ((flags >>> 1) & 3) > 2) throw new Error(`vertex ${v}: flags ${flags} use unknown bits or rule`);
    const boundary = (flags & VERTEX_BOUNDARY) !== 0;
    let sharp = 0;
    for (let k = a; k < b; k++) {
      const s = m.spokeFlags[k];
      if (s & ~3) throw new Error(`vertex ${v}: spoke flags ${s} use unknown bits`);
      const end = k === a || k === b - 1;
      if (((s & SPOKE_BOUNDARY) !== 0) !== (boundary && end)) throw new Error(`vertex ${v}: boundary spoke bits do not mark the ends of a boundary ring`);
      if (s & SPOKE_BOUNDARY && !(s & SPOKE_SHARP)) throw new Error(`vertex ${v}: a boundary spoke is not sharp`);
      if (s & SPOKE_SHARP) sharp += 1;
      const w = m.ring[k];
      let back = -1;
      for (let j = m.ringOffsets[w]; j < m.ringOffsets[w + 1]; j++) if (m.ring[j] === v) back = j;
      if (back < 0) throw new Error(`vertex ${v}: spoke to ${w} has no reverse in ${w}'s ring`);
      if ((m.spokeFlags[back] & SPOKE_SHARP) !== (s & SPOKE_SHARP)) throw new Error(`edge (${v}, ${w}) is sharp at one end only`);
    }
    const rule = (flags >>> 1) & 3;
    const want = (boundary && b - a === 2) || sharp >= 3 ? 2 : sharp === 2 ? 1 : 0;
    if (rule !== want) throw new Error(`vertex ${v}: rule ${rule} but its ${sharp} sharp spokes call for ${want}`);
  }
}

/**
 * The records, trees, normals and colours the colouring reads (`validate_tables`, Appendix C
 * rules 7 to 9). Returns the deepest tree.
 * @param {HceObject} o
 */
function checkShading(o) {
  const F = o.mesh.triangles.length / 3;
  if (o.records.length / 4 !== F) throw new Error(`${o.records.length / 4} triangle records for ${F} triangles; re-bake the asset`);
  if (o.bitLen > o.bits.length * 32) throw new Error(`bit_len ${o.bitLen} exceeds the ${o.bits.length * 32} bits stored`);
  if (o.bitLen % 32 !== 0 && o.bits.length > 0 && o.bits[o.bits.length - 1] >>> (o.bitLen % 32) !== 0) throw new Error('bits past bit_len are not zero');
  for (let i = 0; i < o.normals.length / 3; i++) {
    const [x, y, z] = [o.normals[3 * i], o.normals[3 * i + 1], o.normals[3 * i + 2]];
    const len = Math.hypot(x, y, z);
    if (!Number.isFinite(len) || Math.abs(len - 1) > 1e-3) throw new Error(`normals[${i}] is not a unit vector (SPEC.md C rule 8)`);
  }
  let nodes = 0;
  let maxDepth = 0;
  for (let t = 0; t < F; t++) {
    const [bitsStart, colourStart, normalStart, normalCount] = o.records.subarray(4 * t, 4 * t + 4);
    const where = `triangle ${t}`;
    if (normalCount === 0) throw new Error(`${where}: normal_count is 0 (needs at least the geometric normal)`);
    if (o.kind === 'flat' && normalCount !== 1) throw new Error(`${where}: a flat object's triangle has ${normalCount} normals, not 1`);
    if (normalStart + normalCount > o.normals.length / 3) throw new Error(`${where}: normals ${normalStart}..+${normalCount} outside the ${o.normals.length / 3} stored`);
    let shape;
    try {
      shape = treeShape(o.bits, o.bitLen, bitsStart);
    } catch (e) {
      throw new Error(`${where}: ${/** @type {Error} */ (e).message}`);
    }
    nodes += shape.nodeCount;
    if (nodes > o.bitLen) throw new Error(`trees claim more nodes than the ${o.bitLen} bits of the bitstream`);
    maxDepth = Math.max(maxDepth, shape.depth);
    if (colourStart + shape.nodeCount * normalCount > o.colours.length) throw new Error(`${where}: colours up to ${colourStart + shape.nodeCount * normalCount} needed but ${o.colours.length} stored`);
  }
  return maxDepth;
}

/**
 * @typedef {object} CheckedObject what the checks learnt, for the derived tables
 * @property {{ verts: number[], sides: number[] }} edges
 * @property {{ maxValence: number, creaseSpokes: Uint32Array } | null} loop null for flat objects
 * @property {number} treeDepth the deepest tree
 */

/**
 * Every check of an object before upload; throws an HceError at `objects[i]`.
 * @param {HceObject} o
 * @returns {CheckedObject}
 */
export function checkObject(o) {
  const at = `objects[${o.index}]`;
  try {
    const m = o.mesh;
    for (let i = 0; i < m.positions.length; i++) {
      if (!Number.isFinite(m.positions[i])) throw new Error(`position ${Math.floor(i / 3)} is not finite (SPEC.md C rule 1)`);
    }
    if (m.positions.length / 3 > 0x7fffffff || m.triangles.length / 3 > 0x3fffffff) throw new Error('mesh too large for 32-bit indices');
    const edges = checkTriangles(m);
    const loop = o.kind === 'multiresolution' ? checkLoopTables(m) : null;
    checkSpokes(m);
    const treeDepth = checkShading(o);
    const hash = geometryHash(m.positions, m.triangles);
    if (hash !== o.geometryHash) throw new Error(`geometry hash ${hash} of the control triangles differs from the stored ${o.geometryHash}: the mesh was edited after baking (SPEC.md C rule 11)`);
    return { edges, loop, treeDepth };
  } catch (e) {
    if (e instanceof HceError) throw e;
    throw new HceError(at, `'${o.name}': ${/** @type {Error} */ (e).message}`);
  }
}
