// Column-major 4×4 matrices (glTF's and WGSL's layout) and 3-vectors, in plain arrays.

/** @typedef {number[]} Mat4 16 numbers, column-major */
/** @typedef {[number, number, number]} Vec3 */

/** @returns {Mat4} */
export const identity = () => [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1];

/** @param {Mat4} a @param {Mat4} b @returns {Mat4} a · b */
export function multiply(a, b) {
  const out = new Array(16).fill(0);
  for (let c = 0; c < 4; c++) {
    for (let r = 0; r < 4; r++) {
      let s = 0;
      for (let k = 0; k < 4; k++) s += a[4 * k + r] * b[4 * c + k];
      out[4 * c + r] = s;
    }
  }
  return out;
}

/**
 * T · R · S from a glTF node's translation, rotation (x, y, z, w) and scale.
 * @param {number[]} t @param {number[]} q @param {number[]} s
 * @returns {Mat4}
 */
export function fromTrs(t, q, s) {
  const [x, y, z, w] = q;
  const [x2, y2, z2] = [x + x, y + y, z + z];
  const [xx, xy, xz] = [x * x2, x * y2, x * z2];
  const [yy, yz, zz] = [y * y2, y * z2, z * z2];
  const [wx, wy, wz] = [w * x2, w * y2, w * z2];
  return [
    (1 - (yy + zz)) * s[0], (xy + wz) * s[0], (xz - wy) * s[0], 0,
    (xy - wz) * s[1], (1 - (xx + zz)) * s[1], (yz + wx) * s[1], 0,
    (xz + wy) * s[2], (yz - wx) * s[2], (1 - (xx + yy)) * s[2], 0,
    t[0], t[1], t[2], 1,
  ];
}

/** @param {Mat4} m @param {number[]} p @returns {Vec3} */
export const transformPoint = (m, p) => [
  m[0] * p[0] + m[4] * p[1] + m[8] * p[2] + m[12],
  m[1] * p[0] + m[5] * p[1] + m[9] * p[2] + m[13],
  m[2] * p[0] + m[6] * p[1] + m[10] * p[2] + m[14],
];

/** @param {Mat4} m @param {number[]} v @returns {Vec3} */
export const transformVector = (m, v) => [
  m[0] * v[0] + m[4] * v[1] + m[8] * v[2],
  m[1] * v[0] + m[5] * v[1] + m[9] * v[2],
  m[2] * v[0] + m[6] * v[1] + m[10] * v[2],
];

/** @param {number[]} a @param {number[]} b */
export const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
/** @param {number[]} a @param {number[]} b @returns {Vec3} */
export const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
/** @param {number[]} a @param {number[]} b @returns {Vec3} */
export const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
/** @param {number[]} a @param {number[]} b @returns {Vec3} */
export const add = (a, b) => [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
/** @param {number[]} a @param {number} s @returns {Vec3} */
export const scale = (a, s) => [a[0] * s, a[1] * s, a[2] * s];
/** @param {number[]} a */
export const length = (a) => Math.sqrt(dot(a, a));
/** @param {number[]} a @returns {Vec3} */
export function normalize(a) {
  const l = length(a);
  return l > 0 ? [a[0] / l, a[1] / l, a[2] / l] : [0, 0, 0];
}

/** The largest scale of a transform's three axes. @param {Mat4} m */
export const maxScale = (m) => Math.max(length([m[0], m[1], m[2]]), length([m[4], m[5], m[6]]), length([m[8], m[9], m[10]]));

/**
 * @typedef {{ min: Vec3, max: Vec3 }} Bounds
 */

/** @param {Bounds} b @param {Mat4} m @returns {Bounds} the box around the transformed corners */
export function transformBounds(b, m) {
  const lo = /** @type {Vec3} */ ([Infinity, Infinity, Infinity]);
  const hi = /** @type {Vec3} */ ([-Infinity, -Infinity, -Infinity]);
  for (let i = 0; i < 8; i++) {
    const p = transformPoint(m, [i & 1 ? b.max[0] : b.min[0], i & 2 ? b.max[1] : b.min[1], i & 4 ? b.max[2] : b.min[2]]);
    for (let k = 0; k < 3; k++) {
      lo[k] = Math.min(lo[k], p[k]);
      hi[k] = Math.max(hi[k], p[k]);
    }
  }
  return { min: lo, max: hi };
}

/** @param {Bounds} a @param {Bounds} b @returns {Bounds} */
export const unionBounds = (a, b) => ({
  min: [Math.min(a.min[0], b.min[0]), Math.min(a.min[1], b.min[1]), Math.min(a.min[2], b.min[2])],
  max: [Math.max(a.max[0], b.max[0]), Math.max(a.max[1], b.max[1]), Math.max(a.max[2], b.max[2])],
});
