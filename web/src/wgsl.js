// The WGSL sources of the kernels, fetched from the directory the Rust runtime compiles them
// from (runtime/src/gpu/) and assembled exactly as runtime/src/gpu/wgsl.rs assembles them:
// shared modules prepended in dependency order, and the `loop_normals.wgsl` template
// instantiated once per patch memory. There is no copy of any WGSL in web/.

/** The files the kernels are assembled from, all in runtime/src/gpu/. */
export const WGSL_FILES = /** @type {const} */ ([
  'hce_constants.wgsl',
  'hce_tree.wgsl',
  'hce_light.wgsl',
  'hce_lattice.wgsl',
  'hce_gather.wgsl',
  'loop.wgsl',
  'loop_workgroup.wgsl',
  'loop_normals.wgsl',
  'flat.wgsl',
  'decode.wgsl',
  'render.wgsl',
  'fill.wgsl',
]);

/** @typedef {Record<string, string>} WgslFiles file name → text */

/** The placeholder of `loop_normals.wgsl`: the prefix of a patch memory's accessors. */
const PATCH = '{patch}';

/**
 * Fetches every file of {@link WGSL_FILES} from `base` (a URL of the runtime/src/gpu/
 * directory, ending in `/`).
 * @param {string | URL} base
 * @param {typeof fetch} [fetchImpl]
 * @returns {Promise<WgslFiles>}
 */
export async function fetchWgsl(base, fetchImpl = fetch) {
  /** @type {WgslFiles} */
  const files = {};
  await Promise.all(
    WGSL_FILES.map(async (name) => {
      const url = new URL(name, base);
      const response = await fetchImpl(url);
      if (!response.ok) {
        throw new Error(`cannot load the kernel source ${url}: HTTP ${response.status}`);
      }
      files[name] = await response.text();
    }),
  );
  return files;
}

/**
 * The assembled modules, as `wgsl.rs` builds them.
 */
export class KernelSources {
  /** @param {WgslFiles} files */
  constructor(files) {
    for (const name of WGSL_FILES) {
      if (typeof files[name] !== 'string') throw new Error(`kernel source ${name} is missing`);
    }
    /** @private */
    this.files = files;
  }

  /**
   * The shared modules of a refinement kernel (flat and Loop), in dependency order, followed
   * by `kernel` (`wgsl.rs` `refinement_source`).
   * @param {string} kernel
   */
  refinement(kernel) {
    const f = this.files;
    return `${f['hce_constants.wgsl']}\n${f['hce_tree.wgsl']}\n${f['hce_light.wgsl']}\n${f['hce_lattice.wgsl']}\n${f['hce_gather.wgsl']}\n${kernel}`;
  }

  /**
   * `loop_normals.wgsl` for the patch memory whose accessors start with `prefix`.
   * @param {string} prefix
   */
  patchNormals(prefix) {
    return this.files['loop_normals.wgsl'].replaceAll(PATCH, prefix);
  }

  /** The flat kernel's module (`flat.rs`). */
  flat() {
    return this.refinement(this.files['flat.wgsl']);
  }

  /** The Loop kernel's module: its three steps, with the scratch patch kernel (`loop_source`). */
  loop() {
    return this.refinement(`${this.files['loop.wgsl']}\n${this.patchNormals('')}`);
  }

  /**
   * A variant of the workgroup patch kernel (`loop_workgroup_source`): the Loop module, then
   * `header` (the variant's constants) and `loop_workgroup.wgsl` with its normals.
   * @param {string} header
   */
  loopWorkgroup(header) {
    return `${this.loop()}\n${header}\n${this.files['loop_workgroup.wgsl']}\n${this.patchNormals('wg_')}`;
  }

  /** The colour-decoding kernel of the tests (`decode.rs`). */
  decode() {
    return `${this.files['hce_constants.wgsl']}\n${this.files['hce_tree.wgsl']}\n${this.files['decode.wgsl']}`;
  }

  /** The headless renderer's module (`render.rs`). */
  render() {
    return this.files['render.wgsl'];
  }

  /** The bandwidth reference of `hce bench-gpu` (`bench.rs`). */
  fill() {
    return this.files['fill.wgsl'];
  }
}

/** Triangles per workgroup the cooperative kernel aims for at levels 0 to 5 (`loop_kernel.rs`). */
const WG_TRIANGLES = [16, 8, 4, 2, 1, 1];

/**
 * The shape of one variant of the workgroup kernel (`WgShape` in `loop_kernel.rs`): its level,
 * the triangles per workgroup and the floats of one triangle's regions.
 */
export class WgShape {
  /**
   * @param {number} level
   * @param {number} tris
   * @param {number} squareA
   * @param {number} squareB
   * @param {number} ring
   */
  constructor(level, tris, squareA, squareB, ring) {
    this.level = level;
    this.tris = tris;
    this.squareA = squareA;
    this.squareB = squareB;
    this.ring = ring;
  }

  /**
   * The variant for `level` when a triangle's three rings hold at most `ringPoints` points,
   * or `null` when one triangle's patch does not fit `limit` bytes of workgroup memory.
   * @param {number} level
   * @param {number} ringPoints
   * @param {number} limit
   * @returns {WgShape | null}
   */
  static fit(level, ringPoints, limit) {
    const square = (/** @type {number} */ n) => (3 * (n + 4) * (n + 5)) / 2;
    const m = 2 ** level;
    const wanted = WG_TRIANGLES[level];
    if (wanted === undefined) return null;
    const shape = new WgShape(level, wanted, square(m), level === 0 ? 0 : square(m / 2), 3 * ringPoints);
    while (shape.tris > 1 && shape.bytes() > limit) shape.tris = Math.floor(shape.tris / 2);
    return shape.bytes() > limit ? null : shape;
  }

  /** Workgroup memory of the variant: the patches and, per triangle, its corner table. */
  bytes() {
    return this.tris * (4 * (this.squareA + this.squareB + 2 * this.ring) + 96);
  }

  /** The constants `loop_workgroup.wgsl` expects ahead of it. */
  header() {
    return (
      `const WG_LEVEL: u32 = ${this.level}u;\nconst WG_TRIS: u32 = ${this.tris}u;\n` +
      `const WG_SQ_A: u32 = ${this.squareA}u;\nconst WG_SQ_B: u32 = ${this.squareB}u;\n` +
      `const WG_RING: u32 = ${this.ring}u;\n`
    );
  }

  /** A key naming the variant. */
  key() {
    return `${this.level}/${this.tris}/${this.squareA}/${this.squareB}/${this.ring}`;
  }
}
