// hce's own reader, validator and table builder in the browser: the Rust of hce-runtime's
// asset loading, hce-format and hce-geometry compiled to WebAssembly (wasm/, built into
// web/src/hce.wasm by web/build-wasm.sh), so that the checks, the messages and the tables are
// the CLI's and the native runtime's, bit for bit. The request and result frames are those of
// wasm/src/lib.rs; this file only moves words in and out.
import { HceError } from './errors.js';

const WASM_URL = new URL('./hce.wasm', import.meta.url);

/** Compiles hce.wasm: fetched beside this module, or read from disk when run by node. */
async function compile() {
  if (WASM_URL.protocol === 'file:') {
    // Through a variable: a bundler leaves this node-only import alone.
    const fsModule = 'node:fs/promises';
    const { readFile } = /** @type {typeof import('node:fs/promises')} */ (await import(/* @vite-ignore */ fsModule));
    return WebAssembly.compile(await readFile(WASM_URL));
  }
  const response = await fetch(WASM_URL);
  if (!response.ok) throw new Error(`cannot load ${WASM_URL}: HTTP ${response.status} (build it with web/build-wasm.sh)`);
  return WebAssembly.compile(await response.arrayBuffer());
}

/**
 * @typedef {object} Exports
 * @property {WebAssembly.Memory} memory
 * @property {(bytes: number) => number} hce_alloc
 * @property {(ptr: number, bytes: number) => void} hce_free
 * @property {(ptr: number, bytes: number) => number} hce_load
 * @property {(ptr: number, bytes: number) => number} hce_tables
 * @property {(ptr: number, bytes: number) => number} hce_geometry_hash
 * @property {(ptr: number, bytes: number) => number} hce_refine
 */

// Compiled from the moment the module is imported, but not awaited there: a top-level await
// would hold back every page script that imports the runtime. `loadAsset` waits for it, and
// every object the synchronous calls take comes from `loadAsset`.
const compiled = compile();
// Marked handled here: a missing hce.wasm is reported by the first load that needs it (as a
// rejected load), not as an unhandled rejection at import.
compiled.catch(() => {});
const instantiate = async () => /** @type {Exports} */ (/** @type {unknown} */ ((await WebAssembly.instantiate(await compiled)).exports));
/** @type {Exports | null} null until instantiated, and after a trap until a fresh instance replaces it */
let wasm = null;
/** @type {Promise<void> | null} */
let starting = null;

/** Instantiates hce.wasm when there is no instance (the first time, or after a trap). */
function ready() {
  if (wasm !== null) return Promise.resolve();
  starting ??= instantiate().then((fresh) => {
    wasm = fresh;
    starting = null;
  }, (e) => {
    starting = null;
    throw new HceError('', `cannot start the WebAssembly reader: ${/** @type {Error} */ (e).message}`);
  });
  return starting;
}

/** Request frames: the items of wasm/src/lib.rs, appended in order. */
class Writer {
  constructor() {
    /** @type {Uint32Array[]} */
    this.parts = [];
  }

  /** @param {number} v */
  u32(v) {
    this.parts.push(Uint32Array.of(v));
  }

  /** @param {string} hex 16 hexadecimal digits */
  u64hex(hex) {
    this.parts.push(Uint32Array.of(parseInt(hex.slice(8), 16), parseInt(hex.slice(0, 8), 16)));
  }

  /** @param {number} v */
  u64(v) {
    this.parts.push(Uint32Array.of(v % 4294967296, Math.floor(v / 4294967296)));
  }

  /** @param {ArrayLike<number> & { buffer?: ArrayBufferLike }} a u32 words, or f32 when a Float32Array */
  words(a) {
    this.u32(a.length);
    this.parts.push(a instanceof Float32Array ? new Uint32Array(a.buffer.slice(a.byteOffset, a.byteOffset + a.byteLength)) : Uint32Array.from(a));
  }

  /** @param {Uint8Array} b */
  bytes(b) {
    this.u32(b.length);
    const padded = new Uint8Array(Math.ceil(b.length / 4) * 4);
    padded.set(b);
    this.parts.push(new Uint32Array(padded.buffer));
  }

  /** @param {string} s */
  string(s) {
    this.bytes(new TextEncoder().encode(s));
  }

  finish() {
    const out = new Uint32Array(this.parts.reduce((n, p) => n + p.length, 0));
    let at = 0;
    for (const p of this.parts) {
      out.set(p, at);
      at += p.length;
    }
    return out;
  }
}

/** Result frames, read in the order wasm/src/lib.rs writes them. */
class Reader {
  /** @param {Uint32Array} words */
  constructor(words) {
    this.w = words;
    this.at = 0;
  }

  u32() {
    return this.w[this.at++];
  }

  f32() {
    return new Float32Array(this.w.buffer, 4 * this.at++, 1)[0];
  }

  /** A u64 as a number (exact below 2^53). */
  u64() {
    const lo = this.u32();
    return this.u32() * 4294967296 + lo;
  }

  /** A u64 as 16 lowercase hexadecimal digits. */
  u64hex() {
    const lo = this.u32();
    return this.u32().toString(16).padStart(8, '0') + lo.toString(16).padStart(8, '0');
  }

  words() {
    const n = this.u32();
    const out = this.w.slice(this.at, this.at + n);
    this.at += n;
    return out;
  }

  floats() {
    return new Float32Array(this.words().buffer);
  }

  string() {
    const n = this.u32();
    const bytes = new Uint8Array(this.w.buffer, 4 * this.at, n);
    this.at += Math.ceil(n / 4);
    return new TextDecoder().decode(bytes);
  }
}

/**
 * Calls export `name` on a request frame; the result's payload, or its error as an HceError.
 * @param {'hce_load' | 'hce_tables' | 'hce_geometry_hash' | 'hce_refine'} name
 * @param {Uint32Array} request
 */
function call(name, request) {
  const e = wasm;
  if (e === null) throw new HceError('', 'the WebAssembly reader is not running: load an asset first (loadAsset), or again after an internal error');
  const bytes = 4 * request.length;
  let out;
  try {
    const ptr = e.hce_alloc(bytes);
    new Uint32Array(e.memory.buffer, ptr, request.length).set(request);
    out = e[name](ptr, bytes);
    e.hce_free(ptr, bytes);
  } catch (err) {
    // A trap (out of memory, or a bug) leaves the instance's memory unknown: the next
    // loadAsset starts a fresh one.
    wasm = null;
    throw new HceError('', `the WebAssembly reader failed: ${/** @type {Error} */ (err).message}`);
  }
  const mem = new Uint32Array(e.memory.buffer);
  const words = mem[out / 4];
  const status = mem[out / 4 + 1];
  const r = new Reader(mem.slice(out / 4 + 2, out / 4 + words));
  e.hce_free(out, 4 * words);
  if (status !== 0) throw new HceError('', r.string());
  return r;
}

/**
 * @typedef {object} ControlMesh the arrays of `ControlMesh` in format/src/model.rs
 * @property {Float32Array} positions
 * @property {Uint32Array} triangles
 * @property {Uint32Array} ringOffsets
 * @property {Uint32Array} ring
 * @property {Uint32Array} vertexFlags
 * @property {Uint32Array} spokeFlags
 * @property {Uint32Array} cornerSpokes
 * @property {Uint32Array} neighbours
 * @property {Uint32Array} edges
 */

/**
 * @typedef {object} HceObject one container object (SPEC.md A.7), validated
 * @property {number} index
 * @property {string} name
 * @property {'multiresolution' | 'flat'} kind
 * @property {string} geometryHash 16 hex digits
 * @property {ControlMesh} mesh
 * @property {Uint32Array} records TREC: bits_start, colour_start, normal_start, normal_count
 * @property {Float32Array} normals x, y, z per normal
 * @property {Uint32Array} bits
 * @property {number} bitLen
 * @property {Uint32Array} colours RGB9E5
 * @property {Uint32Array} cornerColours RGB9E5, three per colour at its node's corners (SPEC.md
 *   A.10); empty when the object has none
 * @property {number} treeDepth the deepest tree
 */

/**
 * @typedef {import('./math.js').Mat4} Mat4
 * @typedef {import('./math.js').Bounds} Bounds
 * @typedef {{ node: number | null, name: string, transform: Mat4 }} Instance
 * @typedef {{ object: HceObject, instances: Instance[], bounds: Bounds, meanEdgeLength: number }} AssetObject
 * @typedef {{ name: string, eye: number[], forward: number[], up: number[], fovYDegrees: number, aspectRatio: number | null }} SceneCamera
 * @typedef {{ format: 'hce' | 'glb' | 'gltf', objects: AssetObject[], camera: SceneCamera | null, warnings: string[], generator: string }} Asset
 */

/**
 * @typedef {object} LoadOptions
 * @property {string} [name] the file's name, for its extension (default 'asset')
 * @property {boolean} [strict] reject the asset on a bad primitive link or a stale geometry hash
 *   (default true); false ignores such primitives with a warning (SPEC.md 3.5)
 * @property {(uri: string) => Promise<Uint8Array>} [resolveUri] external buffers of a .gltf
 */

/** @param {Reader} r @returns {Float32Array & number[]} */
const vec = (r) => /** @type {any} */ (Array.from(r.floats()));

/**
 * Loads a baked asset from its bytes (a .glb, .gltf or .hce), checked as `hce` checks it
 * (runtime/src/asset.rs): every failure is an HceError with the CLI's message.
 * @param {Uint8Array} bytes
 * @param {LoadOptions} [options]
 * @returns {Promise<Asset>}
 */
export async function loadAsset(bytes, options = {}) {
  await ready();
  const w = new Writer();
  w.string(options.name ?? 'asset');
  w.u32(options.strict ?? true ? 1 : 0);
  w.bytes(bytes);
  const external = await externalBuffers(bytes, options);
  w.u32(external.length);
  for (const [uri, data] of external) {
    w.string(uri);
    w.bytes(data);
  }
  const r = call('hce_load', w.finish());
  const format = /** @type {const} */ (['hce', 'glb', 'gltf'])[r.u32()];
  const generator = r.string();
  const warnings = Array.from({ length: r.u32() }, () => r.string());
  /** @type {SceneCamera | null} */
  let camera = null;
  if (r.u32() === 1) {
    camera = { name: r.string(), eye: vec(r), forward: vec(r), up: vec(r), fovYDegrees: r.f32(), aspectRatio: null };
    const hasAspect = r.u32() === 1;
    const aspect = r.f32();
    camera.aspectRatio = hasAspect ? aspect : null;
  }
  /** @type {AssetObject[]} */
  const objects = [];
  for (let n = r.u32(), i = 0; i < n; i++) {
    const index = r.u32();
    const object = readObject(r, index);
    object.treeDepth = r.u32();
    const b = r.floats();
    const bounds = { min: /** @type {[number, number, number]} */ ([b[0], b[1], b[2]]), max: /** @type {[number, number, number]} */ ([b[3], b[4], b[5]]) };
    const meanEdgeLength = r.f32();
    const instances = Array.from({ length: r.u32() }, () => {
      const node = r.u32();
      return { node: node === 0xffffffff ? null : node, name: r.string(), transform: Array.from(r.floats()) };
    });
    objects.push({ object, instances, bounds, meanEdgeLength });
  }
  return { format, objects, camera, warnings, generator };
}

/**
 * The external buffers a .gltf names (not its data: URIs, which the reader decodes), through
 * `resolveUri`; none for a GLB or container, or without `resolveUri`.
 * @param {Uint8Array} bytes
 * @param {LoadOptions} options
 * @returns {Promise<[string, Uint8Array][]>}
 */
async function externalBuffers(bytes, options) {
  const resolve = options.resolveUri;
  if (!resolve || bytes[0] !== 0x7b) return [];
  let json;
  try {
    json = JSON.parse(new TextDecoder().decode(bytes));
  } catch {
    return []; // The reader says what is wrong with the JSON.
  }
  const uris = (Array.isArray(json?.buffers) ? json.buffers : []).map((/** @type {any} */ b) => b?.uri).filter((/** @type {unknown} */ u) => typeof u === 'string' && !u.startsWith('data:'));
  return Promise.all(uris.map(async (/** @type {string} */ uri, /** @type {number} */ i) => {
    try {
      return /** @type {[string, Uint8Array]} */ ([uri, await resolve(uri)]);
    } catch (e) {
      throw new HceError(`buffers[${i}].uri`, `cannot load '${uri}': ${/** @type {Error} */ (e).message}`);
    }
  }));
}

/** @param {Reader} r @param {number} index @returns {HceObject} */
function readObject(r, index) {
  const name = r.string();
  const kind = r.u32() === 0 ? 'multiresolution' : 'flat';
  const geometryHash = r.u64hex();
  const bitLen = r.u64();
  const mesh = {
    positions: r.floats(), triangles: r.words(), ringOffsets: r.words(), ring: r.words(), vertexFlags: r.words(),
    spokeFlags: r.words(), cornerSpokes: r.words(), neighbours: r.words(), edges: r.words(),
  };
  return { index, name, kind, geometryHash, mesh, records: r.words(), normals: r.floats(), bits: r.words(), bitLen, colours: r.words(), cornerColours: r.words(), treeDepth: 0 };
}

/**
 * The geometry hash (SPEC.md 2.5) of the corners `triangles` pick from `positions`, as 16
 * lowercase hexadecimal digits.
 * @param {Float32Array} positions
 * @param {ArrayLike<number>} triangles
 */
export function geometryHash(positions, triangles) {
  const w = new Writer();
  w.words(positions);
  w.words(triangles);
  return call('hce_geometry_hash', w.finish()).u64hex();
}

/** The deepest levels the kernels refine to (subdivide.rs `MAX_LOOP_LEVEL`, the flat kernel's path). */
export const MAX_LOOP_LEVEL = 6;
export const MAX_PATH_LEVEL = 15;

/** @typedef {'smooth' | 'nearest' | 'gouraud'} Reconstruction */

const RECONSTRUCTION_WORD = { smooth: 0, nearest: 1, gouraud: 2 };

/**
 * How a flat object is refined (SPEC.md F.7): 'adaptive' from its trees, one triangle per leaf
 * plus those its finer neighbours need (F.7.1, the default: the same field with a fraction of
 * the triangles); 'uniform' split 1-to-4 to a level (F.7.2).
 * @typedef {'adaptive' | 'uniform'} FlatRefinement
 */

const FLAT_REFINEMENT_WORD = { adaptive: 0, uniform: 1 };

/**
 * A request that starts with an object: its index, then the object as `hce_load` wrote it.
 * @param {HceObject} object
 */
function objectRequest(object) {
  const w = new Writer();
  w.u32(object.index);
  w.string(object.name);
  w.u32(object.kind === 'multiresolution' ? 0 : 1);
  w.u64hex(object.geometryHash);
  w.u64(object.bitLen);
  const m = object.mesh;
  w.words(m.positions);
  for (const table of [m.triangles, m.ringOffsets, m.ring, m.vertexFlags, m.spokeFlags, m.cornerSpokes, m.neighbours, m.edges, object.records]) w.words(table);
  w.words(object.normals);
  w.words(object.bits);
  w.words(object.colours);
  w.words(object.cornerColours);
  return w;
}

/**
 * @typedef {object} ObjectTables what the kernels read of one object beside its own arrays
 * @property {number} treeDepth the deepest tree
 * @property {{ vertexCount: number, triangleCount: number, edgeCount: number, edgeVerts: Uint32Array }} topology
 *   the incidence (geometry/src/incidence.rs `FlatTopology`)
 * @property {{ copies: number, splitEdges: number, edgeSlotOffsets: Uint32Array, edgeSlotSides: Uint32Array, cornerSlotOffsets: Uint32Array, cornerSlotCorners: Uint32Array, cornerCopy: Uint32Array, edgeCopy: Uint32Array, slotSplit: Uint32Array }} split
 *   the split where the surface folds (SPEC.md F.5, geometry/src/split.rs `SplitTables`)
 * @property {{ triFlags: Uint32Array, crease: Uint32Array, weights: Uint32Array, maxValence: number, ringPoints: number } | null} loop
 *   the Loop kernel's tables (geometry/src/loop_tables.rs), null for a flat object
 * @property {Uint32Array} light the `hce_light` words (SPEC.md Appendix G); one zero word for 'nearest'
 * @property {AdaptiveLists | null} adaptive a flat object's adaptive refinement (SPEC.md F.7.1) as
 *   the flat kernel reads it; null for a multiresolution object or a uniform one
 */

/**
 * @typedef {object} AdaptiveLists geometry/src/adaptive_flat.rs `KernelLists`
 * @property {number} vertices
 * @property {number} triangles
 * @property {Uint32Array[]} sections sources, faces, indices, use offsets, uses (flat.wgsl's order)
 * @property {Uint32Array} triangleStart per coarse triangle its first triangle, then the count
 */

/**
 * Checks `object` as the native runtime's upload does (every table the kernels index) and
 * builds its derived tables and lighting table: the same Rust, so the same words.
 * @param {HceObject} object
 * @param {Reconstruction} [reconstruction]
 * @param {FlatRefinement} [flat] how a flat object will be refined
 * @returns {ObjectTables}
 */
export function objectTables(object, reconstruction = 'smooth', flat = 'adaptive') {
  const w = objectRequest(object);
  w.u32(RECONSTRUCTION_WORD[reconstruction]);
  w.u32(FLAT_REFINEMENT_WORD[flat]);
  const r = call('hce_tables', w.finish());
  const treeDepth = r.u32();
  const topology = { vertexCount: r.u32(), triangleCount: r.u32(), edgeCount: r.u32(), edgeVerts: r.words() };
  const split = {
    copies: r.u32(), splitEdges: r.u32(), edgeSlotOffsets: r.words(), edgeSlotSides: r.words(), cornerSlotOffsets: r.words(),
    cornerSlotCorners: r.words(), cornerCopy: r.words(), edgeCopy: r.words(), slotSplit: r.words(),
  };
  const loop = r.u32() === 1 ? { triFlags: r.words(), crease: r.words(), weights: r.words(), maxValence: r.u32(), ringPoints: r.u32() } : null;
  const light = r.words();
  const adaptive = r.u32() === 1
    ? { vertices: r.u32(), triangles: r.u32(), sections: [r.words(), r.words(), r.words(), r.words(), r.words()], triangleStart: r.words() }
    : null;
  return { treeDepth, topology, split, loop, light, adaptive };
}

/**
 * @typedef {object} CpuRefined one object refined on the CPU (wasm/src/refine.rs)
 * @property {number} level the level of the triangles' numbering (0 for an adaptive flat object)
 * @property {Float32Array} positions x, y, z per vertex
 * @property {Float32Array} normals unit, x, y, z per vertex
 * @property {Float32Array} colours linear radiance, r, g, b per vertex
 * @property {Uint32Array} indices 3 per triangle, grouped by coarse triangle
 * @property {Uint32Array} triangleStart per coarse triangle its first triangle, then the count
 */

/**
 * Refines `object` to `level` (0 to MAX_LOOP_LEVEL) on the CPU with its baked light, as
 * `hce subdivide` refines it: the same Rust, so the same positions, bit for bit. A flat object
 * is refined from its trees whatever the level unless `flat` is 'uniform'.
 * @param {HceObject} object
 * @param {number} level
 * @param {Reconstruction} [reconstruction]
 * @param {FlatRefinement} [flat]
 * @returns {CpuRefined}
 */
export function refineOnCpu(object, level, reconstruction = 'smooth', flat = 'adaptive') {
  const w = objectRequest(object);
  w.u32(level);
  w.u32(RECONSTRUCTION_WORD[reconstruction]);
  w.u32(FLAT_REFINEMENT_WORD[flat]);
  const r = call('hce_refine', w.finish());
  return { level: r.u32(), positions: r.floats(), normals: r.floats(), colours: r.floats(), indices: r.words(), triangleStart: r.words() };
}

/**
 * The indices of the refined triangles of coarse triangles `first .. first + count` (a
 * primitive's range, SPEC.md 2.3): refined triangles are grouped by coarse triangle, and
 * `triangleStart` says where each group starts.
 * @param {Uint32Array} indices 3 per refined triangle
 * @param {Uint32Array} triangleStart per coarse triangle its first triangle, then the count
 * @param {number} first
 * @param {number} count
 */
export function coarseRangeIndices(indices, triangleStart, first, count) {
  const at = (/** @type {number} */ t) => triangleStart[Math.min(t, triangleStart.length - 1)];
  return indices.subarray(3 * at(first), 3 * at(first + count));
}

/**
 * `triangleStart` of a uniform refinement to `level` of `coarse` triangles: `t · 4^level`.
 * @param {number} coarse
 * @param {number} level
 */
export function uniformTriangleStart(coarse, level) {
  const out = new Uint32Array(coarse + 1);
  for (let t = 0; t <= coarse; t++) out[t] = t * 4 ** level;
  return out;
}
