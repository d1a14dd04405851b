// The level-of-detail rule, flat objects' level and the automatic camera against the values of
// the Rust unit tests (runtime/src/gpu/lod.rs, scene.rs, framing.rs), in node.
import test from 'node:test';
import assert from 'node:assert/strict';
import { chooseLevel, DEFAULT_LOD, autoCamera, viewProjection } from '../src/view.js';
import { flatLevel } from '../src/scene.js';

const cameraAt = (/** @type {number} */ z) => ({ eye: [0, 0, z], target: [0, 0, 0], fovYDegrees: 90 });
/** @type {import('../src/math.js').Bounds} */
const cube = { min: [-1, -1, -1], max: [1, 1, 1] };

test('the level follows choose_level and drops with distance', () => {
  const d = 10 - Math.sqrt(3);
  const expected = Math.ceil(Math.log2(250 / d / 8));
  assert.equal(expected, 2);
  assert.equal(chooseLevel(cube, 0.5, cameraAt(10), 1000), expected);
  const near = chooseLevel(cube, 0.5, cameraAt(3), 1000);
  const far = chooseLevel(cube, 0.5, cameraAt(1000), 1000);
  assert.ok(near > expected && far === 0, `near ${near} far ${far}`);
  assert.equal(chooseLevel(cube, 0.5, cameraAt(0.5), 1000), DEFAULT_LOD.maxLevel);
});

test('flat objects go to their tree depth within the triangle bound, as scene.rs flat_level', () => {
  for (const [depth, coarse, level] of [
    [0, 2, 0], [5, 2, 5], [7, 10000, 7], // shallow trees: the tree depth, whatever the size
    [9, 2, 9], [12, 2, 10], [12, 1, 11], [8, 3, 8], // a room's floor split along a contact shadow
    [8, 44, 8], [9, 44, 8], // Teatime's table
    [9, 300, 7], // many triangles: level 7, no deeper
  ]) assert.equal(flatLevel(depth, coarse), level, `depth ${depth}, ${coarse} triangles`);
});

test('the automatic camera frames the bounds and projects the centre to the middle', () => {
  const c = autoCamera(cube, 4 / 3);
  assert.deepEqual(c.target, [0, 0, 0]);
  assert.equal(c.fovYDegrees, 40);
  // The eye is outside the bounding sphere, along (0.55, 0.45, 1).
  const dist = Math.hypot(...c.eye);
  assert.ok(dist > Math.sqrt(3) * 1.1, `${dist}`);
  assert.ok(Math.abs(c.eye[0] / c.eye[2] - 0.55) < 1e-9 && Math.abs(c.eye[1] / c.eye[2] - 0.45) < 1e-9);
  const m = viewProjection(c, cube, 4 / 3);
  // Clip coordinates of the target: x = y = 0, depth inside 0..1.
  const clip = [0, 1, 2, 3].map((r) => m[12 + r]);
  assert.ok(Math.abs(clip[0] / clip[3]) < 1e-9 && Math.abs(clip[1] / clip[3]) < 1e-9);
  assert.ok(clip[2] / clip[3] > 0 && clip[2] / clip[3] < 1);
});
