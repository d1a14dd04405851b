// The `.hce` container reader (SPEC.md Appendix A): identifier, header, directory, checksums,
// padding, metadata, object table and every object's sections, checked against each other
// before anything is allocated from a count the file gives. It never throws anything but
// HceError on any input.
import { HceError } from './errors.js';

/** The file identifier (A.2). */
const IDENTIFIER = [0x89, 0x48, 0x43, 0x45, 0x0d, 0x0a, 0x1a, 0x0a];
const FILE_LEVEL = 0xffffffff;
const DIRECTORY_ENTRY = 32;
const SECTION_ALIGN = 256;
const OBJECT_RECORD_LEN = 64;

/** `NBRS` entry of an edge without a neighbour. */
export const NO_NEIGHBOUR = 0xffffffff;
/** Vertex flag bits (A.5). */
export const VERTEX_BOUNDARY = 1;
/** Spoke flag bits (A.5). */
export const SPOKE_SHARP = 1;
export const SPOKE_BOUNDARY = 2;
export const RULE_SMOOTH = 0;
export const RULE_CREASE = 1;
export const RULE_CORNER = 2;

/** @param {string} s four ASCII characters */
const fourcc = (s) => s.charCodeAt(0) | (s.charCodeAt(1) << 8) | (s.charCodeAt(2) << 16) | (s.charCodeAt(3) << 24) >>> 0;

/** The per-object sections of table A.5, in order, with their element size in bytes. */
const OBJECT_SECTIONS = /** @type {const} */ ([
  ['POSN', 4], ['TRIS', 4], ['ROFS', 4], ['RING', 4], ['VFLG', 4], ['SFLG', 4], ['CSPK', 4],
  ['NBRS', 4], ['EDGE', 4], ['TREC', 16], ['NRML', 12], ['BITS', 4], ['COLR', 4],
]);
const KNOWN = new Map([['META', 'file'], ['OBJS', 'file'], ...OBJECT_SECTIONS.map(([n]) => [n, 'object'])].map(([n, s]) => [fourcc(n) >>> 0, { name: n, scope: s }]));

/** @type {Uint32Array | null} */
let crcTable = null;

/**
 * CRC-32 (ISO-HDLC, as zlib) of `bytes`, continuing from `crc` (A.3).
 * @param {Uint8Array} bytes
 * @param {number} [crc]
 */
export function crc32(bytes, crc = 0) {
  if (crcTable === null) {
    crcTable = new Uint32Array(256);
    for (let n = 0; n < 256; n++) {
      let c = n;
      for (let k = 0; k < 8; k++) c = c & 1 ? 0xedb88320 ^ (c >>> 1) : c >>> 1;
      crcTable[n] = c >>> 0;
    }
  }
  let c = (crc ^ 0xffffffff) >>> 0;
  for (let i = 0; i < bytes.length; i++) c = crcTable[(c ^ bytes[i]) & 0xff] ^ (c >>> 8);
  return (c ^ 0xffffffff) >>> 0;
}

/**
 * The 64-bit FNV-1a geometry hash (2.5) of the corners `triangles` pick from `positions`, as
 * 16 lowercase hexadecimal digits.
 * @param {Float32Array} positions x, y, z per vertex
 * @param {ArrayLike<number>} triangles three vertex indices per triangle
 */
export function geometryHash(positions, triangles) {
  // h in four 16-bit limbs; the prime 2^40 + 0x1b3 is limbs (0x1b3, 0, 0x100, 0).
  let h0 = 0x2325, h1 = 0x8422, h2 = 0x9ce4, h3 = 0xcbf2;
  const bytes = new Uint8Array(4);
  const view = new DataView(bytes.buffer);
  for (let i = 0; i < triangles.length; i++) {
    const v = triangles[i];
    for (let k = 0; k < 3; k++) {
      view.setFloat32(0, positions[3 * v + k], true);
      for (let b = 0; b < 4; b++) {
        h0 ^= bytes[b];
        const r0 = h0 * 0x1b3;
        const r1 = h1 * 0x1b3 + (r0 >>> 16);
        const r2 = h2 * 0x1b3 + h0 * 0x100 + Math.floor(r1 / 65536);
        const r3 = h3 * 0x1b3 + h1 * 0x100 + Math.floor(r2 / 65536);
        h0 = r0 & 0xffff;
        h1 = r1 & 0xffff;
        h2 = r2 & 0xffff;
        h3 = r3 & 0xffff;
      }
    }
  }
  const hex = (/** @type {number} */ x) => x.toString(16).padStart(4, '0');
  return hex(h3) + hex(h2) + hex(h1) + hex(h0);
}

/**
 * @typedef {object} ControlMesh the arrays of `ControlMesh` in format/src/model.rs
 * @property {Float32Array} positions
 * @property {Uint32Array} triangles
 * @property {Uint32Array} ringOffsets
 * @property {Uint32Array} ring
 * @property {Uint32Array} vertexFlags
 * @property {Uint32Array} spokeFlags
 * @property {Uint32Array} cornerSpokes
 * @property {Uint32Array} neighbours
 * @property {Uint32Array} edges
 */

/**
 * @typedef {object} HceObject one container object (A.7)
 * @property {number} index
 * @property {string} name
 * @property {'multiresolution' | 'flat'} kind
 * @property {string} geometryHash 16 hex digits
 * @property {ControlMesh} mesh
 * @property {Uint32Array} records TREC: bits_start, colour_start, normal_start, normal_count
 * @property {Float32Array} normals x, y, z per normal
 * @property {Uint32Array} bits
 * @property {number} bitLen
 * @property {Uint32Array} colours RGB9E5
 */

/**
 * @typedef {object} Container
 * @property {{ major: number, minor: number }} version
 * @property {{ generator: string, bakeParameters: string }} metadata
 * @property {HceObject[]} objects
 */

/**
 * Reads a container (A.1 to A.9): every structural rule, every checksum and the zero padding.
 * Content rules (the tables) are checked by tables.js before upload.
 * @param {Uint8Array} bytes the container, from its first byte
 * @returns {Container}
 */
export function readContainer(bytes) {
  const dv = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  const u32 = (/** @type {number} */ at) => dv.getUint32(at, true);
  const u64 = (/** @type {number} */ at) => {
    const hi = dv.getUint32(at + 4, true);
    // Offsets and lengths past 2^53 cannot be inside any file we can hold.
    return hi >= 0x200000 ? Infinity : hi * 4294967296 + dv.getUint32(at, true);
  };
  // A.2: the identifier, and what a mismatch suggests.
  if (bytes.length < 8 || IDENTIFIER.some((b, i) => bytes[i] !== b)) {
    let hint = 'not an hce container';
    if (bytes.length >= 4 && bytes[0] === 0x09 && bytes[1] === 0x48) hint = 'the high bit of the first byte was stripped (a 7-bit transfer)';
    else if (bytes.length >= 8 && bytes[4] === 0x0a) hint = 'CR LF was converted to LF (a text-mode transfer)';
    else if (bytes.length >= 8 && bytes[4] === 0x0d && bytes[5] === 0x0d) hint = 'LF was converted to CR LF (a text-mode transfer)';
    throw new HceError('file[0]', `bad file identifier: ${hint} (SPEC.md A.2)`);
  }
  if (bytes.length < 32) throw new HceError('file', `${bytes.length} bytes, shorter than the 32-byte header (SPEC.md A.3)`);
  const major = dv.getUint16(8, true);
  const minor = dv.getUint16(10, true);
  if (major !== 1) throw new HceError('file[8]', `container major version ${major}; this reader reads version 1 (SPEC.md A.8)`);
  const n = u32(12);
  const fileLength = u64(16);
  const dirEnd = 32 + DIRECTORY_ENTRY * n;
  if (dirEnd > fileLength) throw new HceError('file[12]', `${n} directory entries do not fit in file_length ${fileLength} (SPEC.md A.3)`);
  if (fileLength !== bytes.length) throw new HceError('file[16]', `file_length is ${fileLength} but ${bytes.length} bytes are present: the file is ${fileLength > bytes.length ? 'truncated' : 'followed by extra bytes'} (SPEC.md A.3)`);
  const headerCrc = crc32(bytes.subarray(32, dirEnd), crc32(bytes.subarray(0, 28)));
  if (headerCrc !== u32(28)) throw new HceError('file[28]', `header checksum mismatch (stored ${u32(28).toString(16)}, computed ${headerCrc.toString(16)}) (SPEC.md A.3)`);

  // A.4: the directory.
  /** @type {{ type: number, object: number, offset: number, length: number, at: string }[]} */
  const sections = [];
  for (let i = 0; i < n; i++) {
    const e = 32 + DIRECTORY_ENTRY * i;
    const s = { type: u32(e), object: u32(e + 4), offset: u64(e + 8), length: u64(e + 16), at: `sections[${i}]` };
    if (!(s.offset + s.length <= fileLength) || s.offset < dirEnd || s.offset % SECTION_ALIGN !== 0) {
      throw new HceError(s.at, `offset ${s.offset} and length ${s.length} break the layout rules (inside the file, after the directory, 256-aligned; SPEC.md A.4)`);
    }
    const crc = crc32(bytes.subarray(s.offset, s.offset + s.length));
    if (crc !== u32(e + 24)) throw new HceError(s.at, `section checksum mismatch (stored ${u32(e + 24).toString(16)}, computed ${crc.toString(16)}): the file is damaged (SPEC.md A.4)`);
    sections.push(s);
  }
  // Overlaps, padding and trailing bytes (A.1): sorted by offset, the gaps must be zero.
  const sorted = [...sections].sort((a, b) => a.offset - b.offset || a.length - b.length);
  let end = dirEnd;
  for (const s of sorted) {
    if (s.length === 0) continue;
    if (s.offset < end) throw new HceError(s.at, `overlaps another section or the directory (SPEC.md A.4)`);
    for (let i = end; i < s.offset; i++) {
      if (bytes[i] !== 0) throw new HceError(`file[${i}]`, 'padding byte between sections is not zero (SPEC.md A.1)');
    }
    end = s.offset + s.length;
  }
  if (end !== fileLength) throw new HceError(`file[${end}]`, `${fileLength - end} bytes after the last section (SPEC.md A.1)`);

  /** @type {Map<string, { offset: number, length: number }>} */
  const byKey = new Map();
  for (const s of sections) {
    const known = KNOWN.get(s.type >>> 0);
    if (!known) continue; // A.8: unknown sections are skipped after the bounds checks.
    if (known.scope === 'file' && s.object !== FILE_LEVEL) throw new HceError(s.at, `file-level section ${known.name} names object ${s.object} (SPEC.md A.4)`);
    const key = `${known.name}/${s.object}`;
    if (byKey.has(key)) throw new HceError(s.at, `a second ${known.name} section for the same ${s.object === FILE_LEVEL ? 'file' : `object ${s.object}`} (SPEC.md A.4)`);
    byKey.set(key, s);
  }
  const file = (/** @type {string} */ name) => {
    const s = byKey.get(`${name}/${FILE_LEVEL}`);
    if (!s) throw new HceError('file', `the required ${name} section is missing (SPEC.md A.5)`);
    return bytes.subarray(s.offset, s.offset + s.length);
  };

  // A.6: metadata.
  const meta = file('META');
  if (meta.length < 16) throw new HceError('metadata', `section is ${meta.length} bytes, the fixed part needs 16 (SPEC.md A.6)`);
  const md = new DataView(meta.buffer, meta.byteOffset, meta.byteLength);
  const g = md.getUint32(8, true);
  const p = md.getUint32(12, true);
  if (16 + g + p > meta.length) throw new HceError('metadata', `generator and bake parameters run past the section (SPEC.md A.6)`);
  const utf8 = new TextDecoder('utf-8', { fatal: true });
  let metadata;
  try {
    metadata = { generator: utf8.decode(meta.subarray(16, 16 + g)), bakeParameters: utf8.decode(meta.subarray(16 + g, 16 + g + p)) };
  } catch {
    throw new HceError('metadata', 'generator or bake parameters are not valid UTF-8 (SPEC.md A.6)');
  }
  if (metadata.bakeParameters !== '') {
    let parsed;
    try {
      parsed = JSON.parse(metadata.bakeParameters);
    } catch {
      parsed = null;
    }
    if (parsed === null || typeof parsed !== 'object' || Array.isArray(parsed)) {
      throw new HceError('metadata.bake_parameters', 'is not a JSON object text (SPEC.md A.6)');
    }
  }

  // A.7: the object table.
  const objs = file('OBJS');
  if (objs.length < 8) throw new HceError('OBJS', `section is ${objs.length} bytes, the fixed part needs 8 (SPEC.md A.7)`);
  const od = new DataView(objs.buffer, objs.byteOffset, objs.byteLength);
  const count = od.getUint32(0, true);
  const recordSize = od.getUint32(4, true);
  if (recordSize < OBJECT_RECORD_LEN) throw new HceError('OBJS', `record_size ${recordSize} is smaller than 64 (SPEC.md A.7)`);
  const poolStart = 8 + count * recordSize;
  if (poolStart > objs.length) throw new HceError('OBJS', `${count} records of ${recordSize} bytes run past the section (SPEC.md A.7)`);
  for (const s of sections) {
    const known = KNOWN.get(s.type >>> 0);
    if (known?.scope === 'object' && s.object >= count) throw new HceError(s.at, `names object ${s.object} but the table has ${count} (SPEC.md A.4)`);
  }
  /** @type {HceObject[]} */
  const objects = [];
  for (let i = 0; i < count; i++) {
    const r = 8 + i * recordSize;
    const at = `objects[${i}]`;
    const nameOffset = od.getUint32(r, true);
    const nameLength = od.getUint32(r + 4, true);
    if (poolStart + nameOffset + nameLength > objs.length) throw new HceError(at, 'name lies outside the name pool (SPEC.md A.7)');
    let name;
    try {
      name = utf8.decode(objs.subarray(poolStart + nameOffset, poolStart + nameOffset + nameLength));
    } catch {
      throw new HceError(at, 'name is not valid UTF-8 (SPEC.md A.7)');
    }
    const kindValue = od.getUint32(r + 8, true);
    if (kindValue > 1) throw new HceError(at, `kind ${kindValue} is neither 0 (multiresolution) nor 1 (flat) (SPEC.md A.7)`);
    const hashLo = od.getUint32(r + 16, true);
    const hashHi = od.getUint32(r + 20, true);
    const V = od.getUint32(r + 24, true);
    const F = od.getUint32(r + 28, true);
    const R = od.getUint32(r + 32, true);
    const E = od.getUint32(r + 36, true);
    const normalCount = od.getUint32(r + 40, true);
    const colourCount = od.getUint32(r + 44, true);
    const bitLenHi = od.getUint32(r + 52, true);
    const bitLen = bitLenHi >= 0x200000 ? Infinity : bitLenHi * 4294967296 + od.getUint32(r + 48, true);
    const counts = {
      POSN: 3 * V, TRIS: 3 * F, ROFS: V + 1, RING: R, VFLG: V, SFLG: R, CSPK: 3 * F, NBRS: 3 * F,
      EDGE: 3 * F, TREC: F, NRML: normalCount, BITS: Math.ceil(bitLen / 32), COLR: colourCount,
    };
    /** @type {Record<string, Uint8Array>} */
    const data = {};
    for (const [sec, size] of OBJECT_SECTIONS) {
      const s = byKey.get(`${sec}/${i}`);
      if (!s) throw new HceError(at, `the required ${sec} section is missing (SPEC.md A.5)`);
      const want = counts[sec] * size;
      if (s.length !== want) throw new HceError(`${at}.${sec}`, `section is ${s.length} bytes but the record's counts call for ${want} (SPEC.md A.7)`);
      // A copy: aligned for typed arrays whatever the container's offset in its buffer.
      data[sec] = bytes.slice(s.offset, s.offset + s.length);
    }
    const f32 = (/** @type {string} */ sec) => new Float32Array(data[sec].buffer, 0, data[sec].length / 4);
    const w32 = (/** @type {string} */ sec) => new Uint32Array(data[sec].buffer, 0, data[sec].length / 4);
    const object = {
      index: i,
      name,
      kind: /** @type {'multiresolution' | 'flat'} */ (kindValue === 0 ? 'multiresolution' : 'flat'),
      geometryHash: hashHi.toString(16).padStart(8, '0') + hashLo.toString(16).padStart(8, '0'),
      mesh: {
        positions: f32('POSN'), triangles: w32('TRIS'), ringOffsets: w32('ROFS'), ring: w32('RING'),
        vertexFlags: w32('VFLG'), spokeFlags: w32('SFLG'), cornerSpokes: w32('CSPK'),
        neighbours: w32('NBRS'), edges: w32('EDGE'),
      },
      records: w32('TREC'),
      normals: f32('NRML'),
      bits: w32('BITS'),
      bitLen,
      colours: w32('COLR'),
    };
    let maxEdge = -1;
    for (const e of object.mesh.edges) maxEdge = Math.max(maxEdge, e);
    if (E !== maxEdge + 1) throw new HceError(at, `edge_count ${E} is not max(EDGE) + 1 = ${maxEdge + 1} (SPEC.md A.7)`);
    objects.push(object);
  }
  return { version: { major, minor }, metadata, objects };
}
