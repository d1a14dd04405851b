// The WGSL sources of the kernels, fetched from the directory the Rust runtime compiles them
// from (runtime/src/gpu/) and assembled exactly as runtime/src/gpu/wgsl.rs assembles them: each
// module names the modules it needs in its own file (`// #import hce_tree`), and a kernel's
// source is its module after every module it imports, each once, in the order of a
// depth-first walk of those declarations; the `loop_normals.wgsl` template is instantiated once
// per patch memory. There is no copy of any WGSL in web/, and no list of its modules either.

/**
 * The modules the browser compiles (the kernels, the renderer, the bandwidth reference) and the
 * normals template: every other file is found through their imports.
 */
export const WGSL_ROOTS = /** @type {const} */ ([
  'flat',
  'loop',
  'loop_workgroup',
  'loop_normals',
  'decode',
  'render',
  'fill',
]);

/** @typedef {Record<string, string>} WgslFiles file name (`hce_tree.wgsl`) → text */

/** The placeholder of `loop_normals.wgsl`: the prefix of a patch memory's accessors. */
const PATCH = '{patch}';

/** The line that starts an import declaration. */
const IMPORT = '// #import ';

/**
 * The modules a module's `text` imports, in the order it declares them (`wgsl.rs` `imports`).
 * @param {string} text
 * @returns {string[]}
 */
export function imports(text) {
  return text
    .split('\n')
    .map((line) => line.trim())
    .filter((line) => line.startsWith(IMPORT))
    .map((line) => line.slice(IMPORT.length).trim());
}

/**
 * `root` and every module it imports, directly or not, each once, every module after the
 * modules it imports (`wgsl.rs` `import_order`). Throws, naming the modules, on an import of a
 * module that `text` does not have or on a circular import.
 * @param {string} root
 * @param {(name: string) => string | undefined} text a module's file, by name
 * @returns {string[]}
 */
export function importOrder(root, text) {
  /** @type {string[]} */
  const order = [];
  /** @type {string[]} */
  const path = [];
  const visit = (/** @type {string} */ module) => {
    if (order.includes(module)) return;
    const at = path.indexOf(module);
    if (at >= 0) throw new Error(`circular import: ${[...path.slice(at), module].join(' -> ')}`);
    const source = text(module);
    if (source === undefined) {
      const importer = path[path.length - 1];
      throw new Error(
        importer === undefined
          ? `no module ${module} (${module}.wgsl)`
          : `${importer}.wgsl imports ${module}, which is not a module (no ${module}.wgsl)`,
      );
    }
    path.push(module);
    for (const i of imports(source)) visit(i);
    path.pop();
    order.push(module);
  };
  visit(root);
  return order;
}

/**
 * Reads every file of {@link WGSL_ROOTS} and, following their imports, every module they
 * need, with `read` (a file name to its text).
 * @param {(file: string) => Promise<string>} read
 * @returns {Promise<WgslFiles>}
 */
export async function loadWgsl(read) {
  /** @type {WgslFiles} */
  const files = {};
  /** @type {string[]} */
  let wanted = [...WGSL_ROOTS];
  while (wanted.length > 0) {
    const texts = await Promise.all(wanted.map((m) => read(`${m}.wgsl`)));
    wanted.forEach((m, i) => {
      files[`${m}.wgsl`] = texts[i];
    });
    wanted = [...new Set(texts.flatMap(imports))].filter((m) => files[`${m}.wgsl`] === undefined);
  }
  return files;
}

/**
 * Fetches the kernels' files ({@link loadWgsl}) from `base` (a URL of the runtime/src/gpu/
 * directory, ending in `/`).
 * @param {string | URL} base
 * @param {typeof fetch} [fetchImpl]
 * @returns {Promise<WgslFiles>}
 */
export async function fetchWgsl(base, fetchImpl = fetch) {
  return loadWgsl(async (name) => {
    const url = new URL(name, base);
    const response = await fetchImpl(url);
    if (!response.ok) {
      throw new Error(`cannot load the kernel source ${url}: HTTP ${response.status}`);
    }
    return response.text();
  });
}

/**
 * The kernels' files as the npm package ships them (`wgsl/`, copied byte for byte from
 * runtime/src/gpu/ when the package is packed: `scripts/prepack.js`), each reached through
 * `import.meta.url` so that a bundler (Vite, Rollup, webpack) emits it with the bundle.
 * @param {typeof fetch} [fetchImpl]
 * @returns {Promise<WgslFiles>}
 */
export async function packagedWgsl(fetchImpl = fetch) {
  return loadWgsl(async (name) => {
    const url = new URL(`../wgsl/${name}`, import.meta.url);
    const response = await fetchImpl(url).catch((e) => {
      throw new Error(`cannot load the kernel source ${url}: ${e}`);
    });
    if (!response.ok) {
      throw new Error(`cannot load the kernel source ${url}: HTTP ${response.status} (outside the npm package, pass wgslBase: the URL of runtime/src/gpu/)`);
    }
    return response.text();
  });
}

/**
 * The kernels' files from `wgslBase` when given ({@link fetchWgsl}), else the package's own
 * ({@link packagedWgsl}).
 * @param {string | URL | undefined} wgslBase
 */
export function kernelFiles(wgslBase) {
  return wgslBase === undefined ? packagedWgsl() : fetchWgsl(wgslBase);
}

/**
 * The assembled modules, as `wgsl.rs` builds them.
 */
export class KernelSources {
  /** @param {WgslFiles} files */
  constructor(files) {
    /** @private */
    this.files = files;
    // Every import resolves, or the error names the module now rather than at compile time.
    for (const root of WGSL_ROOTS) importOrder(root, (m) => this.text(m));
  }

  /**
   * The text of module `name`, `undefined` where there is none.
   * @private
   * @param {string} name
   */
  text(name) {
    const t = this.files[`${name}.wgsl`];
    return typeof t === 'string' ? t : undefined;
  }

  /**
   * The source of kernel `root`: its modules in import order, each passed through `expand`
   * (what a module is assembled with, given its name and text), joined by newlines.
   * @private
   * @param {string} root
   * @param {(name: string, text: string) => string} [expand]
   */
  assemble(root, expand = (_, text) => text) {
    return importOrder(root, (m) => this.text(m))
      .map((m) => expand(m, /** @type {string} */ (this.text(m))))
      .join('\n');
  }

  /**
   * `loop_normals.wgsl` for the patch memory whose accessors start with `prefix`.
   * @param {string} prefix
   */
  patchNormals(prefix) {
    return /** @type {string} */ (this.text('loop_normals')).replaceAll(PATCH, prefix);
  }

  /**
   * `loop.wgsl` with the normals of its scratch patch kernel; `loop_workgroup.wgsl` after
   * `header` with the normals of workgroup memory (`wgsl.rs` `loop_module`).
   * @private
   * @param {string} name
   * @param {string} text
   * @param {string} header
   */
  loopModule(name, text, header) {
    if (name === 'loop') return `${text}\n${this.patchNormals('')}`;
    if (name === 'loop_workgroup') return `${header}\n${text}\n${this.patchNormals('wg_')}`;
    return text;
  }

  /**
   * The binding numbers of `hce_bindings.wgsl`, the storage buffers the kernels share, by
   * their WGSL names (`bindings.rs` is the Rust twin): read from the file, so that the numbers
   * are written there alone.
   * @returns {Record<string, number>}
   */
  bindings() {
    /** @type {Record<string, number>} */
    const out = {};
    const text = this.text('hce_bindings') ?? '';
    for (const m of text.matchAll(/@binding\((\d+)\)\s*var(?:<[^>]*>)?\s+(\w+)/g)) out[m[2]] = Number(m[1]);
    return out;
  }

  /** The flat kernel's module (`flat.rs`). */
  flat() {
    return this.assemble('flat');
  }

  /** The Loop kernel's module: its three steps, with the scratch patch kernel (`loop_source`). */
  loop() {
    return this.assemble('loop', (name, text) => this.loopModule(name, text, ''));
  }

  /**
   * A variant of the workgroup patch kernel (`loop_workgroup_source`): the Loop module, then
   * `header` (the variant's constants) and `loop_workgroup.wgsl` with its normals.
   * @param {string} header
   */
  loopWorkgroup(header) {
    return this.assemble('loop_workgroup', (name, text) => this.loopModule(name, text, header));
  }

  /** The colour-decoding kernel of the tests (`decode.rs`). */
  decode() {
    return this.assemble('decode');
  }

  /** The headless renderer's module (`render.rs`). */
  render() {
    return this.assemble('render');
  }

  /** The bandwidth reference of `hce bench-gpu` (`bench.rs`). */
  fill() {
    return this.assemble('fill');
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
