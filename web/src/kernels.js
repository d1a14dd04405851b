// The refinement kernels on a WebGPU device: the flat kernel (flat.wgsl) and the Loop kernel
// (loop.wgsl, its scratch patch kernel), as runtime/src/gpu/flat.rs and loop_kernel.rs drive
// them: the same WGSL, the same uniform blocks, the same packed sections and bindings, one
// bind-group layout per entry point ('auto'), so every step stays within WebGPU's default
// limit of 8 storage buffers per stage.
import { HceError } from './errors.js';
import { MAX_LOOP_LEVEL, MAX_PATH_LEVEL, objectTables, uniformTriangleStart } from './native.js';

/** @typedef {import('./native.js').HceObject} HceObject */
/** @typedef {import('./native.js').Reconstruction} Reconstruction */

/** Threads per workgroup of every 1-D kernel. */
const WORKGROUP = 64;
/** Upper bound of the Loop kernel's scratch buffer (loop_kernel.rs `SCRATCH_BUDGET`). */
const SCRATCH_BUDGET = 256 * 1024 * 1024;
const STORAGE = 0x80; // GPUBufferUsage.STORAGE, spelled out so the module loads outside a browser.
const COPY_SRC = 0x04;
const COPY_DST = 0x08;
const UNIFORM = 0x40;
const VERTEX = 0x20;
const INDEX = 0x10;
const MAP_READ = 0x01;

/**
 * Sections packed into one word buffer, with where each starts (util.rs `pack_sections`).
 * @param {ArrayLike<number>[]} sections
 */
function packSections(sections) {
  const total = sections.reduce((s, a) => s + a.length, 0);
  const packed = new Uint32Array(Math.max(total, 1));
  const offsets = [];
  let at = 0;
  for (const s of sections) {
    offsets.push(at);
    packed.set(s, at);
    at += s.length;
  }
  return { packed, offsets };
}

/**
 * The triangle records as the `array<TriRecord>` words the kernels read.
 * @param {HceObject} o
 */
const recordsWords = (o) => o.records;

/**
 * A refined object's buffers on the GPU: drawable as they are.
 * @typedef {object} RefinedBuffers
 * @property {number} level
 * @property {number} vertexCount
 * @property {number} triangleCount
 * @property {GPUBuffer} positions x, y, z f32 per vertex
 * @property {GPUBuffer | null} normals x, y, z f32 per vertex (Loop only)
 * @property {GPUBuffer} colours linear r, g, b, 1 f32 per vertex
 * @property {GPUBuffer} indices u32 ×3 per fine triangle
 * @property {GPUBuffer} faces linear r, g, b, area per fine triangle
 * @property {GPUBuffer | null} scratch
 * @property {Uint32Array} triangleStart per coarse triangle its first refined triangle, then
 *   the count (`t · 4^level`, or an adaptive flat object's own)
 */

/**
 * An object uploaded: its tables checked and on the GPU.
 * @typedef {object} UploadedObject
 * @property {HceObject} object
 * @property {Reconstruction} reconstruction
 * @property {number} treeDepth
 * @property {import('./native.js').ObjectTables['topology']} topology
 * @property {import('./native.js').ObjectTables['loop']} loop
 * @property {import('./native.js').ObjectTables['split']} split the split where the surface folds (F.5)
 * @property {import('./native.js').AdaptiveLists | null} adaptive a flat object's adaptive
 *   refinement (SPEC.md F.7.1), drawn whatever the level; null for the uniform one
 * @property {number[]} offsets where the packed sections start in `topo`
 * @property {Record<string, GPUBuffer>} buffers
 */

/**
 * The kernels of one device. Build with {@link Kernels.create}, which compiles every pipeline
 * once, asynchronously (on SwiftShader a pipeline takes seconds), reporting progress.
 */
export class Kernels {
  /**
   * @param {GPUDevice} device
   * @param {Record<string, GPUComputePipeline>} pipelines
   * @param {Record<string, number>} bindings the shared bindings' numbers by WGSL name
   *   (`KernelSources.bindings`)
   */
  constructor(device, pipelines, bindings) {
    this.device = device;
    this.pipelines = pipelines;
    /** @private */
    this.bindings = bindings;
  }

  /**
   * The number of shared binding `name` (hce_bindings.wgsl).
   * @private
   * @param {string} name
   */
  at(name) {
    const b = this.bindings[name];
    if (b === undefined) throw new HceError('', `hce_bindings.wgsl declares no binding ${name}`);
    return b;
  }

  /**
   * @param {GPUDevice} device
   * @param {import('./wgsl.js').KernelSources} sources
   * @param {(done: number, total: number, label: string) => void} [progress]
   */
  static async create(device, sources, progress = () => {}) {
    const flat = device.createShaderModule({ label: 'hce flat', code: sources.flat() });
    const loop = device.createShaderModule({ label: 'hce loop', code: sources.loop() });
    const wanted = /** @type {[string, GPUShaderModule, string][]} */ ([
      ['flat_positions', flat, 'positions_main'],
      ['flat_faces', flat, 'faces_main'],
      ['flat_colours', flat, 'colours_main'],
      ['loop_patch', loop, 'patch_main'],
      ['loop_faces', loop, 'faces_main'],
      ['loop_colours', loop, 'colours_main'],
    ]);
    for (const [label, module] of [['flat', flat], ['loop', loop]]) {
      const info = await /** @type {GPUShaderModule} */ (module).getCompilationInfo();
      const errors = info.messages.filter((m) => m.type === 'error');
      if (errors.length > 0) {
        throw new HceError('', `the ${label} kernel does not compile on this browser: ${errors.map((m) => `${m.lineNum}:${m.linePos} ${m.message}`).join('; ')}`);
      }
    }
    /** @type {Record<string, GPUComputePipeline>} */
    const pipelines = {};
    let done = 0;
    progress(0, wanted.length, 'compiling kernels');
    // One at a time: SwiftShader compiles on the same few threads anyway, and the progress
    // counts whole pipelines.
    for (const [key, module, entryPoint] of wanted) {
      pipelines[key] = await device.createComputePipelineAsync({ label: `hce ${key}`, layout: 'auto', compute: { module, entryPoint } });
      done += 1;
      progress(done, wanted.length, entryPoint);
    }
    return new Kernels(device, pipelines, sources.bindings());
  }

  /**
   * @param {string} label
   * @param {ArrayBufferView} data
   */
  storage(label, data) {
    const size = Math.max(4, Math.ceil(data.byteLength / 4) * 4);
    this.checkSize(label, size);
    const buffer = this.device.createBuffer({ label, size, usage: STORAGE | COPY_SRC | COPY_DST });
    if (data.byteLength > 0) this.device.queue.writeBuffer(buffer, 0, data.buffer, data.byteOffset, data.byteLength);
    return buffer;
  }

  /** @param {string} what @param {number} bytes */
  checkSize(what, bytes) {
    const limits = this.device.limits;
    const limit = Math.min(limits.maxBufferSize, limits.maxStorageBufferBindingSize);
    if (bytes > limit) throw new HceError('', `${what} needs ${bytes} bytes but the device allows at most ${limit} per buffer; choose a lower level`);
    return Math.max(4, Math.ceil(bytes / 4) * 4);
  }

  /**
   * Checks `object` (every table the kernels index, SPEC.md Appendix C), builds the derived
   * tables and the lighting table, and uploads them; a flat object with the lists of its
   * adaptive refinement (SPEC.md F.7.1) unless `flat` is 'uniform'.
   * @param {HceObject} object
   * @param {Reconstruction} [reconstruction]
   * @param {import('./native.js').FlatRefinement} [flat]
   * @returns {UploadedObject}
   */
  upload(object, reconstruction = 'smooth', flat = 'adaptive') {
    // Checked and built by the Rust of the native upload (hce.wasm): the same words.
    const { treeDepth, topology, split, loop, light, adaptive } = objectTables(object, reconstruction, flat);
    const m = object.mesh;
    // The split where the surface folds (SPEC.md F.5): its slot lists replace the vertex and
    // edge incidence, as loop_kernel.rs and flat.rs `upload_with` pack them.
    let packed;
    if (loop) {
      packed = packSections([
        m.triangles, m.ringOffsets, m.ring, m.spokeFlags, m.vertexFlags, m.cornerSpokes, m.edges,
        loop.triFlags, loop.crease, loop.weights, split.edgeSlotOffsets, split.edgeSlotSides,
        split.cornerSlotOffsets, split.cornerSlotCorners, split.cornerCopy, split.edgeCopy,
        split.slotSplit,
      ]);
    } else {
      // Then the adaptive lists (empty for the uniform refinement), as flat.rs `upload` packs
      // its 14 sections.
      const none = new Uint32Array(0);
      packed = packSections([
        m.triangles, m.edges, topology.edgeVerts, split.edgeSlotOffsets, split.edgeSlotSides,
        split.cornerSlotOffsets, split.cornerSlotCorners, split.cornerCopy, split.edgeCopy,
        ...(adaptive ? adaptive.sections : [none, none, none, none, none]),
      ]);
    }
    return {
      object,
      reconstruction,
      treeDepth,
      topology,
      loop,
      split,
      adaptive,
      offsets: packed.offsets,
      buffers: {
        positions: this.storage('coarse positions', m.positions),
        topo: this.storage('topology', packed.packed),
        records: this.storage('records', recordsWords(object)),
        bits: this.storage('bits', object.bits),
        normals: this.storage('normals', object.normals),
        colours: this.storage('colours', object.colours),
        light: this.storage('lighting table', light),
      },
    };
  }

  /**
   * Vertex and triangle counts of `u` at `level`, checked (F.5); an adaptive flat object's
   * own, whatever the level (F.7.1).
   * @param {UploadedObject} u
   * @param {number} level
   */
  counts(u, level) {
    if (u.adaptive) return { v: u.adaptive.vertices, f: u.adaptive.triangles, appended: 0 };
    const max = u.loop ? MAX_LOOP_LEVEL : MAX_PATH_LEVEL;
    if (!Number.isInteger(level) || level < 0 || level > max) throw new HceError('', `level ${level} is out of range; use 0..=${max}`);
    const t = u.topology;
    const n = 2 ** level;
    const perTri = ((n - 1) * Math.max(n - 2, 0)) / 2;
    // Vertices appended by the split at sharp edges (F.5): X + S (n − 1).
    const appended = u.split.copies + u.split.splitEdges * (n - 1);
    const v = t.vertexCount + t.edgeCount * (n - 1) + t.triangleCount * perTri + appended;
    const f = t.triangleCount * 4 ** level;
    if (v > 0xffffffff || 3 * f > 0xffffffff) throw new HceError('', `level ${level} of '${u.object.name}' needs more than 2^32 vertices or indices`);
    return { v, f, appended };
  }

  /** @param {number} threads @returns {[number, number]} */
  dispatchSize(threads) {
    const groups = Math.max(1, Math.ceil(threads / WORKGROUP));
    const max = this.device.limits.maxComputeWorkgroupsPerDimension;
    const x = Math.min(groups, max);
    const y = Math.ceil(groups / x);
    if (y > max) throw new HceError('', `a dispatch of ${threads} invocations exceeds the device's workgroup grid`);
    return [x, y];
  }

  /**
   * Refines `u` to `level` into `out` (reallocated when absent or too small) and submits the
   * work; await `device.queue.onSubmittedWorkDone()` to time it. An adaptive flat object is
   * refined from its trees whatever `level` (its buffers' level is 0).
   * @param {UploadedObject} u
   * @param {number} asked
   * @param {RefinedBuffers | null} [out]
   * @returns {RefinedBuffers}
   */
  refine(u, asked, out = null) {
    const { v, f, appended } = this.counts(u, asked);
    // The uniform lattice's level; the adaptive lists have none (flat.rs `begin`).
    const level = u.adaptive ? 0 : asked;
    const triangleStart = u.adaptive ? u.adaptive.triangleStart : uniformTriangleStart(u.topology.triangleCount, level);
    const d = this.device;
    const isLoop = u.loop !== null;
    const output = (/** @type {string} */ label, /** @type {number} */ bytes, /** @type {number} */ extra) =>
      d.createBuffer({ label, size: this.checkSize(label, bytes), usage: STORAGE | COPY_SRC | extra });
    const fits = out !== null && out.positions.size >= v * 12 && out.colours.size >= v * 16 && out.indices.size >= f * 12 && out.faces.size >= f * 16 && (!isLoop || (out.normals !== null && out.normals.size >= v * 12));
    /** @type {RefinedBuffers} */
    const o = fits && out !== null ? out : {
      level,
      vertexCount: v,
      triangleCount: f,
      positions: output('refined positions', v * 12, VERTEX),
      normals: isLoop ? output('refined normals', v * 12, VERTEX) : null,
      colours: output('refined colours', v * 16, VERTEX),
      indices: output('refined indices', f * 12, INDEX),
      faces: output('refined faces', f * 16, 0),
      scratch: null,
      triangleStart,
    };
    if (!fits && out !== null) destroyRefined(out);
    o.level = level;
    o.vertexCount = v;
    o.triangleCount = f;
    o.triangleStart = triangleStart;
    const b = u.buffers;
    const smooth = u.reconstruction === 'nearest' ? 0 : 1;
    const n = 2 ** level;
    const t = u.topology;
    const encoder = d.createCommandEncoder({ label: 'hce refine' });
    // The buffers of each step by their names in hce_bindings.wgsl; binding 0 is the uniform.
    /** @type {[GPUComputePipeline, [string, GPUBuffer][], [number, number]][]} */
    let steps;
    /** @type {[string, GPUBuffer][]} */
    const tree = [['hce_records', b.records], ['hce_bits', b.bits], ['hce_normals', b.normals], ['hce_colours', b.colours]];
    let uniform;
    if (!isLoop) {
      const params = new Uint32Array([
        level, n, t.vertexCount, t.edgeCount, t.triangleCount, n < 2 ? 0 : ((n - 1) * (n - 2)) / 2, v, f,
        // split_base and split_copies: an adaptive object's lists hold its split vertices.
        ...u.offsets.slice(0, 7), smooth, u.offsets[7], u.offsets[8], u.adaptive ? v : v - appended, u.adaptive ? 0 : u.split.copies,
        // range_first, range_end: every item of each step in one dispatch.
        0, 0xffffffff,
        // adaptive, then where its lists' five sections start.
        u.adaptive ? 1 : 0, ...u.offsets.slice(9, 14),
      ]);
      uniform = d.createBuffer({ label: 'flat params', size: params.byteLength, usage: UNIFORM | COPY_DST });
      d.queue.writeBuffer(uniform, 0, params);
      const vg = this.dispatchSize(v);
      const fg = this.dispatchSize(f);
      const p = this.pipelines;
      steps = [
        [p.flat_positions, [['coarse_positions', b.positions], ['topo', b.topo], ['out_positions', o.positions]], vg],
        [p.flat_faces, [['topo', b.topo], ...tree, ['out_positions', o.positions], ['out_indices', o.indices], ['out_faces', o.faces]], fg],
        [p.flat_colours, [['topo', b.topo], ['out_faces', o.faces], ['out_colours', o.colours], ['hce_light', b.light]], vg],
      ];
    } else {
      const loop = /** @type {NonNullable<UploadedObject['loop']>} */ (u.loop);
      // The scratch patch kernel (loop_kernel.rs `scratch_shape`): one slot per triangle in
      // flight, within the budget and the device's binding limit.
      const w = n + 3;
      const square = 3 * w * w;
      const slotBytes = 4 * (2 * square + 18 * loop.maxValence);
      const limits = d.limits;
      const budget = Math.min(SCRATCH_BUDGET, limits.maxStorageBufferBindingSize, limits.maxBufferSize);
      if (slotBytes > budget) throw new HceError('', `one triangle's subdivision scratch needs ${slotBytes} bytes, more than the device's ${budget}`);
      let slots = Math.max(1, Math.min(Math.floor(budget / slotBytes), t.triangleCount));
      if (slots > WORKGROUP) slots = Math.floor(slots / WORKGROUP) * WORKGROUP;
      if (o.scratch === null || o.scratch.size < slotBytes * slots) {
        o.scratch?.destroy();
        o.scratch = output('loop scratch', slotBytes * slots, 0);
      }
      const params = new Uint32Array([
        level, n, t.vertexCount, t.edgeCount, t.triangleCount, n - 1, ((n - 1) * Math.max(n - 2, 0)) / 2, v, f,
        slots, square, loop.maxValence, ...u.offsets, 1, smooth, v - appended,
        u.split.copies, 0, 0xffffffff,
      ]);
      uniform = d.createBuffer({ label: 'loop params', size: params.byteLength, usage: UNIFORM | COPY_DST });
      d.queue.writeBuffer(uniform, 0, params);
      const p = this.pipelines;
      const normals = /** @type {GPUBuffer} */ (o.normals);
      steps = [
        [p.loop_patch, [['coarse_positions', b.positions], ['topo', b.topo], ['scratch', o.scratch], ['out_positions', o.positions], ['out_normals', normals]], this.dispatchSize(slots)],
        [p.loop_faces, [['topo', b.topo], ...tree, ['out_positions', o.positions], ['out_indices', o.indices], ['out_faces', o.faces]], this.dispatchSize(f)],
        [p.loop_colours, [['topo', b.topo], ['out_positions', o.positions], ['out_normals', normals], ['out_faces', o.faces], ['out_colours', o.colours], ['hce_light', b.light]], this.dispatchSize(v)],
      ];
    }
    // One pass per step: each sees the previous one's writes.
    for (const [pipeline, entries, size] of steps) {
      const group = d.createBindGroup({
        layout: pipeline.getBindGroupLayout(0),
        entries: [
          { binding: 0, resource: { buffer: uniform } },
          ...entries.map(([name, buffer]) => ({ binding: this.at(name), resource: { buffer } })),
        ],
      });
      const pass = encoder.beginComputePass();
      pass.setPipeline(pipeline);
      pass.setBindGroup(0, group);
      pass.dispatchWorkgroups(size[0], size[1], 1);
      pass.end();
    }
    d.queue.submit([encoder.finish()]);
    uniform.destroy();
    return o;
  }

  /**
   * Copies a refined mesh back: positions, normals (Loop), colours, indices.
   * @param {RefinedBuffers} o
   */
  async readBack(o) {
    const d = this.device;
    /** @type {[string, GPUBuffer | null, number][]} */
    const parts = [
      ['positions', o.positions, o.vertexCount * 12],
      ['normals', o.normals, o.vertexCount * 12],
      ['colours', o.colours, o.vertexCount * 16],
      ['indices', o.indices, o.triangleCount * 12],
    ];
    const encoder = d.createCommandEncoder();
    const staging = parts.map(([label, src, bytes]) => {
      if (src === null || bytes === 0) return null;
      const buffer = d.createBuffer({ label: `read back ${label}`, size: Math.ceil(bytes / 4) * 4, usage: MAP_READ | COPY_DST });
      encoder.copyBufferToBuffer(src, 0, buffer, 0, buffer.size);
      return buffer;
    });
    d.queue.submit([encoder.finish()]);
    /** @type {Record<string, ArrayBuffer | null>} */
    const out = {};
    await Promise.all(staging.map(async (buffer, i) => {
      if (buffer === null) {
        out[parts[i][0]] = null;
        return;
      }
      await buffer.mapAsync(1);
      out[parts[i][0]] = buffer.getMappedRange().slice(0, parts[i][2]);
      buffer.destroy();
    }));
    return {
      level: o.level,
      triangleStart: o.triangleStart,
      positions: new Float32Array(/** @type {ArrayBuffer} */ (out.positions ?? new ArrayBuffer(0))),
      normals: out.normals ? new Float32Array(out.normals) : null,
      colours: new Float32Array(/** @type {ArrayBuffer} */ (out.colours ?? new ArrayBuffer(0))),
      indices: new Uint32Array(/** @type {ArrayBuffer} */ (out.indices ?? new ArrayBuffer(0))),
    };
  }
}

/**
 * Frees a refined object's buffers.
 * @param {RefinedBuffers} o
 */
export function destroyRefined(o) {
  for (const b of [o.positions, o.normals, o.colours, o.indices, o.faces, o.scratch]) b?.destroy();
}

/**
 * Frees an uploaded object's buffers.
 * @param {UploadedObject} u
 */
export function destroyUploaded(u) {
  for (const b of Object.values(u.buffers)) b.destroy();
}
