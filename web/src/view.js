// Cameras, as the Rust runtime frames and projects them (runtime/src/gpu/render.rs
// `view_projection` and `auto_camera`, framing.rs `auto_scene_camera`, scene.rs
// `resolve_camera`), and the level-of-detail rule of lod.rs `choose_level`, so that the page
// and `hce render` see a file through the same camera and refine it to the same levels.
import { add, cross, dot, length, normalize, scale, sub, transformPoint, maxScale, transformBounds, unionBounds } from './math.js';

/**
 * @typedef {import('./math.js').Vec3} Vec3
 * @typedef {import('./math.js').Bounds} Bounds
 * @typedef {{ eye: number[], target: number[], fovYDegrees: number }} Camera
 * @typedef {{ targetPixelsPerEdge: number, minLevel: number, maxLevel: number }} LodParams
 */

/** lod.rs `LodParams::default`. */
export const DEFAULT_LOD = Object.freeze({ targetPixelsPerEdge: 8, minLevel: 0, maxLevel: 5 });

const f32 = Math.fround;
/** @param {number} deg */
const radians = (deg) => (deg * Math.PI) / 180;

/**
 * The level at which an object's coarse edges cover about `targetPixelsPerEdge` pixels on a
 * viewport `viewportHeight` pixels high (lod.rs `choose_level`).
 * @param {Bounds} bounds world bounds of the instance
 * @param {number} meanEdgeLength in world units
 * @param {Camera} camera
 * @param {number} viewportHeight
 * @param {LodParams} [lod]
 */
export function chooseLevel(bounds, meanEdgeLength, camera, viewportHeight, lod = DEFAULT_LOD) {
  const centre = [0, 1, 2].map((k) => 0.5 * (bounds.min[k] + bounds.max[k]));
  const radius = 0.5 * length(sub(bounds.max, bounds.min));
  const d = Math.max(length(sub(camera.eye, centre)) - radius, 1e-6 * Math.max(radius, 1e-12));
  const halfFov = radians(Math.min(Math.max(camera.fovYDegrees, 1), 179) * 0.5);
  const pixelsPerUnit = viewportHeight / (2 * d * Math.tan(halfFov));
  const ratio = f32((meanEdgeLength * pixelsPerUnit) / Math.max(lod.targetPixelsPerEdge, 1e-3));
  let level;
  if (Number.isFinite(ratio) && ratio > 1) level = Math.ceil(Math.log2(ratio));
  else if (Number.isFinite(ratio)) level = 0;
  else level = lod.maxLevel;
  return Math.min(Math.max(level, lod.minLevel), Math.max(lod.maxLevel, lod.minLevel));
}

/**
 * The level of an object over all its instances: the largest (scene.rs `level_for`).
 * @param {import('./native.js').AssetObject} o
 * @param {Camera} camera
 * @param {number} viewportHeight
 * @param {LodParams} [lod]
 */
export function objectLevel(o, camera, viewportHeight, lod = DEFAULT_LOD) {
  let level = -1;
  for (const inst of o.instances) {
    const b = transformBounds(o.bounds, inst.transform);
    level = Math.max(level, chooseLevel(b, o.meanEdgeLength * maxScale(inst.transform), camera, viewportHeight, lod));
  }
  return level < 0 ? lod.minLevel : level;
}

/**
 * World bounds of everything drawn, or null when nothing is.
 * @param {import('./native.js').Asset} asset
 * @returns {Bounds | null}
 */
export function assetBounds(asset) {
  /** @type {Bounds | null} */
  let out = null;
  for (const o of asset.objects) {
    for (const inst of o.instances) {
      const b = transformBounds(o.bounds, inst.transform);
      out = out === null ? b : unionBounds(out, b);
    }
  }
  return out;
}

/**
 * The camera of `Framing::Auto`: the bounds' sphere fitted in the narrower field of view
 * (render.rs `auto_camera`).
 * @param {Bounds} b @param {number} aspect @returns {Camera}
 */
export function autoCamera(b, aspect) {
  const fov = 40;
  const centre = scale(add(b.min, b.max), 0.5);
  const radius = Math.max(length(sub(b.max, b.min)) * 0.5, 1e-6);
  const halfV = radians(fov * 0.5);
  const halfH = Math.atan(Math.tan(halfV) * Math.min(aspect, 1));
  const distance = (1.1 * radius) / Math.sin(halfH);
  const dir = normalize([0.55, 0.45, 1]);
  return { eye: add(centre, scale(dir, distance)), target: centre, fovYDegrees: fov };
}

/**
 * Möller–Trumbore: whether the ray from `o` along `d` hits triangle `t` ahead.
 * @param {number[]} o @param {number[]} d @param {number[][]} t
 */
function rayHits(o, d, t) {
  const e1 = sub(t[1], t[0]);
  const e2 = sub(t[2], t[0]);
  const p = cross(d, e2);
  const det = dot(e1, p);
  if (Math.abs(det) < 1e-12) return false;
  const inv = 1 / det;
  const s = sub(o, t[0]);
  const u = dot(s, p) * inv;
  if (u < 0 || u > 1) return false;
  const q = cross(s, e1);
  const v = dot(d, q) * inv;
  if (v < 0 || u + v > 1) return false;
  return dot(e2, q) * inv > 0;
}

/**
 * The automatic camera of a scene (framing.rs `auto_scene_camera`): inside a closed room, in
 * front of a box open on one side, else from outside.
 * @param {import('./native.js').Asset} asset
 * @param {Bounds} b world bounds
 * @param {number} aspect
 * @returns {{ camera: Camera, placement: 'outside' | 'inside' | 'opening' }}
 */
export function autoSceneCamera(asset, b, aspect) {
  /** @type {number[][][]} */
  const triangles = [];
  for (const o of asset.objects) {
    const m = o.object.mesh;
    for (const inst of o.instances) {
      for (let t = 0; t < m.triangles.length; t += 3) {
        triangles.push([0, 1, 2].map((c) => transformPoint(inst.transform, Array.from(m.positions.subarray(3 * m.triangles[t + c], 3 * m.triangles[t + c] + 3)))));
      }
    }
  }
  const hits = (/** @type {number[]} */ o, /** @type {number[]} */ d) => triangles.some((t) => rayHits(o, d, t));
  const centre = scale(add(b.min, b.max), 0.5);
  const size = sub(b.max, b.min);
  const open = [[1, 0, 0], [-1, 0, 0], [0, 0, 1], [0, 0, -1]].filter((d) => !hits(centre, d));
  const floorAndCeiling = hits(centre, [0, 1, 0]) && hits(centre, [0, -1, 0]);
  if (!floorAndCeiling || open.length > 1 || Math.min(...size) <= 0) return { camera: autoCamera(b, aspect), placement: 'outside' };
  if (open.length === 1) {
    const out = open[0];
    const fov = 40;
    const tanV = Math.tan(radians(fov * 0.5));
    const halfW = 0.5 * (out[0] !== 0 ? size[2] : size[0]);
    const halfH = 0.5 * size[1];
    const depth = 0.5 * dot(out.map(Math.abs), size);
    const distance = 1.05 * Math.max(halfH / tanV, halfW / (tanV * Math.max(aspect, 1e-3)));
    return { camera: { eye: add(centre, scale(out, depth + distance)), target: centre, fovYDegrees: fov }, placement: 'opening' };
  }
  const axis = size[0] > size[2] ? [1, 0, 0] : [0, 0, 1];
  const half = 0.5 * dot(axis, size);
  const eye = add(centre, scale(axis, 0.9 * half));
  eye[1] = b.min[1] + 0.55 * size[1];
  const target = sub(centre, scale(axis, half));
  target[1] = b.min[1] + 0.4 * size[1];
  return { camera: { eye, target, fovYDegrees: 65 }, placement: 'inside' };
}

/**
 * The file's camera, else the automatic one (scene.rs `resolve_camera`, `SceneOrAuto`).
 * @param {import('./native.js').Asset} asset
 * @param {number} aspect
 * @param {'scene-or-auto' | 'auto'} [choice]
 * @returns {{ camera: Camera, source: string } | null} null when nothing is drawn
 */
export function resolveCamera(asset, aspect, choice = 'scene-or-auto') {
  const b = assetBounds(asset);
  if (b === null) return null;
  const c = asset.camera;
  if (c && choice === 'scene-or-auto') {
    const reach = Math.max(0.5 * length(sub(b.max, b.min)), 1e-3);
    return { camera: { eye: c.eye, target: add(c.eye, scale(c.forward, reach)), fovYDegrees: c.fovYDegrees }, source: `the file's camera '${c.name}'` };
  }
  const auto = autoSceneCamera(asset, b, aspect);
  return { camera: auto.camera, source: `an automatic camera (${auto.placement})` };
}

/**
 * View-projection matrix (column-major, WebGPU clip space, depth 0..1) of `camera`, with the
 * near and far planes around the bounds (render.rs `view_projection`).
 * @param {Camera} camera @param {Bounds} b @param {number} aspect
 * @returns {number[]}
 */
export function viewProjection(camera, b, aspect) {
  const eye = camera.eye;
  let forward = normalize(sub(camera.target, eye));
  if (length(forward) === 0) forward = [0, 0, -1];
  const up = length(cross(forward, [0, 1, 0])) < 1e-4 ? [0, 0, 1] : [0, 1, 0];
  const centre = scale(add(b.min, b.max), 0.5);
  const radius = Math.max(length(sub(b.max, b.min)) * 0.5, 1e-6);
  const d = length(sub(centre, eye));
  const near = Math.max((d - radius) * 0.5, radius * 1e-4);
  const far = (d + radius) * 1.5 + near;
  const f = 1 / Math.tan(radians(Math.min(Math.max(camera.fovYDegrees, 1), 179)) * 0.5);
  const proj = [f / aspect, 0, 0, 0, 0, f, 0, 0, 0, 0, far / (near - far), -1, 0, 0, (near * far) / (near - far), 0];
  const s = normalize(cross(forward, up));
  const u = cross(s, forward);
  const view = [s[0], u[0], -forward[0], 0, s[1], u[1], -forward[1], 0, s[2], u[2], -forward[2], 0, -dot(s, eye), -dot(u, eye), dot(forward, eye), 1];
  const out = new Array(16).fill(0);
  for (let c = 0; c < 4; c++) for (let r = 0; r < 4; r++) for (let k = 0; k < 4; k++) out[4 * c + r] += proj[4 * k + r] * view[4 * c + k];
  return out;
}
