// Loading a baked asset: a `.hce` container, or a glTF/GLB with the EXT_hce_baked_lighting
// extension (SPEC.md section 3), into checked container objects with their instances (node
// world transforms, walked as meshio/src/scene_graph.rs walks them), bounds and the scene's
// camera. Every failure is an HceError naming the JSON location or byte at fault.
import { HceError } from './errors.js';
import { geometryHash, readContainer } from './container.js';
import { fromTrs, identity, multiply, normalize, sub, scale, dot, transformPoint, transformVector } from './math.js';

const EXT = 'EXT_hce_baked_lighting';
const GLB_MAGIC = 0x46546c67;
const CHUNK_JSON = 0x4e4f534a;
const CHUNK_BIN = 0x004e4942;

/**
 * @typedef {import('./container.js').HceObject} HceObject
 * @typedef {import('./math.js').Mat4} Mat4
 * @typedef {import('./math.js').Bounds} Bounds
 * @typedef {{ node: number | null, name: string, transform: Mat4 }} Instance
 * @typedef {{ object: HceObject, instances: Instance[], bounds: Bounds, meanEdgeLength: number }} AssetObject
 * @typedef {{ name: string, eye: number[], forward: number[], up: number[], fovYDegrees: number, aspectRatio: number | null }} SceneCamera
 * @typedef {{ format: 'hce' | 'glb' | 'gltf', objects: AssetObject[], camera: SceneCamera | null, warnings: string[], generator: string }} Asset
 */

/**
 * @typedef {object} LoadOptions
 * @property {boolean} [strict] reject the asset on a bad primitive link or a stale geometry hash
 *   (default true); false ignores such primitives with a warning (SPEC.md 3.5)
 * @property {(uri: string) => Promise<Uint8Array>} [resolveUri] external buffers of a .gltf
 */

/**
 * Loads a baked asset from its bytes, whichever of the three formats it is.
 * @param {Uint8Array} bytes
 * @param {LoadOptions} [options]
 * @returns {Promise<Asset>}
 */
export async function loadAsset(bytes, options = {}) {
  if (bytes.length >= 4 && bytes[0] === 0x89 && bytes[1] === 0x48 && bytes[2] === 0x43 && bytes[3] === 0x45) return loadHce(bytes);
  // A high-bit-stripped or converted container still says HCE: let the reader explain.
  if (bytes.length >= 4 && bytes[1] === 0x48 && bytes[2] === 0x43 && bytes[3] === 0x45) return loadHce(bytes);
  const dv = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  if (bytes.length >= 12 && dv.getUint32(0, true) === GLB_MAGIC) return loadGlb(bytes, options);
  let text;
  try {
    text = new TextDecoder('utf-8', { fatal: true }).decode(bytes);
  } catch {
    throw new HceError('file', 'neither an .hce container, a GLB nor glTF JSON');
  }
  let json;
  try {
    json = JSON.parse(text);
  } catch (e) {
    throw new HceError('file', `neither an .hce container, a GLB nor glTF JSON (${/** @type {Error} */ (e).message})`);
  }
  const buffers = await gltfBuffers(json, null, options);
  return loadGltf(json, buffers, 'gltf', options);
}

/** @param {Uint8Array} bytes @returns {Asset} */
function loadHce(bytes) {
  const c = readContainer(bytes);
  const objects = c.objects.map((object) => finish(object, [{ node: null, name: object.name, transform: identity() }]));
  return { format: 'hce', objects, camera: null, warnings: [], generator: c.metadata.generator };
}

/**
 * Bounds and mean edge length of an object, after checking its geometry hash.
 * @param {HceObject} object
 * @param {Instance[]} instances
 * @returns {AssetObject}
 */
function finish(object, instances) {
  const p = object.mesh.positions;
  const t = object.mesh.triangles;
  const min = /** @type {[number, number, number]} */ ([Infinity, Infinity, Infinity]);
  const max = /** @type {[number, number, number]} */ ([-Infinity, -Infinity, -Infinity]);
  for (let i = 0; i < p.length; i += 3) {
    for (let k = 0; k < 3; k++) {
      min[k] = Math.min(min[k], p[i + k]);
      max[k] = Math.max(max[k], p[i + k]);
    }
  }
  let sum = 0;
  for (let f = 0; f < t.length; f += 3) {
    for (let e = 0; e < 3; e++) {
      const a = t[f + e];
      const b = t[f + ((e + 1) % 3)];
      sum += Math.fround(Math.hypot(p[3 * a] - p[3 * b], p[3 * a + 1] - p[3 * b + 1], p[3 * a + 2] - p[3 * b + 2]));
    }
  }
  const bounds = p.length === 0 ? { min: /** @type {[number, number, number]} */ ([0, 0, 0]), max: /** @type {[number, number, number]} */ ([0, 0, 0]) } : { min, max };
  return { object, instances, bounds, meanEdgeLength: sum / Math.max(t.length, 1) };
}

/**
 * @param {Uint8Array} bytes
 * @param {LoadOptions} options
 */
async function loadGlb(bytes, options) {
  const dv = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  const version = dv.getUint32(4, true);
  if (version !== 2) throw new HceError('glb', `GLB version ${version}; only glTF 2.0 is read`);
  const length = dv.getUint32(8, true);
  if (length > bytes.length) throw new HceError('glb', `the header says ${length} bytes but ${bytes.length} are present: the file is truncated`);
  let at = 12;
  let json = null;
  /** @type {Uint8Array | null} */
  let bin = null;
  while (at + 8 <= length) {
    const chunkLength = dv.getUint32(at, true);
    const type = dv.getUint32(at + 4, true);
    if (at + 8 + chunkLength > length) throw new HceError(`glb[${at}]`, 'a chunk runs past the end of the file');
    const data = bytes.subarray(at + 8, at + 8 + chunkLength);
    if (type === CHUNK_JSON && json === null) {
      try {
        json = JSON.parse(new TextDecoder('utf-8', { fatal: true }).decode(data));
      } catch (e) {
        throw new HceError('glb.json', `the JSON chunk does not parse: ${/** @type {Error} */ (e).message}`);
      }
    } else if (type === CHUNK_BIN && bin === null) {
      bin = data;
    }
    at += 8 + Math.ceil(chunkLength / 4) * 4;
  }
  if (json === null) throw new HceError('glb', 'no JSON chunk');
  const buffers = await gltfBuffers(json, bin, options);
  return loadGltf(json, buffers, 'glb', options);
}

/**
 * The bytes of every buffer of `json`: the GLB's binary chunk, data URIs, or `resolveUri`.
 * @param {any} json
 * @param {Uint8Array | null} bin
 * @param {LoadOptions} options
 * @returns {Promise<Uint8Array[]>}
 */
async function gltfBuffers(json, bin, options) {
  const list = Array.isArray(json?.buffers) ? json.buffers : [];
  return Promise.all(list.map(async (/** @type {any} */ b, /** @type {number} */ i) => {
    const at = `buffers[${i}]`;
    let data;
    if (b?.uri === undefined) {
      if (bin === null || i !== 0) throw new HceError(at, 'has no uri and is not the GLB binary chunk');
      data = bin;
    } else if (typeof b.uri !== 'string') {
      throw new HceError(`${at}.uri`, 'is not a string');
    } else if (b.uri.startsWith('data:')) {
      const comma = b.uri.indexOf(',');
      if (comma < 0 || !b.uri.slice(0, comma).endsWith(';base64')) throw new HceError(`${at}.uri`, 'only base64 data URIs are read');
      const raw = atob(b.uri.slice(comma + 1));
      data = Uint8Array.from(raw, (c) => c.charCodeAt(0));
    } else if (options.resolveUri) {
      try {
        data = await options.resolveUri(b.uri);
      } catch (e) {
        throw new HceError(`${at}.uri`, `cannot load '${b.uri}': ${/** @type {Error} */ (e).message}`);
      }
    } else {
      throw new HceError(`${at}.uri`, `the external buffer '${b.uri}' cannot be loaded here; open the .glb, or the .gltf by URL`);
    }
    if (typeof b.byteLength !== 'number' || data.length < b.byteLength) throw new HceError(at, `byteLength ${b.byteLength} but ${data.length} bytes are present`);
    return data;
  }));
}

/** @param {unknown} x */
const isIndex = (x) => typeof x === 'number' && Number.isInteger(x) && x >= 0;

/**
 * The bytes of buffer view `i`, checked to lie inside its buffer.
 * @param {any} json @param {Uint8Array[]} buffers @param {number} i
 */
function bufferView(json, buffers, i) {
  const at = `bufferViews[${i}]`;
  const v = json.bufferViews?.[i];
  if (!v || !isIndex(v.buffer) || v.buffer >= buffers.length) throw new HceError(at, 'does not exist or names no buffer');
  const offset = v.byteOffset ?? 0;
  if (!isIndex(offset) || !isIndex(v.byteLength) || offset + v.byteLength > buffers[v.buffer].length) throw new HceError(at, 'lies outside its buffer');
  return { view: v, bytes: buffers[v.buffer].subarray(offset, offset + v.byteLength) };
}

/**
 * Reads accessor `i` as numbers (POSITION: float VEC3; indices: unsigned SCALAR).
 * @param {any} json @param {Uint8Array[]} buffers @param {number} i @param {'VEC3' | 'SCALAR'} type
 * @returns {ArrayLike<number>}
 */
function accessor(json, buffers, i, type) {
  const at = `accessors[${i}]`;
  const a = json.accessors?.[i];
  if (!a || a.type !== type || !isIndex(a.count) || !isIndex(a.bufferView)) throw new HceError(at, `is not a ${type} accessor with a buffer view`);
  const { view, bytes } = bufferView(json, buffers, a.bufferView);
  const sizes = /** @type {Record<number, number>} */ ({ 5121: 1, 5123: 2, 5125: 4, 5126: 4 });
  const size = sizes[a.componentType];
  if (!size || (type === 'VEC3') !== (a.componentType === 5126)) throw new HceError(at, `component type ${a.componentType} is not read here`);
  const comps = type === 'VEC3' ? 3 : 1;
  const stride = view.byteStride ?? size * comps;
  const offset = a.byteOffset ?? 0;
  if (a.count > 0 && offset + stride * (a.count - 1) + size * comps > bytes.length) throw new HceError(at, 'runs past its buffer view');
  const dv = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  const out = type === 'VEC3' ? new Float32Array(3 * a.count) : new Uint32Array(a.count);
  for (let k = 0; k < a.count; k++) {
    for (let c = 0; c < comps; c++) {
      const p = offset + stride * k + size * c;
      out[comps * k + c] = size === 1 ? dv.getUint8(p) : size === 2 ? dv.getUint16(p, true) : a.componentType === 5126 ? dv.getFloat32(p, true) : dv.getUint32(p, true);
    }
  }
  return out;
}

/**
 * @param {any} json
 * @param {Uint8Array[]} buffers
 * @param {'glb' | 'gltf'} format
 * @param {LoadOptions} options
 * @returns {Asset}
 */
function loadGltf(json, buffers, format, options) {
  const strict = options.strict ?? true;
  /** @type {string[]} */
  const warnings = [];
  const root = json?.extensions?.[EXT];
  if (root === undefined) throw new HceError('extensions', `no ${EXT}: this glTF has no baked lighting; bake it with \`hce bake\``);
  // Rules 12 and 13 (SPEC.md Appendix C).
  if (!Array.isArray(json.extensionsUsed) || !json.extensionsUsed.includes(EXT)) throw new HceError('extensionsUsed', `does not list ${EXT}; an asset that uses it MUST list it (SPEC.md 3.2)`);
  if (Array.isArray(json.extensionsRequired) && json.extensionsRequired.includes(EXT)) throw new HceError('extensionsRequired', `lists ${EXT}; it MUST NOT be required (SPEC.md 3.2)`);
  if (typeof root !== 'object' || root === null || !isIndex(root.bufferView)) throw new HceError(`extensions.${EXT}.bufferView`, 'must be a buffer view index (SPEC.md 3.3)');
  if (root.version !== undefined && (typeof root.version !== 'string' || !/^[0-9]+\.[0-9]+$/.test(root.version))) {
    throw new HceError(`extensions.${EXT}.version`, `${JSON.stringify(root.version)} does not match "major.minor" (SPEC.md 3.3)`);
  }
  const { view, bytes } = bufferView(json, buffers, root.bufferView);
  if (view.byteStride !== undefined || view.target !== undefined) throw new HceError(`bufferViews[${root.bufferView}]`, "the container's buffer view MUST NOT have byteStride or target (SPEC.md 3.3)");
  if ((view.byteOffset ?? 0) % 4 !== 0) throw new HceError(`bufferViews[${root.bufferView}].byteOffset`, 'must be a multiple of 4 (SPEC.md 3.3)');
  const container = readContainer(bytes);

  // Rules 14 and 15: every primitive link.
  const meshes = Array.isArray(json.meshes) ? json.meshes : [];
  /** @type {Map<number, number[]>} objects of each mesh, in first-primitive order */
  const meshObjects = new Map();
  /** @type {Map<number, { mesh: number, ranges: [number, number][] }>} */
  const objectUse = new Map();
  meshes.forEach((/** @type {any} */ mesh, /** @type {number} */ m) => {
    (Array.isArray(mesh?.primitives) ? mesh.primitives : []).forEach((/** @type {any} */ prim, /** @type {number} */ p) => {
      const ext = prim?.extensions?.[EXT];
      if (ext === undefined) return;
      const at = `meshes[${m}].primitives[${p}]`;
      const schema = `${at}.extensions.${EXT}`;
      if (typeof ext !== 'object' || ext === null) throw new HceError(schema, 'is not an object (SPEC.md 3.3)');
      if (!isIndex(ext.object)) throw new HceError(`${schema}.object`, 'must be an integer >= 0 (SPEC.md 3.3)');
      if (ext.firstTriangle !== undefined && !isIndex(ext.firstTriangle)) throw new HceError(`${schema}.firstTriangle`, 'must be an integer >= 0 (SPEC.md 3.3)');
      if (typeof ext.geometryHash !== 'string' || !/^[0-9a-f]{16}$/.test(ext.geometryHash)) {
        throw new HceError(`${schema}.geometryHash`, `must be 16 lowercase hexadecimal digits, found ${JSON.stringify(ext.geometryHash)} (SPEC.md 3.3)`);
      }
      const bad = (/** @type {string} */ message) => {
        if (strict) throw new HceError(at, message);
        warnings.push(`${at}: ${message}; the primitive is ignored (SPEC.md 3.5)`);
      };
      const object = container.objects[ext.object];
      if (!object) return bad(`object ${ext.object} is out of range; the container has ${container.objects.length} objects (SPEC.md 3.5)`);
      if ((prim.mode ?? 4) !== 4) return bad(`mode ${prim.mode} is not triangles (SPEC.md 3.3)`);
      let triangles;
      let hash;
      try {
        const positions = /** @type {Float32Array} */ (accessor(json, buffers, prim.attributes?.POSITION, 'VEC3'));
        const indices = prim.indices === undefined ? Uint32Array.from({ length: positions.length / 3 }, (_, i) => i) : accessor(json, buffers, prim.indices, 'SCALAR');
        for (let i = 0; i < indices.length; i++) if (indices[i] >= positions.length / 3) throw new Error(`index ${indices[i]} is out of range`);
        triangles = Math.floor(indices.length / 3);
        hash = geometryHash(positions, indices);
      } catch (e) {
        return bad(`cannot read its geometry: ${/** @type {Error} */ (e).message}`);
      }
      const first = ext.firstTriangle ?? 0;
      const F = object.records.length / 4;
      if (first + triangles > F) return bad(`triangles ${first}..${first + triangles} exceed object ${ext.object} '${object.name}' with ${F} triangles (SPEC.md 3.5)`);
      if (hash !== ext.geometryHash) return bad(`geometry hash ${hash} differs from the baked ${ext.geometryHash}: the mesh was edited after baking (SPEC.md 3.5)`);
      if (first === 0 && triangles === F && hash !== object.geometryHash) return bad(`geometry hash ${hash} differs from object ${ext.object}'s ${object.geometryHash} (SPEC.md 3.3)`);
      const use = objectUse.get(ext.object) ?? { mesh: m, ranges: [] };
      if (use.mesh !== m) return bad(`object ${ext.object} is linked from meshes ${use.mesh} and ${m}; one object belongs to one mesh (SPEC.md 3.3)`);
      if (use.ranges.some(([a, b]) => first < b && a < first + triangles)) return bad(`its triangle range overlaps another primitive's of object ${ext.object} (SPEC.md 3.3)`);
      use.ranges.push([first, first + triangles]);
      objectUse.set(ext.object, use);
      const list = meshObjects.get(m) ?? [];
      if (!list.includes(ext.object)) list.push(ext.object);
      meshObjects.set(m, list);
    });
  });

  // The scene walk (scene_graph.rs): the scene is `scene`, else the first of `scenes`, else
  // every node that is no node's child; depth first, a node before its children.
  const nodes = Array.isArray(json.nodes) ? json.nodes : [];
  /** @type {number[]} */
  let roots;
  if (Array.isArray(json.scenes) && json.scenes.length > 0) {
    const s = json.scene ?? 0;
    if (!isIndex(s) || s >= json.scenes.length) throw new HceError('scene', `${s} is not a scene index`);
    roots = json.scenes[s]?.nodes ?? [];
  } else {
    const children = new Set(nodes.flatMap((/** @type {any} */ n) => (Array.isArray(n?.children) ? n.children : [])));
    roots = nodes.map((/** @type {any} */ _, /** @type {number} */ i) => i).filter((/** @type {number} */ i) => !children.has(i));
  }
  /** @type {Instance[][]} */
  const instances = container.objects.map(() => []);
  /** @type {SceneCamera | null} */
  let camera = null;
  const seen = new Set();
  /** @param {number} i @param {Mat4} parent */
  const visit = (i, parent) => {
    const at = `nodes[${i}]`;
    if (!isIndex(i) || i >= nodes.length) throw new HceError(at, 'is not a node index');
    if (seen.has(i)) {
      warnings.push(`${at} is reached a second time; it is not followed again`);
      return;
    }
    seen.add(i);
    const n = nodes[i];
    let local;
    if (n.matrix !== undefined) {
      if (!Array.isArray(n.matrix) || n.matrix.length !== 16 || !n.matrix.every(Number.isFinite)) throw new HceError(`${at}.matrix`, 'must be 16 finite numbers');
      local = n.matrix.map(Math.fround);
    } else {
      const t = n.translation ?? [0, 0, 0];
      const r = n.rotation ?? [0, 0, 0, 1];
      const s = n.scale ?? [1, 1, 1];
      for (const [name, v, len] of /** @type {[string, any, number][]} */ ([['translation', t, 3], ['rotation', r, 4], ['scale', s, 3]])) {
        if (!Array.isArray(v) || v.length !== len || !v.every(Number.isFinite)) throw new HceError(`${at}.${name}`, `must be ${len} finite numbers`);
      }
      if (Math.hypot(...r) < 1e-6) throw new HceError(`${at}.rotation`, 'has (nearly) zero length');
      local = fromTrs(t.map(Math.fround), r.map(Math.fround), s.map(Math.fround));
    }
    const world = multiply(parent, local);
    const name = typeof n.name === 'string' ? n.name : at;
    if (n.mesh !== undefined) {
      if (!isIndex(n.mesh) || n.mesh >= meshes.length) throw new HceError(`${at}.mesh`, 'is not a mesh index');
      for (const o of meshObjects.get(n.mesh) ?? []) instances[o].push({ node: i, name, transform: world });
    }
    if (camera === null && n.camera !== undefined) camera = sceneCamera(json, i, name, world, warnings);
    for (const c of Array.isArray(n.children) ? n.children : []) visit(c, world);
  };
  for (const r of roots) visit(r, identity());
  const objects = container.objects.map((object, i) => {
    if (instances[i].length === 0) warnings.push(`objects[${i}] '${object.name}' is used by no node of the scene; it is not drawn`);
    const o = finish(object, instances[i]);
    if (o.object.geometryHash !== geometryHash(object.mesh.positions, object.mesh.triangles)) {
      throw new HceError(`objects[${i}].geometry_hash`, `the stored hash does not match the control triangles: the file was edited after baking (SPEC.md C rule 11)`);
    }
    return o;
  });
  return { format, objects, camera, warnings, generator: container.metadata.generator };
}

/**
 * The perspective camera of node `i` (asset.rs `camera`): the node looks along its local −Z
 * with +Y up.
 * @param {any} json @param {number} i @param {string} name @param {Mat4} world @param {string[]} warnings
 * @returns {SceneCamera | null}
 */
function sceneCamera(json, i, name, world, warnings) {
  const at = `nodes[${i}].camera`;
  const c = json.cameras?.[json.nodes[i].camera];
  if (!c) throw new HceError(at, 'does not name a camera of `cameras`');
  if (c.type !== 'perspective') {
    warnings.push(`${at}: only perspective cameras are used; this one is ignored`);
    return null;
  }
  const yfov = c.perspective?.yfov;
  if (typeof yfov !== 'number' || !(yfov > 0 && yfov < Math.PI)) throw new HceError(at, 'perspective.yfov must be in (0, π) radians');
  const aspect = c.perspective?.aspectRatio;
  const eye = transformPoint(world, [0, 0, 0]);
  const forward = normalize(transformVector(world, [0, 0, -1]));
  const upRaw = transformVector(world, [0, 1, 0]);
  const up = normalize(sub(upRaw, scale(forward, dot(upRaw, forward))));
  if (dot(forward, forward) === 0 || dot(up, up) === 0 || !eye.every(Number.isFinite)) {
    warnings.push(`${at}: the node's transform collapses the camera's axes; it is ignored`);
    return null;
  }
  return {
    name,
    eye,
    forward,
    up,
    fovYDegrees: (Math.fround(yfov) * 180) / Math.PI,
    aspectRatio: typeof aspect === 'number' && aspect > 0 && Number.isFinite(aspect) ? aspect : null,
  };
}
