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
import { BufferAttribute, BufferGeometry, MeshBasicMaterial } from 'three/webgpu';
import { coarseRangeIndices, loadAsset } from '../native.js';
import { kernelFiles, KernelSources } from '../wgsl.js';
import { Kernels, destroyRefined, destroyUploaded } from '../kernels.js';
import { flatLevel } from '../scene.js';
import { CpuRefiner } from '../cpu_refine.js';

const EXT = 'EXT_hce_baked_lighting';

/**
 * @typedef {object} PluginOptions
 * @property {number | ((object: import('../native.js').HceObject) => number)} [level] the Loop
 *   level of multiresolution objects (default 3)
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
    return Kernels.create(device, sources, options.progress);
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
    const container = { objects: (await loadAsset(new Uint8Array(view), { name: 'container.hce' })).objects.map((o) => o.object) };
    /** @type {Map<string, { object: import('../native.js').HceObject, first: number }>} */
    const links = new Map();
    (json.meshes ?? []).forEach((/** @type {any} */ mesh, /** @type {number} */ m) => {
      (mesh.primitives ?? []).forEach((/** @type {any} */ prim, /** @type {number} */ p) => {
        const ext = prim.extensions?.[EXT];
        const object = ext && container.objects[ext.object];
        if (object) links.set(`${m}/${p}`, { object, first: ext.firstTriangle ?? 0 });
      });
    });
    // One refinement per object, shared by its primitives and instances.
    /** @type {Map<number, Promise<{ level: number, positions: Float32Array, normals: Float32Array | null, colours: Float32Array, indices: Uint32Array, triangleStart: Uint32Array }>>} */
    const refined = new Map();
    const refine = (/** @type {import('../native.js').HceObject} */ object) => {
      let p = refined.get(object.index);
      if (!p) {
        p = (async () => {
          const kernels = this.kernels;
          const reconstruction = this.options.reconstruction ?? 'smooth';
          const asked = typeof this.options.level === 'function' ? this.options.level(object) : this.options.level ?? 3;
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
    /** @type {any[]} */
    const meshes = [];
    for (const scene of result.scenes) scene.traverse((/** @type {any} */ o) => { if (o.isMesh) meshes.push(o); });
    for (const mesh of meshes) {
      const assoc = this.parser.associations.get(mesh);
      if (!assoc || assoc.meshes === undefined || assoc.primitives === undefined) continue;
      const key = `${assoc.meshes}/${assoc.primitives}`;
      const link = links.get(key);
      if (!link) continue;
      let geometry = geometries.get(key);
      if (!geometry) {
        const r = await refine(link.object);
        const prim = json.meshes[assoc.meshes].primitives[assoc.primitives];
        const coarse = json.accessors[prim.indices ?? prim.attributes.POSITION].count / 3;
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
      if (this.options.unlit ?? true) {
        mesh.material = new MeshBasicMaterial({ vertexColors: true, side: mesh.material?.side, name: `${mesh.material?.name ?? ''} (hce baked lighting)` });
      } else {
        mesh.material.vertexColors = true;
      }
    }
  }
}
