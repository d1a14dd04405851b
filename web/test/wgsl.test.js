// The assembly of the kernels' WGSL in JavaScript against what runtime/src/gpu/wgsl.rs and
// loop_kernel.rs do (no browser needed).
import test from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';
import { importOrder, KernelSources, loadWgsl, WgShape } from '../src/wgsl.js';
import { REPO } from './browser.js';

const GPU = path.join(REPO, 'runtime/src/gpu');

async function sources() {
  return new KernelSources(await loadWgsl(async (f) => fs.readFileSync(path.join(GPU, f), 'utf8')));
}

test('modules come once each, after the modules they import (wgsl.rs)', async () => {
  // The cases of wgsl.rs `imports_come_once_each_before_the_modules_that_import_them` and
  // `a_missing_or_circular_import_names_the_modules`.
  /** @type {Record<string, string>} */
  const files = {
    kernel: '// #import b\n// #import a\nfn main() {}\n',
    a: '  // #import c\n',
    b: '// #import c\n// #import a\n',
    c: '// imports nothing: `#import` only starts a line\n',
  };
  const text = (/** @type {string} */ m) => files[m];
  assert.deepEqual(importOrder('kernel', text), ['c', 'a', 'b', 'kernel']);
  /** @type {Record<string, string>} */
  const bad = { kernel: '// #import a\n', a: '// #import b\n', b: '// #import kernel\n', lone: '// #import hce_nothing\n' };
  const badText = (/** @type {string} */ m) => bad[m];
  assert.throws(() => importOrder('kernel', badText), { message: 'circular import: kernel -> a -> b -> kernel' });
  assert.throws(() => importOrder('lone', badText), { message: 'lone.wgsl imports hce_nothing, which is not a module (no hce_nothing.wgsl)' });
  // The kernels' modules are found through their imports, in wgsl.rs's order.
  const s = await sources();
  const shared = ['hce_constants', 'hce_bindings', 'hce_tree', 'hce_light', 'hce_lattice', 'hce_gather'];
  const files2 = await loadWgsl(async (f) => fs.readFileSync(path.join(GPU, f), 'utf8'));
  const own = (/** @type {string} */ m) => files2[`${m}.wgsl`];
  assert.deepEqual(importOrder('flat', own), [...shared, 'hce_batch', 'flat']);
  assert.deepEqual(importOrder('loop_workgroup', own), [...shared, 'loop', 'loop_workgroup']);
  assert.ok(s.flat().startsWith(fs.readFileSync(path.join(GPU, 'hce_constants.wgsl'), 'utf8')));
  // A file that is gone is named.
  await assert.rejects(
    loadWgsl(async (f) => {
      if (f === 'hce_lattice.wgsl') throw new Error(`cannot load ${f}`);
      return fs.readFileSync(path.join(GPU, f), 'utf8');
    }),
    { message: 'cannot load hce_lattice.wgsl' },
  );
});

test('the shared bindings are read from hce_bindings.wgsl', async () => {
  const b = (await sources()).bindings();
  // The numbers of bindings.rs.
  assert.deepEqual(b, {
    coarse_positions: 1, topo: 2, hce_records: 3, hce_bits: 4, hce_normals: 5, hce_colours: 6,
    out_positions: 7, out_indices: 8, out_faces: 9, out_colours: 10, hce_light: 11,
    out_normals: 12, scratch: 13,
  });
});

test('the normals template is instantiated once per patch memory', async () => {
  const s = await sources();
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
