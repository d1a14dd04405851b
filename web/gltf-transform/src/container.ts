// Just enough of the `.hce` container (SPEC.md Appendix A) to know its objects: the header, the
// section directory and the `OBJS` object table. Nothing here checks checksums or decodes the
// per-object sections; `hce validate` does that.

/** One row of the container's object table (SPEC.md A.7). */
export interface ContainerObject {
  name: string;
  /** 0 multiresolution, 1 flat. */
  kind: number;
  /** The object's geometry hash, 16 lowercase hexadecimal digits. */
  geometryHash: string;
  triangleCount: number;
}

/** What the header says and the object table lists. */
export interface ContainerSummary {
  majorVersion: number;
  minorVersion: number;
  objects: ContainerObject[];
}

const IDENTIFIER = [0x89, 0x48, 0x43, 0x45, 0x0d, 0x0a, 0x1a, 0x0a];
const OBJS = 0x534a424f; // "OBJS" read as a little-endian u32
const FILE_LEVEL = 0xffffffff;

/**
 * Reads the header and object table of a container. Throws an Error that says what is wrong
 * when the bytes are not a version 1 container or its object table lies outside them.
 */
export function readContainerSummary(bytes: Uint8Array): ContainerSummary {
  if (bytes.byteLength < 32) throw new Error(`${bytes.byteLength} bytes are too few for a container header (32)`);
  for (let i = 0; i < IDENTIFIER.length; i++) {
    if (bytes[i] !== IDENTIFIER[i]) throw new Error('the bytes do not start with the .hce file identifier');
  }
  const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  const majorVersion = view.getUint16(8, true);
  const minorVersion = view.getUint16(10, true);
  if (majorVersion !== 1) throw new Error(`container major version ${majorVersion} is not 1`);
  const sectionCount = view.getUint32(12, true);
  if (32 + 32 * sectionCount > bytes.byteLength) {
    throw new Error(`the directory of ${sectionCount} sections does not fit in ${bytes.byteLength} bytes`);
  }
  let objs: { offset: number; length: number } | null = null;
  for (let i = 0; i < sectionCount; i++) {
    const entry = 32 + 32 * i;
    if (view.getUint32(entry, true) === OBJS && view.getUint32(entry + 4, true) === FILE_LEVEL) {
      const offset = Number(view.getBigUint64(entry + 8, true));
      const length = Number(view.getBigUint64(entry + 16, true));
      if (offset + length > bytes.byteLength) throw new Error('the OBJS section lies outside the container');
      objs = { offset, length };
    }
  }
  if (!objs) throw new Error('the container has no OBJS section');
  if (objs.length < 8) throw new Error('the OBJS section is shorter than its 8-byte head');
  const count = view.getUint32(objs.offset, true);
  const recordSize = view.getUint32(objs.offset + 4, true);
  if (recordSize < 64) throw new Error(`OBJS record size ${recordSize} is below 64`);
  const poolStart = 8 + recordSize * count;
  if (poolStart > objs.length) throw new Error(`OBJS is too short for ${count} records of ${recordSize} bytes`);
  const decoder = new TextDecoder();
  const objects: ContainerObject[] = [];
  for (let i = 0; i < count; i++) {
    const record = objs.offset + 8 + recordSize * i;
    const nameOffset = view.getUint32(record, true);
    const nameLength = view.getUint32(record + 4, true);
    if (poolStart + nameOffset + nameLength > objs.length) throw new Error(`the name of object ${i} lies outside OBJS`);
    const nameStart = objs.offset + poolStart + nameOffset;
    objects.push({
      name: decoder.decode(bytes.subarray(nameStart, nameStart + nameLength)),
      kind: view.getUint32(record + 8, true),
      geometryHash: view.getBigUint64(record + 16, true).toString(16).padStart(16, '0'),
      triangleCount: view.getUint32(record + 28, true),
    });
  }
  return { majorVersion, minorVersion, objects };
}
