// The assembly of the kernels' WGSL in JavaScript against what runtime/src/gpu/wgsl.rs and
// loop_kernel.rs do (no browser needed).
import test from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';
import { KernelSources, WGSL_FILES, WgShape } from '../src/wgsl.js';
import { REPO } from './browser.js';

function sources() {
  /** @type {Record<string, string>} */
  const files = {};
  for (const f of WGSL_FILES) files[f] = fs.readFileSync(path.join(REPO, 'runtime/src/gpu', f), 'utf8');
  return new KernelSources(files);
}

test('the normals template is instantiated once per patch memory', () => {
  const s = sources();
  const scratch = s.loop();
  const workgroup = s.loopWorkgroup('');
  for (const src of [scratch, workgroup]) {
    assert.ok(!src.includes('{patch}'));
    assert.equal(src.split('fn grid_normal(').length - 1, 1);
    assert.equal(src.split('fn corner_normal(').length - 1, 1);
  }
  assert.equal(scratch.split('fn wg_grid_normal(').length - 1, 0);
  assert.equal(workgroup.split('fn wg_grid_normal(').length - 1, 1);
  // The shared modules come first, in wgsl.rs's order.
  const flat = s.flat();
  const at = (/** @type {string} */ needle) => flat.indexOf(needle);
  assert.ok(at('fn hce_light_eval(') > 0 && at('fn hce_light_eval(') < at('fn vertex_colour(') && at('fn vertex_colour(') < at('fn positions_main('));
});

test('workgroup shapes are those of loop_kernel.rs', () => {
  // The values of loop_kernel.rs `workgroup_shapes_fit_the_webgpu_limit`.
  const limit = 16384;
  const s = WgShape.fit(5, 24, limit);
  assert.ok(s);
  assert.deepEqual([s.tris, s.squareA, s.squareB, s.ring], [1, 1998, 630, 72]);
  assert.equal(s.bytes(), 4 * (1998 + 630 + 2 * 72) + 96);
  assert.equal(WgShape.fit(5, 240, limit)?.bytes(), 16368);
  assert.equal(WgShape.fit(5, 248, limit), null);
  assert.equal(WgShape.fit(1, 24, limit)?.tris, 8);
  assert.equal(WgShape.fit(1, 200, limit)?.tris, 2);
  assert.equal(WgShape.fit(0, 24, limit)?.squareB, 0);
  assert.equal(WgShape.fit(6, 24, limit), null);
  assert.equal(s.header(), 'const WG_LEVEL: u32 = 5u;\nconst WG_TRIS: u32 = 1u;\nconst WG_SQ_A: u32 = 1998u;\nconst WG_SQ_B: u32 = 630u;\nconst WG_RING: u32 = 72u;\n');
});
