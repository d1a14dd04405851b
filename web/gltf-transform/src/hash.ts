import type { Primitive } from '@gltf-transform/core';

const FNV_OFFSET = 0xcbf29ce484222325n;
const FNV_PRIME = 0x100000001b3n;
const MASK = 0xffffffffffffffffn;
const LITTLE_ENDIAN = new Uint8Array(new Uint32Array([1]).buffer)[0] === 1;

/** The number of triangles of a triangle-list primitive (its indices, or else its vertices, over 3). */
export function triangleCount(prim: Primitive): number {
  const indices = prim.getIndices();
  const position = prim.getAttribute('POSITION');
  const corners = indices ? indices.getCount() : position ? position.getCount() : 0;
  return Math.floor(corners / 3);
}

/**
 * The geometry hash (SPEC.md 2.5) of triangles `[first, first + count)` of a primitive: 64-bit
 * FNV-1a over the little-endian `f32` bytes of `x, y, z` of every corner, in triangle order, as
 * 16 lowercase hexadecimal digits. Positions are read as the accessor gives them (a normalized
 * integer accessor is denormalized), before any node transform. Returns null when the primitive
 * has no POSITION or the range lies outside its triangles.
 */
export function geometryHash(prim: Primitive, first = 0, count = triangleCount(prim) - first): string | null {
  const position = prim.getAttribute('POSITION');
  if (!position || first < 0 || count < 0 || first + count > triangleCount(prim)) return null;
  const indices = prim.getIndices();
  const corner = new Float32Array(3);
  const bytes = new Uint8Array(corner.buffer);
  const element: number[] = [];
  let hash = FNV_OFFSET;
  for (let c = 3 * first; c < 3 * (first + count); c++) {
    const vertex = indices ? indices.getScalar(c) : c;
    position.getElement(vertex, element);
    corner[0] = element[0];
    corner[1] = element[1];
    corner[2] = element[2];
    // Float32Array holds native-endian bytes; every platform Node runs on is little-endian, and
    // the check below keeps it honest where that would not hold.
    for (let b = 0; b < 12; b++) hash = ((hash ^ BigInt(bytes[LITTLE_ENDIAN ? b : (b & ~3) + 3 - (b & 3)])) * FNV_PRIME) & MASK;
  }
  return hash.toString(16).padStart(16, '0');
}
