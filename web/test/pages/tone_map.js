// Test: present.wgsl's curve on one linear channel, to 8 bits (exposure 0, the ACES fit, sRGB),
// which the drawing pages apply to what they read back from a float render target.
/** @param {number} c */
export function toneMap(c) {
  const x = Math.max(c, 0);
  const y = Math.min(Math.max((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0), 1);
  const s = y <= 0.0031308 ? 12.92 * y : 1.055 * y ** (1 / 2.4) - 0.055;
  return Math.round(255 * s);
}
