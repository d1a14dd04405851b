import {
  type Buffer,
  Extension,
  ExtensionProperty,
  Format,
  GLB_BUFFER,
  type IProperty,
  type Mesh,
  type Nullable,
  type Primitive,
  PropertyType,
  type ReaderContext,
  type WriterContext,
} from '@gltf-transform/core';
import { type ContainerSummary, readContainerSummary } from './container.js';
import { geometryHash, triangleCount } from './hash.js';

export const EXT_HCE_BAKED_LIGHTING = 'EXT_hce_baked_lighting';

/** The container's buffer view starts at a multiple of this within its buffer (SPEC.md 3.3). */
const CONTAINER_ALIGNMENT = 256;
const TRIANGLES = 4;
const GEOMETRY_HASH = /^[0-9a-f]{16}$/;

interface IBakedLighting extends IProperty {
  container: Uint8Array;
  version: string | null;
  buffer: Buffer;
}

/**
 * The root object: the `.hce` container, carried as the exact bytes that were read, and the
 * buffer it is written to.
 */
export class BakedLighting extends ExtensionProperty<IBakedLighting> {
  public static EXTENSION_NAME: typeof EXT_HCE_BAKED_LIGHTING = EXT_HCE_BAKED_LIGHTING;
  public declare extensionName: typeof EXT_HCE_BAKED_LIGHTING;
  public declare propertyType: 'BakedLighting';
  public declare parentTypes: [PropertyType.ROOT];

  protected init(): void {
    this.extensionName = EXT_HCE_BAKED_LIGHTING;
    this.propertyType = 'BakedLighting';
    this.parentTypes = [PropertyType.ROOT];
  }

  protected getDefaults(): Nullable<IBakedLighting> {
    return Object.assign(super.getDefaults() as IProperty, { container: null, version: null, buffer: null });
  }

  /** The container's bytes. */
  public getContainer(): Uint8Array | null {
    return this.get('container');
  }

  public setContainer(container: Uint8Array): this {
    return this.set('container', container);
  }

  /** The root object's informative `version`, or null when it had none. */
  public getVersion(): string | null {
    return this.get('version');
  }

  public setVersion(version: string | null): this {
    return this.set('version', version);
  }

  /** The buffer the container is written to; while set, `prune` keeps that buffer. */
  public getBuffer(): Buffer | null {
    return this.getRef('buffer');
  }

  public setBuffer(buffer: Buffer | null): this {
    return this.setRef('buffer', buffer);
  }
}

interface IBakedPrimitive extends IProperty {
  object: number;
  geometryHash: string;
  firstTriangle: number;
  sourceTriangleCount: number;
}

/** A primitive's link to its object in the container. */
export class BakedPrimitive extends ExtensionProperty<IBakedPrimitive> {
  public static EXTENSION_NAME: typeof EXT_HCE_BAKED_LIGHTING = EXT_HCE_BAKED_LIGHTING;
  public declare extensionName: typeof EXT_HCE_BAKED_LIGHTING;
  public declare propertyType: 'BakedPrimitive';
  public declare parentTypes: [PropertyType.PRIMITIVE];

  protected init(): void {
    this.extensionName = EXT_HCE_BAKED_LIGHTING;
    this.propertyType = 'BakedPrimitive';
    this.parentTypes = [PropertyType.PRIMITIVE];
  }

  protected getDefaults(): Nullable<IBakedPrimitive> {
    return Object.assign(super.getDefaults() as IProperty, {
      object: 0,
      geometryHash: '',
      firstTriangle: 0,
      sourceTriangleCount: 0,
    });
  }

  public getObject(): number {
    return this.get('object');
  }

  public setObject(object: number): this {
    return this.set('object', object);
  }

  /** The geometry hash of the primitive's triangles when it was baked. */
  public getGeometryHash(): string {
    return this.get('geometryHash');
  }

  public setGeometryHash(hash: string): this {
    return this.set('geometryHash', hash);
  }

  public getFirstTriangle(): number {
    return this.get('firstTriangle');
  }

  public setFirstTriangle(first: number): this {
    return this.set('firstTriangle', first);
  }

  /**
   * How many triangles the primitive had when the link was read or made (0: not known). It is
   * not written: the writer drops a link whose primitive no longer has that many triangles, and
   * finds the link's triangles again inside a primitive that a join made.
   */
  public getSourceTriangleCount(): number {
    return this.get('sourceTriangleCount');
  }

  public setSourceTriangleCount(count: number): this {
    return this.set('sourceTriangleCount', count);
  }
}

interface LinkDef {
  object: number;
  geometryHash: string;
  firstTriangle?: number;
}

/** A link that will be written: the primitive, its mesh and what its extension object says. */
interface PlannedLink {
  mesh: Mesh;
  def: LinkDef;
  first: number;
  count: number;
}

/**
 * [`EXT_hce_baked_lighting`](../../SPEC.md): baked diffuse global illumination in a `.hce`
 * container, linked from mesh primitives.
 *
 * Reading keeps the container's bytes as they are; writing puts them back in a buffer view of
 * their own, 256-byte aligned in its buffer. Before writing, every link is checked against what
 * the document now holds, because transforms that join, split or copy primitives know nothing of
 * the extension: a link is written only when its primitive is still a triangle list with as many
 * triangles as when it was linked, lies inside its object's range, is the only primitive outside
 * its mesh drawing that object, and overlaps no other primitive's range of it. A primitive that a join made out of linked primitives of one
 * object, in their order and with their positions unchanged, gets a link covering them all. Every
 * link that is not written is reported as a warning through the document's logger.
 */
export class HCEBakedLighting extends Extension {
  public readonly extensionName: typeof EXT_HCE_BAKED_LIGHTING = EXT_HCE_BAKED_LIGHTING;
  public static readonly EXTENSION_NAME: typeof EXT_HCE_BAKED_LIGHTING = EXT_HCE_BAKED_LIGHTING;
  public readonly prewriteTypes: PropertyType[] = [PropertyType.BUFFER];

  private plan = new Map<Primitive, PlannedLink>();
  private written: { bytes: Uint8Array; baked: BakedLighting } | null = null;

  public createBakedLighting(): BakedLighting {
    return new BakedLighting(this.document.getGraph());
  }

  public createBakedPrimitive(): BakedPrimitive {
    return new BakedPrimitive(this.document.getGraph());
  }

  /** The root object, if the document has one. */
  public getBakedLighting(): BakedLighting | null {
    return this.document.getRoot().getExtension<BakedLighting>(EXT_HCE_BAKED_LIGHTING);
  }

  /** The extension is never required (SPEC.md 3.2): it only adds lighting to complete geometry. */
  public isRequired(): boolean {
    return false;
  }

  private warn(message: string): void {
    this.document.getLogger().warn(`${EXT_HCE_BAKED_LIGHTING}: ${message}`);
  }

  /** @hidden */
  public read(context: ReaderContext): this {
    const json = context.jsonDoc.json;
    const rootDef = json.extensions?.[EXT_HCE_BAKED_LIGHTING] as { bufferView?: unknown; version?: unknown } | undefined;
    if (rootDef) {
      const index = rootDef.bufferView;
      const view = typeof index === 'number' && Number.isInteger(index) ? context.bufferViews[index] : undefined;
      if (view) {
        const baked = this.createBakedLighting()
          .setContainer(view.slice())
          .setVersion(typeof rootDef.version === 'string' ? rootDef.version : null)
          .setBuffer(context.bufferViewBuffers[index as number] ?? null);
        this.document.getRoot().setExtension(EXT_HCE_BAKED_LIGHTING, baked);
      } else {
        this.warn(`the root object names buffer view ${String(index)}, which the asset does not have; the baked lighting is not read`);
      }
    }
    const meshDefs = json.meshes ?? [];
    for (let m = 0; m < meshDefs.length; m++) {
      const primDefs = meshDefs[m].primitives ?? [];
      const prims = context.meshes[m].listPrimitives();
      for (let p = 0; p < primDefs.length; p++) {
        const linkDef = primDefs[p].extensions?.[EXT_HCE_BAKED_LIGHTING] as Record<string, unknown> | undefined;
        if (!linkDef) continue;
        const { object, geometryHash: hash, firstTriangle = 0 } = linkDef;
        if (!isIndex(object) || !isIndex(firstTriangle) || typeof hash !== 'string' || !GEOMETRY_HASH.test(hash)) {
          this.warn(`meshes[${m}].primitives[${p}]: malformed extension object ${JSON.stringify(linkDef)}; it is not read`);
          continue;
        }
        const link = this.createBakedPrimitive()
          .setObject(object)
          .setGeometryHash(hash)
          .setFirstTriangle(firstTriangle)
          .setSourceTriangleCount(triangleCount(prims[p]));
        prims[p].setExtension(EXT_HCE_BAKED_LIGHTING, link);
      }
    }
    return this;
  }

  /** @hidden Decides which links are written and puts the container among the buffer's views. */
  public prewrite(context: WriterContext, propertyType: PropertyType): this {
    if (propertyType !== PropertyType.BUFFER) return this;
    this.written = null;
    const baked = this.getBakedLighting();
    const bytes = baked?.getContainer() ?? null;
    this.plan = this.planLinks(baked !== null && bytes !== null ? bytes : null);
    if (!baked || !bytes) return this;
    const buffer = this.containerBuffer(context, baked);
    const views = context.otherBufferViews.get(buffer) ?? [];
    // A view of its own, so that the index map finds this container and no other extension's
    // identical bytes.
    const own = new Uint8Array(bytes.buffer, bytes.byteOffset, bytes.byteLength);
    views.push(own);
    context.otherBufferViews.set(buffer, views);
    this.written = { bytes: own, baked };
    return this;
  }

  /** @hidden */
  public write(context: WriterContext): this {
    const json = context.jsonDoc.json;
    if (this.written) {
      const index = context.otherBufferViewsIndexMap.get(this.written.bytes);
      if (index !== undefined) {
        this.alignContainer(context, index);
        const rootDef: { bufferView: number; version?: string } = { bufferView: index };
        const version = this.written.baked.getVersion();
        if (version !== null) rootDef.version = version;
        json.extensions = json.extensions ?? {};
        json.extensions[EXT_HCE_BAKED_LIGHTING] = rootDef;
      }
    }
    for (const [prim, planned] of this.plan) {
      const meshIndex = context.meshIndexMap.get(planned.mesh);
      if (meshIndex === undefined) continue;
      const primDef = json.meshes?.[meshIndex].primitives[planned.mesh.listPrimitives().indexOf(prim)];
      if (!primDef) continue;
      primDef.extensions = primDef.extensions ?? {};
      primDef.extensions[EXT_HCE_BAKED_LIGHTING] = planned.def;
    }
    this.plan = new Map();
    this.written = null;
    return this;
  }

  /**
   * The buffer that gets the container: for a GLB the one its other data goes to (a GLB has one
   * binary chunk), otherwise the one it was read from while that still exists.
   */
  private containerBuffer(context: WriterContext, baked: BakedLighting): Buffer {
    const buffers = this.document.getRoot().listBuffers();
    const own = baked.getBuffer();
    if (context.options.format === Format.GLB) {
      const used = buffers.find((buffer) => buffer.listParents().some((parent) => parent.propertyType === PropertyType.ACCESSOR));
      if (used) return used;
    }
    if (own) return own;
    if (buffers.length > 0) return buffers[0];
    const buffer = this.document.createBuffer();
    baked.setBuffer(buffer);
    return buffer;
  }

  /**
   * Moves the container's view (and every view after it in the same buffer) forward to a multiple
   * of 256 within the buffer, by inserting zero bytes before it.
   */
  private alignContainer(context: WriterContext, index: number): void {
    const json = context.jsonDoc.json;
    const viewDef = json.bufferViews![index];
    const start = viewDef.byteOffset ?? 0;
    const pad = (CONTAINER_ALIGNMENT - (start % CONTAINER_ALIGNMENT)) % CONTAINER_ALIGNMENT;
    if (pad === 0) return;
    const bufferDef = json.buffers![viewDef.buffer];
    const uri = bufferDef.uri ?? GLB_BUFFER;
    const data = context.jsonDoc.resources[uri];
    if (!data) {
      this.warn(`the container's buffer view starts at byte ${start}, not a multiple of ${CONTAINER_ALIGNMENT}`);
      return;
    }
    const moved = new Uint8Array(data.byteLength + pad);
    moved.set(data.subarray(0, start), 0);
    moved.set(data.subarray(start), start + pad);
    context.jsonDoc.resources[uri] = moved;
    bufferDef.byteLength += pad;
    for (const def of json.bufferViews!) {
      if (def.buffer === viewDef.buffer && (def.byteOffset ?? 0) >= start && def !== viewDef) def.byteOffset = (def.byteOffset ?? 0) + pad;
      // Compression extensions keep their own offsets into a buffer.
      for (const extensionDef of Object.values(def.extensions ?? {}) as { buffer?: number; byteOffset?: number }[]) {
        if (extensionDef.buffer === viewDef.buffer && (extensionDef.byteOffset ?? 0) >= start) {
          extensionDef.byteOffset = (extensionDef.byteOffset ?? 0) + pad;
        }
      }
    }
    viewDef.byteOffset = start + pad;
  }

  /** Checks every link against the document as it is now (see the class comment). */
  private planLinks(container: Uint8Array | null): Map<Primitive, PlannedLink> {
    const plan = new Map<Primitive, PlannedLink>();
    let summary: ContainerSummary | null = null;
    if (container) {
      try {
        summary = readContainerSummary(container);
      } catch (error) {
        this.warn(`the container cannot be read (${(error as Error).message}); links are written without checking their ranges`);
      }
    }
    const meshOfObject = new Map<number, Mesh>();
    const rangesOfObject = new Map<number, [number, number][]>();
    const written = new Set<BakedPrimitive>();
    const unlinked: { mesh: Mesh; prim: Primitive; where: string }[] = [];
    const objectName = (object: number) => {
      const name = summary?.objects[object]?.name;
      return name ? `object ${object} ("${name}")` : `object ${object}`;
    };

    // Whether a link to `object` over triangles [first, first + count) can be added; says why not.
    const problem = (mesh: Mesh, prim: Primitive, object: number, first: number, count: number): string | null => {
      if (!container) return 'the document has no container';
      if (prim.getMode() !== TRIANGLES) return `its mode is ${prim.getMode()}, not triangles`;
      if (summary) {
        const target = summary.objects[object];
        if (!target) return `${objectName(object)} is not in the container (${summary.objects.length} objects)`;
        if (first + count > target.triangleCount) {
          return `its triangles [${first}, ${first + count}) are not all among the ${target.triangleCount} of ${objectName(object)}`;
        }
      }
      const owner = meshOfObject.get(object);
      if (owner && owner !== mesh) return `${objectName(object)} is already drawn by mesh "${owner.getName()}"`;
      const clash = (rangesOfObject.get(object) ?? []).find(([a, b]) => first < b && a < first + count);
      if (clash) return `its triangles [${first}, ${first + count}) overlap [${clash[0]}, ${clash[1]}) of another primitive of ${objectName(object)}`;
      return null;
    };
    const accept = (mesh: Mesh, prim: Primitive, def: LinkDef, first: number, count: number) => {
      meshOfObject.set(def.object, mesh);
      const ranges = rangesOfObject.get(def.object) ?? [];
      ranges.push([first, first + count]);
      rangesOfObject.set(def.object, ranges);
      plan.set(prim, { mesh, def, first, count });
    };

    const meshes = this.document.getRoot().listMeshes();
    meshes.forEach((mesh, m) => {
      mesh.listPrimitives().forEach((prim, p) => {
        const where = `meshes[${m}] ("${mesh.getName()}").primitives[${p}]`;
        const link = prim.getExtension<BakedPrimitive>(EXT_HCE_BAKED_LIGHTING);
        if (!link) {
          unlinked.push({ mesh, prim, where });
          return;
        }
        if (written.has(link)) {
          this.warn(`${where}: a copy of a primitive that already carries the link to ${objectName(link.getObject())}; the copy's link is dropped`);
          return;
        }
        const object = link.getObject();
        const first = link.getFirstTriangle();
        const count = triangleCount(prim);
        const source = link.getSourceTriangleCount();
        const why =
          source > 0 && count !== source
            ? `it has ${count} triangles, not the ${source} it was linked with (a transform simplified, welded away or split them)`
            : problem(mesh, prim, object, first, count);
        if (why) {
          this.warn(`${where}: the link to ${objectName(object)} is dropped: ${why}`);
          return;
        }
        written.add(link);
        const def: LinkDef = { object, geometryHash: link.getGeometryHash() };
        if (first !== 0) def.firstTriangle = first;
        accept(mesh, prim, def, first, count);
      });
    });

    // Links whose primitive left the document: a join may have put their triangles, unchanged
    // and in order, into one new primitive.
    const orphans = this.listProperties().filter(
      (property): property is BakedPrimitive => property instanceof BakedPrimitive && !written.has(property),
    );
    const orphaned = orphans.filter((link) => !link.listParents().some((parent) => parent.propertyType === PropertyType.PRIMITIVE && meshes.some((mesh) => mesh.listPrimitives().includes(parent as Primitive))));
    const recovered = new Set<BakedPrimitive>();
    if (orphaned.length > 0) {
      for (const { mesh, prim, where } of unlinked) {
        const parts = coverByLinks(prim, orphaned.filter((link) => !recovered.has(link)));
        if (!parts) continue;
        const object = parts[0].getObject();
        const first = parts[0].getFirstTriangle();
        const count = triangleCount(prim);
        const why = problem(mesh, prim, object, first, count);
        const hash = geometryHash(prim);
        if (why || hash === null) {
          if (why) this.warn(`${where}: joined from primitives of ${objectName(object)}, but not linked: ${why}`);
          continue;
        }
        for (const part of parts) recovered.add(part);
        const def: LinkDef = { object, geometryHash: hash };
        if (first !== 0) def.firstTriangle = first;
        accept(mesh, prim, def, first, count);
      }
    }
    for (const link of orphaned) {
      if (recovered.has(link)) continue;
      const first = link.getFirstTriangle();
      this.warn(
        `the primitive with triangles [${first}, ${first + link.getSourceTriangleCount()}) of ${objectName(link.getObject())} ` +
          'was removed, or joined with primitives of other objects or moved by a node transform; its baked lighting is not linked',
      );
    }
    return plan;
  }
}

function isIndex(value: unknown): value is number {
  return typeof value === 'number' && Number.isInteger(value) && value >= 0;
}

/**
 * The links whose triangles, one after another, make up all of `prim`'s triangles: each link's
 * run of `sourceTriangleCount` triangles has the link's geometry hash, the links name one object
 * and their ranges follow each other in the object. Null when there are none such.
 */
function coverByLinks(prim: Primitive, links: BakedPrimitive[]): BakedPrimitive[] | null {
  if (prim.getMode() !== TRIANGLES) return null;
  const total = triangleCount(prim);
  const parts: BakedPrimitive[] = [];
  let at = 0;
  while (at < total) {
    const previous = parts[parts.length - 1];
    const next = links.find(
      (link) =>
        !parts.includes(link) &&
        link.getSourceTriangleCount() > 0 &&
        at + link.getSourceTriangleCount() <= total &&
        (!previous ||
          (link.getObject() === previous.getObject() &&
            link.getFirstTriangle() === previous.getFirstTriangle() + previous.getSourceTriangleCount())) &&
        geometryHash(prim, at, link.getSourceTriangleCount()) === link.getGeometryHash(),
    );
    if (!next) return null;
    parts.push(next);
    at += next.getSourceTriangleCount();
  }
  return parts.length > 0 ? parts : null;
}
