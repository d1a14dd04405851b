// three.js geometry over the kernels' output, on three.js's own device: the refined mesh is
// copied GPU to GPU into the buffers three.js's WebGPU backend draws, with no read-back and no
// JavaScript copy of its vertices. The backend makes an attribute's buffer from its array the
// first time it meets it; here it is made ahead of the first draw (`createAttribute`), from a
// zero-filled array of the right size, and then filled by `copyBufferToBuffer` in the same
// queue as the refinement, so the next frame draws it. The arrays are never written, so they
// cost address space rather than memory.
import { BufferAttribute, BufferGeometry, Box3, Sphere, Vector3 } from 'three/webgpu';

/**
 * @typedef {import('../kernels.js').RefinedBuffers} RefinedBuffers
 * @typedef {{ position: any, color: any, normal: any | null, vertexCount: number }} SharedAttributes
 */

/**
 * The backend's buffer of `attribute`, made now.
 * @param {any} backend a WebGPURenderer's WebGPU backend
 * @param {any} attribute
 * @param {boolean} index
 * @returns {GPUBuffer}
 */
function attributeBuffer(backend, attribute, index) {
  if (index) backend.createIndexAttribute(attribute);
  else backend.createAttribute(attribute);
  const buffer = backend.get(attribute).buffer;
  if (!buffer) throw new Error('three.js made no GPU buffer for a refined attribute (this three.js version lays out its WebGPU backend differently)');
  return buffer;
}

/**
 * Vertex attributes of a refined object (positions, linear RGBA colours, and normals where
 * the kernel makes them: Loop objects), filled from `refined` by commands in `encoder`; the
 * primitives of the object share them.
 * @param {any} renderer a WebGPURenderer on its WebGPU backend
 * @param {GPUCommandEncoder} encoder
 * @param {RefinedBuffers} refined
 * @returns {SharedAttributes}
 */
export function vertexAttributes(renderer, encoder, refined) {
  const v = refined.vertexCount;
  const make = (/** @type {number} */ itemSize, /** @type {GPUBuffer} */ source) => {
    const attribute = new BufferAttribute(new Float32Array(itemSize * Math.max(v, 1)), itemSize);
    const target = attributeBuffer(renderer.backend, attribute, false);
    if (v > 0) encoder.copyBufferToBuffer(source, 0, target, 0, 4 * itemSize * v);
    return attribute;
  };
  return {
    position: make(3, refined.positions),
    color: make(4, refined.colours),
    normal: refined.normals ? make(3, refined.normals) : null,
    vertexCount: v,
  };
}

/**
 * The geometry of one primitive: `shared`'s vertices and the refined triangles
 * `start .. end` of `refined` (the primitive's coarse range, `refined.triangleStart`), with
 * `bounds` (object space) as its bounding box: the vertices never reach JavaScript, so three.js
 * cannot compute one.
 * @param {any} renderer
 * @param {GPUCommandEncoder} encoder
 * @param {RefinedBuffers} refined
 * @param {SharedAttributes} shared
 * @param {number} start
 * @param {number} end
 * @param {{ min: number[], max: number[] }} bounds
 */
export function primitiveGeometry(renderer, encoder, refined, shared, start, end, bounds) {
  const count = Math.max(0, end - start);
  const index = new BufferAttribute(new Uint32Array(3 * Math.max(count, 1)), 1);
  const target = attributeBuffer(renderer.backend, index, true);
  if (count > 0) encoder.copyBufferToBuffer(refined.indices, 12 * start, target, 0, 12 * count);
  const geometry = new BufferGeometry();
  geometry.setAttribute('position', shared.position);
  geometry.setAttribute('color', shared.color);
  if (shared.normal) geometry.setAttribute('normal', shared.normal);
  geometry.setIndex(index);
  geometry.setDrawRange(0, 3 * count);
  geometry.boundingBox = new Box3(new Vector3(...bounds.min), new Vector3(...bounds.max));
  geometry.boundingSphere = geometry.boundingBox.getBoundingSphere(new Sphere());
  return geometry;
}
