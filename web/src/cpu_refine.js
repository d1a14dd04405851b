// Refinement without WebGPU (three.js on its WebGL2 backend, WebGLRenderer, a browser without
// navigator.gpu): the Rust of `hce subdivide` in hce.wasm refines each object on the CPU, and
// this file only packs what it returns the way the GPU path's read-back does (Kernels.readBack:
// colours r, g, b, 1), so that a page draws either the same way.
import { refineOnCpu, MAX_LOOP_LEVEL } from './native.js';
import { flatLevel } from './scene.js';

/**
 * @typedef {import('./native.js').HceObject} HceObject
 * @typedef {import('./native.js').Reconstruction} Reconstruction
 * @typedef {import('./native.js').FlatRefinement} FlatRefinement
 * @typedef {{ level: number, positions: Float32Array, normals: Float32Array, colours: Float32Array, indices: Uint32Array, triangleStart: Uint32Array, ms: number }} CpuMesh
 *   `level` is the triangles' numbering level (0 for an adaptive flat object), `triangleStart`
 *   per coarse triangle its first refined triangle, then the count
 */

/**
 * The level `object` is refined to on the CPU for a requested `level`: a multiresolution
 * object's own (at most MAX_LOOP_LEVEL), a flat object's tree depth as the GPU path draws it
 * (scene.js `flatLevel`), at most MAX_LOOP_LEVEL too: the CPU's linear split stops there, as
 * `hce subdivide` does. (A flat object refined adaptively ignores its level: this is the level
 * reported for it, as the GPU path reports it.)
 * @param {HceObject} object
 * @param {number} level
 */
export function cpuLevel(object, level) {
  const wanted = object.kind === 'flat' ? flatLevel(object.treeDepth, object.records.length / 4) : level;
  return Math.max(0, Math.min(wanted, MAX_LOOP_LEVEL));
}

/**
 * Refines `object` to `level` on the CPU with its baked light (linear radiance), as
 * `hce subdivide --level LEVEL` refines it (a flat object from its trees, SPEC.md F.7.1, unless
 * `flat` is 'uniform'). Synchronous: it runs on the calling thread.
 * @param {HceObject} object
 * @param {number} level 0 to MAX_LOOP_LEVEL
 * @param {Reconstruction} [reconstruction]
 * @param {FlatRefinement} [flat]
 * @returns {CpuMesh}
 */
export function refineCpu(object, level, reconstruction = 'smooth', flat = 'adaptive') {
  const t0 = performance.now();
  const r = refineOnCpu(object, level, reconstruction, flat);
  const n = r.positions.length / 3;
  const colours = new Float32Array(4 * n);
  for (let i = 0; i < n; i++) {
    colours[4 * i] = r.colours[3 * i];
    colours[4 * i + 1] = r.colours[3 * i + 1];
    colours[4 * i + 2] = r.colours[3 * i + 2];
    colours[4 * i + 3] = 1;
  }
  return { level: r.level, positions: r.positions, normals: r.normals, colours, indices: r.indices, triangleStart: r.triangleStart, ms: performance.now() - t0 };
}

/**
 * What the three.js plugin refines with when its renderer has no WebGPU device: the CPU
 * refinement above, at the levels of {@link cpuLevel}.
 */
export class CpuRefiner {
  constructor() {
    /** @type {'cpu'} */
    this.path = 'cpu';
  }

  /**
   * @param {HceObject} object
   * @param {number} level the level asked for (a flat object gets its own, see cpuLevel)
   * @param {Reconstruction} [reconstruction]
   * @param {FlatRefinement} [flat]
   */
  refine(object, level, reconstruction = 'smooth', flat = 'adaptive') {
    return refineCpu(object, cpuLevel(object, level), reconstruction, flat);
  }
}
