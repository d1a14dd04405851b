// A Babylon.js glTF loader extension for EXT_hce_baked_lighting (SPEC.md section 3): every
// primitive linked to a container object gets that object refined (Loop for multiresolution
// objects; flat ones from their trees, SPEC.md F.7.1) by the same Rust as `hce subdivide`, in hce.wasm on the CPU
// (cpu_refine.js), with the baked lighting as vertex colours drawn unlit. The CPU path serves
// Babylon's WebGL2 Engine and its WebGPUEngine alike; the runtime's WGSL kernels are not run
// on Babylon's device yet. Registered once, with options per load:
//
//   registerHceGLTFExtension();
//   await SceneLoader.AppendAsync('', url, scene, null, '.glb', {
//     gltf: { extensionOptions: { EXT_hce_baked_lighting: { level: 3 } } } });
//
// The colours are linear radiance: the extension sets no exposure or tone mapping (as the
// three.js plugin sets none); the page chooses them in the scene's imageProcessingConfiguration.
import { Geometry } from '@babylonjs/core/Meshes/geometry.js';
import { VertexBuffer } from '@babylonjs/core/Buffers/buffer.js';
import { PBRMaterial } from '@babylonjs/core/Materials/PBR/pbrMaterial.js';
import { Color3 } from '@babylonjs/core/Maths/math.color.js';
import { Logger } from '@babylonjs/core/Misc/logger.js';
import { ArrayItem } from '@babylonjs/loaders/glTF/2.0/glTFLoader.js';
import { registerGLTFExtension, unregisterGLTFExtension } from '@babylonjs/loaders/glTF/2.0/glTFLoaderExtensionRegistry.js';
import { coarseRangeIndices, loadAsset } from '../native.js';
import { CpuRefiner } from '../cpu_refine.js';

export const EXT = 'EXT_hce_baked_lighting';

/**
 * The options, given per load as `extensionOptions.EXT_hce_baked_lighting` of the glTF
 * loader's plugin options.
 * @typedef {object} ExtensionOptions
 * @property {number | ((object: import('../native.js').HceObject) => number)} [level] the Loop
 *   level of multiresolution objects (default 3, at most 6)
 * @property {import('../native.js').FlatRefinement} [flatRefinement] how flat objects are
 *   refined: 'adaptive' from their trees (default, SPEC.md F.7.1), or 'uniform' to their tree
 *   depth (at most 6, F.7.2)
 * @property {import('../native.js').Reconstruction} [reconstruction] default 'smooth'
 * @property {boolean} [unlit] give each refined mesh an unlit material showing the baked
 *   lighting (default true: the colours already hold the light); false keeps the file's
 *   material, which then multiplies its lighting by the vertex colours
 * @property {(extension: HceGLTFExtension) => void} [onLoaded] called when the load is ready,
 *   with the extension: its `report` (per object: level, vertices, triangles) and `warnings`
 */

/** @typedef {{ level: number, positions: Float32Array, normals: Float32Array, colours: Float32Array, indices: Uint32Array, triangleStart: Uint32Array }} Refined */

export class HceGLTFExtension {
  /** @param {any} loader Babylon's GLTFLoader (glTF 2.0) */
  constructor(loader) {
    this.name = EXT;
    this._loader = loader;
    this.enabled = loader.isExtensionUsed(EXT);
    /** @type {ExtensionOptions} */
    this.options = loader.parent.extensionOptions?.[EXT] ?? {};
    this._refiner = new CpuRefiner();
    /** The container's objects once read; null when the file holds no container. @type {import('../native.js').HceObject[] | null | undefined} */
    this._objects = undefined;
    /** @type {Map<number, Refined>} */
    this._refined = new Map();
    /** Meshes that got refined geometry, and those that keep their COLOR_0. @type {Set<any>} */
    this._refinedMeshes = new Set();
    /** @type {Set<any>} */
    this._fallbackMeshes = new Set();
    /** @type {Map<any, any>} */
    this._unlitMaterials = new Map();
    /** What the load did, per object: level, vertices, triangles, and where it refined. `level` is the triangles' numbering level, 0 for a flat object drawn from its trees (`adaptive`). @type {{ name: string, level: number, adaptive: boolean, vertices: number, triangles: number, path: 'cpu' }[]} */
    this.report = [];
    /** @type {string[]} */
    this.warnings = [];
  }

  dispose() {
    this._loader = null;
    this._refined.clear();
    this._refinedMeshes.clear();
    this._fallbackMeshes.clear();
    this._unlitMaterials.clear();
  }

  /** @param {string} message */
  _warn(message) {
    this.warnings.push(message);
    Logger.Warn(`${EXT}: ${message}`);
  }

  /**
   * Reads the container before the scene's meshes load (the container links them), then lets
   * the loader go on; a container hce refuses rejects the load with hce's message.
   * @param {string} context @param {any} scene
   */
  loadSceneAsync(context, scene) {
    if (this._objects !== undefined) return null;
    return (async () => {
      await this._readContainer();
      return this._loader.loadSceneAsync(context, scene);
    })();
  }

  /**
   * Loads the node's meshes after the container, for loads of named meshes, which skip the
   * scene.
   * @param {string} context @param {any} node @param {(n: any) => void} assign
   */
  loadNodeAsync(context, node, assign) {
    if (this._objects !== undefined) return null;
    return (async () => {
      await this._readContainer();
      return this._loader.loadNodeAsync(context, node, assign);
    })();
  }

  async _readContainer() {
    const root = this._loader.gltf.extensions?.[EXT];
    if (!root) {
      this._objects = null;
      return;
    }
    const context = `/extensions/${EXT}`;
    const view = ArrayItem.Get(`${context}/bufferView`, this._loader.gltf.bufferViews, root.bufferView);
    const data = await this._loader.loadBufferViewAsync(`/bufferViews/${view.index}`, view);
    try {
      // The container alone, read and checked by hce.wasm as `hce` reads a `.hce` file.
      const bytes = new Uint8Array(data.buffer, data.byteOffset, data.byteLength);
      this._objects = (await loadAsset(bytes, { name: 'container.hce' })).objects.map((o) => o.object);
    } catch (e) {
      throw new Error(`${context}: ${/** @type {Error} */ (e).message}`);
    }
  }

  /**
   * The refined surface of a linked primitive's coarse triangles, as the primitive's geometry;
   * null (the file's own vertex data) for a primitive that links nothing.
   * @param {string} context @param {any} primitive @param {any} babylonMesh
   */
  _loadVertexDataAsync(context, primitive, babylonMesh) {
    const link = primitive.extensions?.[EXT];
    if (!link) return null;
    if (this._objects === undefined) throw new Error(`${context}: the container was not read before the primitive`);
    const object = this._objects?.[link.object];
    if (!object) {
      this._warn(`${context}: ${this._objects === null ? 'the file has no container (no root extension)' : `object ${link.object} is not in the container (${this._objects.length} objects)`}; drawing its coarse bake (COLOR_0) unlit`);
      this._fallbackMeshes.add(babylonMesh);
      return null;
    }
    return (async () => {
      const r = this._refine(object);
      const accessors = this._loader.gltf.accessors;
      const coarse = ArrayItem.Get(`${context}/indices`, accessors, primitive.indices ?? primitive.attributes.POSITION).count / 3;
      const first = link.firstTriangle ?? 0;
      // The primitive's refined triangles: those of its coarse range (SPEC.md 2.3).
      const geometry = new Geometry(babylonMesh.name, this._loader.babylonScene);
      geometry.setVerticesData(VertexBuffer.PositionKind, r.positions, false, 3);
      geometry.setVerticesData(VertexBuffer.NormalKind, r.normals, false, 3);
      // Linear radiance, r, g, b, 1 per vertex.
      geometry.setVerticesData(VertexBuffer.ColorKind, r.colours, false, 4);
      geometry.setIndices(coarseRangeIndices(r.indices, r.triangleStart, first, coarse), r.positions.length / 3);
      babylonMesh.hasVertexAlpha = false;
      babylonMesh.metadata = { ...babylonMesh.metadata, hce: { object: object.name, level: r.level } };
      this._refinedMeshes.add(babylonMesh);
      return geometry;
    })();
  }

  /**
   * One refinement per object, shared by its primitives and instances.
   * @param {import('../native.js').HceObject} object @returns {Refined}
   */
  _refine(object) {
    let r = this._refined.get(object.index);
    if (!r) {
      const asked = typeof this.options.level === 'function' ? this.options.level(object) : this.options.level ?? 3;
      const flat = this.options.flatRefinement ?? 'adaptive';
      r = this._refiner.refine(object, asked, this.options.reconstruction ?? 'smooth', flat);
      this.report.push({ name: object.name, level: r.level, adaptive: object.kind === 'flat' && flat === 'adaptive', vertices: r.positions.length / 3, triangles: r.indices.length / 3, path: 'cpu' });
      this._refined.set(object.index, r);
    }
    return r;
  }

  /** Gives the refined meshes, and those drawing their coarse bake, the unlit material. */
  onReady() {
    if (this.options.unlit ?? true) {
      for (const mesh of this._refinedMeshes) mesh.material = this._unlit(mesh.material, false);
      // COLOR_0 is the light arriving, to be multiplied into the base colour (SPEC.md F.9).
      for (const mesh of this._fallbackMeshes) mesh.material = this._unlit(mesh.material, true);
    }
    this.options.onLoaded?.(this);
  }

  /**
   * An unlit material drawing the vertex colours (PBRMaterial.unlit, as the loader draws
   * KHR_materials_unlit), no light, no environment: times a white albedo for the refined
   * radiance, times the file's base colour for the COLOR_0 fallback.
   * @param {any} source the material the loader gave the mesh
   * @param {boolean} keepBase
   */
  _unlit(source, keepBase) {
    const key = `${source?.uniqueId ?? -1}/${keepBase}`;
    let m = this._unlitMaterials.get(key);
    if (!m) {
      m = new PBRMaterial(`${source?.name ?? ''} (hce baked lighting)`, this._loader.babylonScene);
      m.unlit = true;
      m.albedoColor = keepBase && source?.albedoColor ? source.albedoColor.clone() : Color3.White();
      if (keepBase && source?.albedoTexture) m.albedoTexture = source.albedoTexture;
      if (source) {
        m.sideOrientation = source.sideOrientation;
        m.backFaceCulling = source.backFaceCulling;
      }
      this._unlitMaterials.set(source, m);
    }
    return m;
  }
}

/**
 * Registers the extension with Babylon's glTF loader (once; again replaces the registration).
 * It is used for every file that lists EXT_hce_baked_lighting.
 */
export function registerHceGLTFExtension() {
  unregisterGLTFExtension(EXT);
  registerGLTFExtension(EXT, true, (loader) => new HceGLTFExtension(loader));
}
