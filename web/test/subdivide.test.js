// Test (b), the baked samples: every object of Teatime, the Cornell box (its short block
// multiresolution) and Chesstime, baked by the workspace's hce, refined in Chromium at levels
// 0 to 3 (flat objects too, uniformly) and with flat objects drawn from their trees (F.7.1)
// against `hce subdivide --merge` of the same level and `--flat`:
// the same vertex and triangle counts and indices; positions within 1e-5 of each object's
// bounding-box diagonal and normals within 1e-5 (SPEC.md F.1); colours (hce writes them clamped
// to [0, 1]) within 1e-4 of the vertex's brightest channel (G). The Cornell box also as a
// .gltf with an external buffer.
import test from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { openBrowser, hceBinary, REPO } from './browser.js';
import { SAMPLES, bakedSample, runHce } from './samples.js';

test('the baked samples refine in Chromium as hce subdivide refines them', { timeout: 900_000 }, async (t) => {
  const hce = hceBinary(t);
  if (!hce) return;
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'hce-subdivide-'));
  const b = await openBrowser(t, { '/files/': dir });
  if (!b) return;
  try {
    await b.page.goto(`${b.url}/web/test/pages/compare.html`);
    for (const [name] of SAMPLES) {
      const baked = bakedSample(hce, name);
      fs.copyFileSync(baked, path.join(dir, `${name}.glb`));
      // Flat objects uniformly at levels 0 to 3, then from their trees (SPEC.md F.7.1, what
      // `hce subdivide` writes by default and the viewer draws) beside Loop objects at level 2.
      for (const [level, flat] of /** @type {[number, string][]} */ ([[0, 'uniform'], [1, 'uniform'], [2, 'uniform'], [3, 'uniform'], [2, 'adaptive']])) {
        const ref = `${name}-${level}-${flat}.glb`;
        runHce(hce, ['subdivide', baked, '--level', String(level), '--flat', flat, '--merge', '-o', path.join(dir, ref)]);
        /** @type {any} */
        const r = await b.page.evaluate(([u, l, rf, fl]) => /** @type {any} */ (window).hceCompare(u, l, rf, fl), [`/files/${name}.glb`, level, `/files/${ref}`, flat]);
        const at = `${name} level ${level}, flat ${flat}`;
        assert.ok(r.ok, `${at}: ${r.error}`);
        assert.equal(r.lost, null, `${at}: the device was lost or reported an error`);
        assert.equal(r.totalVertices, r.refVertices, `${at}: vertex count`);
        assert.equal(r.totalTriangles, r.refTriangles, `${at}: triangle count`);
        for (const o of r.objects) {
          const where = `${at} '${o.name}' (${o.kind})`;
          assert.ok(o.indicesEqual, `${where}: indices`);
          assert.ok(o.maxPosition <= 1e-5 * o.diagonal, `${where}: positions differ by ${o.maxPosition} (diagonal ${o.diagonal})`);
          if (o.kind === 'multiresolution') assert.ok(o.maxNormal <= 1e-5, `${where}: normals differ by ${o.maxNormal}`);
          assert.equal(o.colourOver, 0, `${where}: ${o.colourOver} vertex colours differ by more than 1e-4 of their brightest channel (worst ${o.maxColour})`);
        }
        t.diagnostic(`${at}: ${r.objects.length} objects, ${r.totalVertices} vertices agree; worst colour ${Math.max(...r.objects.map((/** @type {any} */ o) => o.maxColour)).toExponential(2)}, refined in ${r.totalMs.toFixed(0)} ms`);
      }
    }
    // A .gltf with its buffer in a .bin beside it, as `hce bake -o x.gltf` writes it.
    const gltf = path.join(dir, 'cornell.gltf');
    runHce(hce, ['bake', path.join(REPO, 'samples/cornell-box.glb'), '-o', gltf, '--multires', 'short_block', '--creases', 'auto', '-q']);
    assert.ok(fs.existsSync(path.join(dir, 'cornell.bin')), 'the .gltf has an external buffer');
    runHce(hce, ['subdivide', gltf, '--level', '2', '--flat', 'uniform', '--merge', '-o', path.join(dir, 'cornell-gltf-2.glb')]);
    /** @type {any} */
    const g = await b.page.evaluate(() => /** @type {any} */ (window).hceCompare('/files/cornell.gltf', 2, '/files/cornell-gltf-2.glb'));
    assert.ok(g.ok, `cornell.gltf: ${g.error}`);
    assert.equal(g.totalVertices, g.refVertices);
    for (const o of g.objects) {
      assert.ok(o.indicesEqual && o.maxPosition <= 1e-5 * o.diagonal && o.colourOver === 0, `cornell.gltf '${o.name}': ${JSON.stringify(o)}`);
    }
    t.diagnostic(`cornell.gltf (external buffer) level 2: ${g.objects.length} objects, ${g.totalVertices} vertices agree`);
    assert.deepEqual(b.pageErrors, []);
  } finally {
    await b.close();
    fs.rmSync(dir, { recursive: true, force: true });
  }
});
