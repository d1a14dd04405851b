// A three.js GLTFLoader plugin for EXT_hce_baked_lighting (SPEC.md section 3): every
// primitive linked to a container object gets that object refined (Loop for multiresolution
// objects; flat ones from their trees, SPEC.md F.7.1), with the baked lighting as vertex
// colours. On a
// WebGPURenderer with a WebGPU backend the hce runtime's kernels run on three.js's own device;
// on a WebGL2 backend (`forceWebGL: true`, or a browser without WebGPU) or a WebGLRenderer, the
// same Rust as `hce subdivide` refines on the CPU in hce.wasm (cpu_refine.js). Registered the
// usual way:
//
//   const runtime = await HceGLTFPlugin.runtime(renderer);
//   loader.register((parser) => new HceGLTFPlugin(parser, runtime, { level: 3 }));
//
// Nothing global: the plugin works on the parser it is given and the meshes it built.
// From three/webgpu, the build a WebGPURenderer app already imports (its core classes are the
// ones `three` exports too, so a WebGLRenderer app draws them as well).
import { BufferAttribute, BufferGeometry, MeshBasicMaterial, Vector3 } from 'three/webgpu';
import { coarseRangeIndices, loadAsset } from '../native.js';
import { kernelFiles, KernelSources } from '../wgsl.js';
import { Kernels, destroyRefined, destroyUploaded } from '../kernels.js';
import { flatLevel } from '../scene.js';
import { CpuRefiner } from '../cpu_refine.js';
import { chooseLevel, DEFAULT_LOD } from '../view.js';
import { maxScale, transformBounds } from '../math.js';
import { primitiveGeometry, vertexAttributes } from './gpu_geometry.js';

/**
 * The renderer each set of kernels from {@link HceGLTFPlugin.runtime} runs on, so that a plugin
 * given those kernels draws their output where it is.
 * @type {WeakMap<Kernels, any>}
 */
const RENDERERS = new WeakMap();

/**
 * An object drawn from the kernels' buffers: uploaded once, refined at `level`.
 * @typedef {object} GpuObject
 * @property {import('../native.js').HceObject} object
 * @property {import('../math.js').Bounds} bounds object space
 * @property {number} meanEdgeLength
 * @property {import('../kernels.js').UploadedObject} uploaded
 * @property {import('../kernels.js').RefinedBuffers | null} refined
 * @property {number} level
 * @property {Map<string, { first: number, coarse: number, geometry: any, meshes: any[] }>} primitives
 */

const EXT = 'EXT_hce_baked_lighting';

/**
 * @typedef {object} PluginOptions
 * @property {number | 'auto' | ((object: import('../native.js').HceObject) => number)} [level] the
 *   Loop level of multiresolution objects (default 3), or 'auto': chosen from the camera by
 *   `plugin.update(camera, height)` each frame (on WebGPU; elsewhere 'auto' is level 3)
 * @property {any} [renderer] the WebGPURenderer to draw into, when the kernels did not come
 *   from {@link HceGLTFPlugin.runtime}
 * @property {import('../native.js').FlatRefinement} [flatRefinement] how flat objects are
 *   refined: 'adaptive' from their trees (default, SPEC.md F.7.1), or 'uniform' to their tree
 *   depth (F.7.2)
 * @property {import('../kernels.js').Reconstruction} [reconstruction] default 'smooth'
 * @property {boolean} [unlit] replace each refined mesh's material by an unlit one showing the
 *   baked lighting (default true: the colours already hold the light)
 */

export class HceGLTFPlugin {
  /**
   * What refines for `renderer`, once per renderer: the kernels on three.js's device for a
   * WebGPURenderer on its WebGPU backend (after `await renderer.init()`), else the CPU.
   * @param {any} renderer a three.js WebGPURenderer (either backend) or WebGLRenderer
   * @param {{ wgslBase?: string | URL, progress?: (done: number, total: number, label: string) => void }} options
   *   `wgslBase`: the URL of the runtime's WGSL (runtime/src/gpu/), on WebGPU only; by default
   *   the kernel sources the npm package ships
   * @returns {Promise<Kernels | CpuRefiner>}
   */
  static async runtime(renderer, options = {}) {
    if (renderer?.isWebGLRenderer || renderer?.backend?.isWebGLBackend) return new CpuRefiner();
    if (!renderer?.isWebGPURenderer) throw new Error('HceGLTFPlugin.runtime needs a three.js WebGPURenderer or WebGLRenderer');
    const device = /** @type {GPUDevice | undefined} */ (renderer.backend?.device);
    if (!device) throw new Error('HceGLTFPlugin.runtime: the WebGPURenderer has no device yet; call it after `await renderer.init()`');
    const sources = new KernelSources(await kernelFiles(options.wgslBase));
    const kernels = await Kernels.create(device, sources, options.progress);
    RENDERERS.set(kernels, renderer);
    return kernels;
  }

  /**
   * @param {any} parser the GLTFLoader's parser
   * @param {Kernels | CpuRefiner} kernels from {@link HceGLTFPlugin.runtime}
   * @param {PluginOptions} [options]
   */
  constructor(parser, kernels, options = {}) {
    this.name = EXT;
    this.parser = parser;
    this.kernels = kernels;
    this.options = options;
    /** What the last load did, per object: level, vertices, triangles, and where it refined. `level` is the triangles' numbering level, 0 for a flat object drawn from its trees (`adaptive`). @type {{ name: string, level: number, adaptive: boolean, vertices: number, triangles: number, path: 'gpu' | 'cpu' }[]} */
    this.report = [];
    /** The objects drawn from the kernels' buffers, by container index. @type {Map<number, GpuObject>} */
    this.objects = new Map();
    /** The level-of-detail rule of `update` (lod.rs `LodParams::default`). */
    this.lod = DEFAULT_LOD;
  }

  /**
   * Replaces the geometry of every linked primitive by its refined, coloured surface.
   * @param {{ scene: any, scenes: any[] }} result
   */
  async afterRoot(result) {
    const json = this.parser.json;
    const root = json.extensions?.[EXT];
    if (!root) return;
    const view = await this.parser.getDependency('bufferView', root.bufferView);
    // The container alone, read and checked by hce.wasm as `hce` reads a `.hce` file.
    const assets = (await loadAsset(new Uint8Array(view), { name: 'container.hce' })).objects;
    const container = { objects: assets.map((o) => o.object) };
    /** @type {Map<string, { object: import('../native.js').HceObject, first: number }>} */
    const links = new Map();
    (json.meshes ?? []).forEach((/** @type {any} */ mesh, /** @type {number} */ m) => {
      (mesh.primitives ?? []).forEach((/** @type {any} */ prim, /** @type {number} */ p) => {
        const ext = prim.extensions?.[EXT];
        const object = ext && container.objects[ext.object];
        if (object) links.set(`${m}/${p}`, { object, first: ext.firstTriangle ?? 0 });
      });
    });
    /** @type {any[]} */
    const meshes = [];
    for (const scene of result.scenes) scene.traverse((/** @type {any} */ o) => { if (o.isMesh) meshes.push(o); });
    /** @type {{ mesh: any, key: string, link: { object: import('../native.js').HceObject, first: number }, coarse: number }[]} */
    const linked = [];
    for (const mesh of meshes) {
      const assoc = this.parser.associations.get(mesh);
      if (!assoc || assoc.meshes === undefined || assoc.primitives === undefined) continue;
      const key = `${assoc.meshes}/${assoc.primitives}`;
      const link = links.get(key);
      if (!link) continue;
      const prim = json.meshes[assoc.meshes].primitives[assoc.primitives];
      linked.push({ mesh, key, link, coarse: json.accessors[prim.indices ?? prim.attributes.POSITION].count / 3 });
    }
    const renderer = this.gpuRenderer();
    if (renderer !== null) this.attachGpu(renderer, linked, assets);
    else await this.attachRead(linked);
    for (const { mesh } of linked) {
      if (this.options.unlit ?? true) {
        mesh.material = new MeshBasicMaterial({ vertexColors: true, side: mesh.material?.side, name: `${mesh.material?.name ?? ''} (hce baked lighting)` });
      } else {
        mesh.material.vertexColors = true;
        // A flat object's triangles are planar and the kernel makes no normals for them.
        if (!mesh.geometry.attributes.normal) mesh.material.flatShading = true;
      }
    }
  }

  /**
   * The WebGPURenderer the kernels' output is drawn into where it is (`options.renderer`, or
   * the one {@link HceGLTFPlugin.runtime} made the kernels for); null on the CPU path.
   * @private
   */
  gpuRenderer() {
    return this.kernels instanceof Kernels ? (this.options.renderer ?? RENDERERS.get(this.kernels) ?? null) : null;
  }

  /** The level asked for `object` by a fixed `level` option. @param {import('../native.js').HceObject} object */
  askedLevel(object) {
    const l = this.options.level;
    return typeof l === 'function' ? l(object) : typeof l === 'number' ? l : 3;
  }

  /**
   * The kernels' output drawn where it is, on three.js's device: each object uploaded once and
   * refined into buffers three.js draws (gpu_geometry.js), again whenever `update` picks it
   * another level.
   * @private
   * @param {any} renderer
   * @param {{ mesh: any, key: string, link: { object: import('../native.js').HceObject, first: number }, coarse: number }[]} linked
   * @param {import('../native.js').AssetObject[]} assets the container's objects, with their bounds
   */
  attachGpu(renderer, linked, assets) {
    const kernels = /** @type {Kernels} */ (this.kernels);
    const flat = this.options.flatRefinement ?? 'adaptive';
    for (const { mesh, key, link, coarse } of linked) {
      let o = this.objects.get(link.object.index);
      if (!o) {
        const source = /** @type {import('../native.js').AssetObject} */ (assets.find((a) => a.object.index === link.object.index));
        o = { object: link.object, bounds: source.bounds, meanEdgeLength: source.meanEdgeLength, uploaded: kernels.upload(link.object, this.options.reconstruction ?? 'smooth', flat), refined: null, level: -1, primitives: new Map() };
        this.objects.set(link.object.index, o);
      }
      let p = o.primitives.get(key);
      if (!p) {
        p = { first: link.first, coarse, geometry: null, meshes: [] };
        o.primitives.set(key, p);
      }
      p.meshes.push(mesh);
      mesh.geometry.dispose();
    }
    for (const o of this.objects.values()) {
      const object = o.object;
      // A fixed level, or under 'auto' the coarsest until `update` sees the camera.
      const level = object.kind === 'flat' ? flatLevel(object.treeDepth, object.records.length / 4) : this.options.level === 'auto' ? this.lod.minLevel : this.askedLevel(object);
      this.refineGpu(renderer, o, level);
    }
  }

  /**
   * Refines `o` to `level` on the GPU and gives its primitives' meshes the new geometry.
   * @private
   * @param {any} renderer
   * @param {GpuObject} o
   * @param {number} level
   */
  refineGpu(renderer, o, level) {
    const kernels = /** @type {Kernels} */ (this.kernels);
    o.refined = kernels.refine(o.uploaded, level, o.refined);
    const refined = o.refined;
    const encoder = kernels.device.createCommandEncoder({ label: 'hce refined mesh into three.js' });
    const shared = vertexAttributes(renderer, encoder, refined);
    const starts = refined.triangleStart;
    const at = (/** @type {number} */ t) => starts[Math.min(t, starts.length - 1)];
    for (const p of o.primitives.values()) {
      // The primitive's refined triangles: those of its coarse range (SPEC.md 2.3).
      const geometry = primitiveGeometry(renderer, encoder, refined, shared, at(p.first), at(p.first + p.coarse), o.bounds);
      geometry.userData.hce = { object: o.object.name, level: refined.level };
      for (const mesh of p.meshes) mesh.geometry = geometry;
      // The previous level's buffers go once nothing draws them: three.js destroys them, and
      // WebGPU keeps a destroyed buffer for the work already submitted.
      p.geometry?.dispose();
      p.geometry = geometry;
    }
    kernels.device.queue.submit([encoder.finish()]);
    o.level = level;
    const entry = { name: o.object.name, level: refined.level, adaptive: o.uploaded.adaptive !== null, vertices: refined.vertexCount, triangles: refined.triangleCount, path: /** @type {'gpu'} */ ('gpu') };
    const i = this.report.findIndex((r) => r.name === entry.name);
    if (i >= 0) this.report[i] = entry;
    else this.report.push(entry);
  }

  /**
   * Chooses each object's level for `camera` by the rule of `gpu::choose_level` (its coarse
   * edges about 8 pixels long on a viewport `viewportHeight` pixels high, levels 0 to 5, the
   * largest over the meshes that draw it) and refines, on the GPU, those whose level changed;
   * the meshes draw the new level from the next frame. Call it before rendering a frame, with
   * `level: 'auto'` on a WebGPU backend (it does nothing otherwise). Returns how many objects
   * it refined. Flat objects keep their refinement, which does not depend on the view.
   * @param {any} camera a three.js PerspectiveCamera
   * @param {number} viewportHeight in pixels
   */
  update(camera, viewportHeight) {
    const renderer = this.gpuRenderer();
    if (this.options.level !== 'auto' || renderer === null) return 0;
    camera.updateMatrixWorld();
    const eye = camera.getWorldPosition(new Vector3());
    const ahead = eye.clone().add(camera.getWorldDirection(new Vector3()));
    const view = { eye: eye.toArray(), target: ahead.toArray(), fovYDegrees: camera.fov ?? 50 };
    let changed = 0;
    for (const o of this.objects.values()) {
      if (o.object.kind === 'flat') continue;
      let level = -1;
      for (const p of o.primitives.values()) {
        for (const mesh of p.meshes) {
          mesh.updateWorldMatrix(true, false);
          const m = mesh.matrixWorld.elements;
          level = Math.max(level, chooseLevel(transformBounds(o.bounds, m), o.meanEdgeLength * maxScale(m), view, viewportHeight, this.lod));
        }
      }
      if (level >= 0 && level !== o.level) {
        this.refineGpu(renderer, o, level);
        changed += 1;
      }
    }
    return changed;
  }

  /**
   * Every object refined once and read back (the CPU path, or the kernels without a renderer
   * to draw into), as three.js `BufferAttribute`s.
   * @private
   * @param {{ mesh: any, key: string, link: { object: import('../native.js').HceObject, first: number }, coarse: number }[]} linked
   */
  async attachRead(linked) {
    // One refinement per object, shared by its primitives and instances.
    /** @type {Map<number, Promise<{ level: number, positions: Float32Array, normals: Float32Array | null, colours: Float32Array, indices: Uint32Array, triangleStart: Uint32Array }>>} */
    const refined = new Map();
    const refine = (/** @type {import('../native.js').HceObject} */ object) => {
      let p = refined.get(object.index);
      if (!p) {
        p = (async () => {
          const kernels = this.kernels;
          const reconstruction = this.options.reconstruction ?? 'smooth';
          const asked = this.askedLevel(object);
          const flat = this.options.flatRefinement ?? 'adaptive';
          let mesh;
          if (kernels instanceof CpuRefiner) {
            mesh = kernels.refine(object, asked, reconstruction, flat);
          } else {
            const level = object.kind === 'flat' ? flatLevel(object.treeDepth, object.records.length / 4) : asked;
            const uploaded = kernels.upload(object, reconstruction, flat);
            const buffers = kernels.refine(uploaded, level);
            mesh = await kernels.readBack(buffers);
            destroyRefined(buffers);
            destroyUploaded(uploaded);
          }
          this.report.push({ name: object.name, level: mesh.level, adaptive: object.kind === 'flat' && flat === 'adaptive', vertices: mesh.positions.length / 3, triangles: mesh.indices.length / 3, path: kernels instanceof CpuRefiner ? 'cpu' : 'gpu' });
          return mesh;
        })();
        refined.set(object.index, p);
      }
      return p;
    };
    /** @type {Map<string, BufferGeometry>} */
    const geometries = new Map();
    for (const { mesh, key, link, coarse } of linked) {
      let geometry = geometries.get(key);
      if (!geometry) {
        const r = await refine(link.object);
        // The primitive's refined triangles: those of its coarse range (SPEC.md 2.3).
        const indices = coarseRangeIndices(r.indices, r.triangleStart, link.first, coarse);
        geometry = new BufferGeometry();
        geometry.setAttribute('position', new BufferAttribute(r.positions, 3));
        if (r.normals) geometry.setAttribute('normal', new BufferAttribute(r.normals, 3));
        else geometry.computeVertexNormals();
        // Linear radiance, r, g, b, 1 per vertex.
        geometry.setAttribute('color', new BufferAttribute(r.colours, 4));
        geometry.setIndex(new BufferAttribute(indices, 1));
        geometry.userData.hce = { object: link.object.name, level: r.level };
        geometries.set(key, geometry);
      }
      mesh.geometry.dispose();
      mesh.geometry = geometry;
    }
  }
}
