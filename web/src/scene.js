// A loaded asset on the GPU (the browser's twin of runtime/src/gpu/scene.rs `GpuScene`): per
// object its tables uploaded once, its level (forced, or chosen from the view by the rule of
// `choose_level`), its refined buffers reused while large enough, and the draws of every
// instance; plus a renderer that draws them with the runtime's render.wgsl and tone-maps the
// result to a canvas.
import { destroyRefined, destroyUploaded } from './kernels.js';
import { multiply } from './math.js';
import { DEFAULT_LOD, objectLevel, viewProjection } from './view.js';
import { MAX_PATH_LEVEL } from './native.js';

/**
 * @typedef {import('./kernels.js').Kernels} Kernels
 * @typedef {import('./kernels.js').Reconstruction} Reconstruction
 * @typedef {import('./native.js').Asset} Asset
 * @typedef {import('./view.js').Camera} Camera
 */

/** Flat objects are split to their tree depth up to this level whatever their size (scene.rs `SceneOptions::flat_max_level`). */
export const FLAT_MAX_LEVEL = 7;
/** ... and deeper while they stay within this many fine triangles (scene.rs `SceneOptions::flat_max_triangles`). */
export const FLAT_MAX_TRIANGLES = 2 ** 22;

/**
 * The level a flat object is drawn at, whatever level the view asks for: its tree depth, up to
 * FLAT_MAX_LEVEL always and deeper only while the object stays within FLAT_MAX_TRIANGLES fine
 * triangles. The twin of scene.rs `flat_level`, which says why.
 * @param {number} treeDepth the depth of the object's deepest leaf
 * @param {number} coarseTriangles
 * @returns {number}
 */
export function flatLevel(treeDepth, coarseTriangles) {
  let level = Math.min(treeDepth, FLAT_MAX_LEVEL);
  while (level < treeDepth && level < MAX_PATH_LEVEL && coarseTriangles * 4 ** (level + 1) <= FLAT_MAX_TRIANGLES) level++;
  return level;
}
/** `hce render`'s default triangle budget. */
export const DEFAULT_TRIANGLE_BUDGET = 16_000_000;

/**
 * The level each object should be drawn at for `camera` (forced levels win; flat objects get
 * their tree depth), lowered while the scene is over the triangle budget: the rule of
 * HceScene.levelsFor, for any path that draws a scene (the WebGL2 one too). An object with
 * `triangles` (an adaptive flat object, SPEC.md F.7.1) draws that many whatever its level, so
 * lowering it gains nothing: it keeps its level, as scene.rs `levels_within` keeps it.
 * @param {{ source: import('./native.js').AssetObject, forced: number | null, treeDepth: number, triangles?: number | null }[]} objects
 * @param {Camera} camera
 * @param {number} viewportHeight
 * @param {import('./view.js').LodParams} lod
 * @param {number} triangleBudget
 * @returns {number[]} -1 for objects that are not drawn
 */
export function sceneLevels(objects, camera, viewportHeight, lod, triangleBudget) {
  const levels = objects.map((o) => {
    if (o.source.instances.length === 0) return -1;
    if (o.source.object.kind === 'flat') return flatLevel(o.treeDepth, o.source.object.records.length / 4);
    return o.forced ?? objectLevel(o.source, camera, viewportHeight, lod);
  });
  const tris = (/** @type {number} */ i, /** @type {number} */ l) => (objects[i].triangles ?? (objects[i].source.object.records.length / 4) * 4 ** l) * objects[i].source.instances.length;
  const total = () => levels.reduce((s, l, i) => s + (l >= 0 ? tris(i, l) : 0), 0);
  while (total() > triangleBudget) {
    let worst = -1;
    for (let i = 0; i < levels.length; i++) {
      const lowerable = levels[i] > 0 && (objects[i].forced === null || objects[i].source.object.kind === 'flat') && objects[i].triangles == null;
      if (lowerable && (worst < 0 || tris(i, levels[i]) > tris(worst, levels[worst]))) worst = i;
    }
    if (worst < 0) break;
    levels[worst] -= 1;
  }
  return levels;
}

/**
 * @typedef {object} SceneObject
 * @property {import('./native.js').AssetObject} source
 * @property {import('./kernels.js').UploadedObject | null} uploaded
 * @property {import('./kernels.js').RefinedBuffers | null} refined
 * @property {number | null} forced a level set by the user, or null for automatic
 * @property {number} level the level drawn (-1 before the first refinement)
 * @property {number} refineMs wall time of the last refinement (submit to done)
 */

export class HceScene {
  /**
   * @param {Kernels} kernels
   * @param {Asset} asset
   * @param {{ reconstruction?: Reconstruction, triangleBudget?: number, flatRefinement?: import('./native.js').FlatRefinement }} [options]
   *   `flatRefinement`: how flat objects are drawn, 'adaptive' from their trees (the default,
   *   SPEC.md F.7.1) or 'uniform' to their tree depth (F.7.2, scene.rs `SceneOptions::flat_refinement`)
   */
  constructor(kernels, asset, options = {}) {
    this.kernels = kernels;
    this.asset = asset;
    this.reconstruction = options.reconstruction ?? 'smooth';
    this.flatRefinement = options.flatRefinement ?? 'adaptive';
    this.triangleBudget = options.triangleBudget ?? DEFAULT_TRIANGLE_BUDGET;
    /** @type {SceneObject[]} */
    this.objects = asset.objects.map((source) => ({ source, uploaded: null, refined: null, forced: null, level: -1, refineMs: 0 }));
  }

  /** Uploads every drawn object (checks its tables first: a damaged object throws here). */
  upload() {
    for (const o of this.objects) {
      if (o.uploaded === null && o.source.instances.length > 0) o.uploaded = this.kernels.upload(o.source.object, this.reconstruction, this.flatRefinement);
    }
  }

  /**
   * Changes the reconstruction: every object is uploaded again with its lighting table.
   * @param {Reconstruction} reconstruction
   */
  setReconstruction(reconstruction) {
    if (reconstruction === this.reconstruction) return;
    this.reconstruction = reconstruction;
    for (const o of this.objects) {
      if (o.uploaded) destroyUploaded(o.uploaded);
      o.uploaded = null;
      o.level = -1;
    }
  }

  /**
   * The level each object should be drawn at for `camera` (forced levels win; flat objects
   * get their tree depth), lowered while the scene is over the triangle budget.
   * @param {Camera} camera
   * @param {number} viewportHeight
   * @param {import('./view.js').LodParams} [lod]
   * @returns {number[]} -1 for objects that are not drawn
   */
  levelsFor(camera, viewportHeight, lod = DEFAULT_LOD) {
    // Adaptive counts are known once uploaded; levels are asked for after upload().
    const objects = this.objects.map((o) => ({ source: o.source, forced: o.forced, treeDepth: o.uploaded?.treeDepth ?? o.source.object.treeDepth, triangles: o.uploaded?.adaptive?.triangles ?? null }));
    return sceneLevels(objects, camera, viewportHeight, lod, this.triangleBudget);
  }

  /**
   * Refines every object whose level changed; resolves when the GPU is done, with each
   * refinement's wall time in `refineMs`.
   * @param {number[]} levels
   */
  async refineTo(levels) {
    this.upload();
    for (let i = 0; i < this.objects.length; i++) {
      const o = this.objects[i];
      if (levels[i] < 0 || o.uploaded === null || (levels[i] === o.level && o.refined !== null)) continue;
      const t0 = performance.now();
      o.refined = this.kernels.refine(o.uploaded, levels[i], o.refined);
      await this.kernels.device.queue.onSubmittedWorkDone();
      o.refineMs = performance.now() - t0;
      o.level = levels[i];
    }
  }

  /** Triangles drawn (every instance). */
  drawnTriangles() {
    return this.objects.reduce((s, o) => s + (o.refined ? o.refined.triangleCount * o.source.instances.length : 0), 0);
  }

  /** One draw per instance of every refined object. */
  draws() {
    return this.objects.flatMap((o) => (o.refined === null ? [] : o.source.instances.map((inst) => ({ refined: /** @type {import('./kernels.js').RefinedBuffers} */ (o.refined), transform: inst.transform }))));
  }

  /** Frees every buffer. */
  destroy() {
    for (const o of this.objects) {
      if (o.uploaded) destroyUploaded(o.uploaded);
      if (o.refined) destroyRefined(o.refined);
    }
  }
}

/**
 * Draws a scene's refined meshes with the runtime's render.wgsl into a linear float image,
 * then tone-maps it to a canvas (present.wgsl).
 */
export class Renderer {
  /**
   * @param {GPUDevice} device
   * @param {GPURenderPipeline} draw
   * @param {GPURenderPipeline} present
   * @param {GPUBindGroupLayout} presentLayout
   */
  constructor(device, draw, present, presentLayout) {
    this.device = device;
    this.draw = draw;
    this.present = present;
    this.presentLayout = presentLayout;
    /** @type {GPUTexture | null} */
    this.hdr = null;
    /** @type {GPUTexture | null} */
    this.depth = null;
    /** @type {GPUBuffer[]} */
    this.uniforms = [];
    /** @type {GPUTexture | undefined} */
    this.offscreen = undefined;
    this.presentUniform = device.createBuffer({ size: 16, usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST });
  }

  /**
   * @param {GPUDevice} device
   * @param {import('./wgsl.js').KernelSources} sources
   * @param {string} presentCode present.wgsl
   * @param {GPUTextureFormat} canvasFormat
   */
  static async create(device, sources, presentCode, canvasFormat) {
    const module = device.createShaderModule({ label: 'hce render', code: sources.render() });
    const draw = await device.createRenderPipelineAsync({
      label: 'hce render',
      layout: 'auto',
      vertex: {
        module,
        entryPoint: 'vs_main',
        buffers: [
          { arrayStride: 12, attributes: [{ shaderLocation: 0, offset: 0, format: 'float32x3' }] },
          { arrayStride: 16, attributes: [{ shaderLocation: 1, offset: 0, format: 'float32x4' }] },
        ],
      },
      // Baked assets may be open surfaces: both sides are drawn, as render.rs does.
      primitive: { topology: 'triangle-list', cullMode: 'none' },
      depthStencil: { format: 'depth32float', depthWriteEnabled: true, depthCompare: 'less' },
      fragment: { module, entryPoint: 'fs_main', targets: [{ format: 'rgba16float' }] },
    });
    const presentModule = device.createShaderModule({ label: 'hce present', code: presentCode });
    const presentLayout = device.createBindGroupLayout({
      entries: [
        { binding: 0, visibility: GPUShaderStage.FRAGMENT, texture: { sampleType: 'unfilterable-float' } },
        { binding: 1, visibility: GPUShaderStage.FRAGMENT, buffer: { type: 'uniform' } },
      ],
    });
    const present = await device.createRenderPipelineAsync({
      label: 'hce present',
      layout: device.createPipelineLayout({ bindGroupLayouts: [presentLayout] }),
      vertex: { module: presentModule, entryPoint: 'vs_present' },
      fragment: { module: presentModule, entryPoint: 'fs_present', targets: [{ format: canvasFormat }] },
    });
    return new Renderer(device, draw, present, presentLayout);
  }

  /**
   * Draws `scene` through `camera` into `target` (a canvas's current texture).
   * @param {HceScene} scene
   * @param {Camera} camera
   * @param {import('./math.js').Bounds} bounds the near and far planes are set around these
   * @param {GPUTexture} target
   * @param {number} exposureEv
   */
  render(scene, camera, bounds, target, exposureEv = 0) {
    const d = this.device;
    const { width, height } = target;
    if (this.hdr === null || this.hdr.width !== width || this.hdr.height !== height) {
      this.hdr?.destroy();
      this.depth?.destroy();
      this.hdr = d.createTexture({ size: [width, height], format: 'rgba16float', usage: GPUTextureUsage.RENDER_ATTACHMENT | GPUTextureUsage.TEXTURE_BINDING | GPUTextureUsage.COPY_SRC });
      this.depth = d.createTexture({ size: [width, height], format: 'depth32float', usage: GPUTextureUsage.RENDER_ATTACHMENT });
    }
    const viewProj = viewProjection(camera, bounds, width / height);
    const draws = scene.draws();
    while (this.uniforms.length < draws.length) this.uniforms.push(d.createBuffer({ size: 64, usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST }));
    const encoder = d.createCommandEncoder({ label: 'hce frame' });
    const pass = encoder.beginRenderPass({
      colorAttachments: [{ view: this.hdr.createView(), clearValue: [0, 0, 0, 1], loadOp: 'clear', storeOp: 'store' }],
      depthStencilAttachment: { view: /** @type {GPUTexture} */ (this.depth).createView(), depthClearValue: 1, depthLoadOp: 'clear', depthStoreOp: 'discard' },
    });
    pass.setPipeline(this.draw);
    draws.forEach((draw, i) => {
      d.queue.writeBuffer(this.uniforms[i], 0, new Float32Array(multiply(viewProj, draw.transform)));
      pass.setBindGroup(0, d.createBindGroup({ layout: this.draw.getBindGroupLayout(0), entries: [{ binding: 0, resource: { buffer: this.uniforms[i] } }] }));
      pass.setVertexBuffer(0, draw.refined.positions);
      pass.setVertexBuffer(1, draw.refined.colours);
      pass.setIndexBuffer(draw.refined.indices, 'uint32');
      pass.drawIndexed(3 * draw.refined.triangleCount);
    });
    pass.end();
    d.queue.writeBuffer(this.presentUniform, 0, new Float32Array([2 ** exposureEv, 0, 0, 0]));
    const present = encoder.beginRenderPass({ colorAttachments: [{ view: target.createView(), clearValue: [0, 0, 0, 1], loadOp: 'clear', storeOp: 'store' }] });
    present.setPipeline(this.present);
    present.setBindGroup(0, d.createBindGroup({ layout: this.presentLayout, entries: [{ binding: 0, resource: this.hdr.createView() }, { binding: 1, resource: { buffer: this.presentUniform } }] }));
    present.draw(3);
    present.end();
    d.queue.submit([encoder.finish()]);
  }

  /**
   * Draws `scene` as {@link Renderer.render} does into an offscreen `rgba8unorm` image and
   * reads it back (RGBA, rows top to bottom): for pages where WebGPU cannot present to a
   * canvas (headless Chromium on SwiftShader), and for screenshots. The renderer must have
   * been created for 'rgba8unorm'.
   * @param {HceScene} scene
   * @param {Camera} camera
   * @param {import('./math.js').Bounds} bounds
   * @param {number} width
   * @param {number} height
   * @param {number} exposureEv
   * @returns {Promise<Uint8ClampedArray<ArrayBuffer>>}
   */
  async renderToPixels(scene, camera, bounds, width, height, exposureEv = 0) {
    const d = this.device;
    if (this.offscreen === undefined || this.offscreen.width !== width || this.offscreen.height !== height) {
      this.offscreen?.destroy();
      this.offscreen = d.createTexture({ size: [width, height], format: 'rgba8unorm', usage: GPUTextureUsage.RENDER_ATTACHMENT | GPUTextureUsage.COPY_SRC });
    }
    this.render(scene, camera, bounds, this.offscreen, exposureEv);
    const row = Math.ceil((4 * width) / 256) * 256;
    const staging = d.createBuffer({ size: row * height, usage: GPUBufferUsage.MAP_READ | GPUBufferUsage.COPY_DST });
    const encoder = d.createCommandEncoder();
    encoder.copyTextureToBuffer({ texture: this.offscreen }, { buffer: staging, bytesPerRow: row }, [width, height]);
    d.queue.submit([encoder.finish()]);
    await staging.mapAsync(GPUMapMode.READ);
    const src = new Uint8Array(staging.getMappedRange());
    const out = new Uint8ClampedArray(new ArrayBuffer(4 * width * height));
    for (let y = 0; y < height; y++) out.set(src.subarray(y * row, y * row + 4 * width), 4 * width * y);
    staging.destroy();
    return out;
  }
}
