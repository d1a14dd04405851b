// The three.js GLTFLoader plugin: on a WebGPURenderer's own device, every linked primitive of
// a baked glTF gets its refined surface with the baked lighting as vertex colours, at the
// requested level (flat objects from their trees, or at their tree depth on asking), agreeing
// with the conformance manifest and `hce subdivide`.
import test from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';
import os from 'node:os';
import { openBrowser, hceBinary, REPO } from './browser.js';
import { runHce } from './samples.js';

const manifest = JSON.parse(fs.readFileSync(path.join(REPO, 'conformance/manifest.json'), 'utf8'));

test('the three.js plugin refines and colours every linked mesh on three.js\'s device', { timeout: 300_000 }, async (t) => {
  const b = await openBrowser(t, { '/conformance/': path.join(REPO, 'conformance') });
  if (!b) return;
  try {
    await b.page.goto(`${b.url}/web/test/pages/three.html`);
    // A multiresolution triangle at level 2 against the manifest.
    /** @type {any} */
    const tri = await b.page.evaluate(() => /** @type {any} */ (window).hceThree('/conformance/valid/triangle.glb', 2));
    assert.ok(tri.ok, tri.error);
    assert.ok(tri.sameDevice, 'the kernels run on the renderer\'s device');
    const want = manifest.cases.find((/** @type {any} */ c) => c.file === 'valid/triangle.glb').refined.find((/** @type {any} */ r) => r.level === 2);
    assert.equal(tri.meshes.length, 1);
    const m = tri.meshes[0];
    assert.deepEqual(m.hce, { object: want.name, level: 2 });
    assert.equal(m.vertices, want.vertex_count);
    assert.equal(m.indices, 3 * want.triangle_count);
    assert.ok(m.vertexColors && m.unlit && m.hasColour);
    const probe = want.probes.find((/** @type {any} */ p) => p.vertex === 0);
    assert.deepEqual(m.colour0.slice(0, 3).map((/** @type {number} */ x) => Math.round(x * 1e5)), probe.colour_smooth.xyz.map((/** @type {number} */ x) => Math.round(x * 1e5)));
    // The Cornell box: eight flat objects, drawn from their trees (SPEC.md F.7.1) with the
    // triangles `hce subdivide` (adaptive, its default) gives them, then uniformly at their tree
    // depth on asking.
    const cornell = manifest.cases.find((/** @type {any} */ c) => c.file === 'valid/cornell-box.glb');
    const hce = hceBinary(t);
    if (!hce) return;
    /** @type {Map<string, number>} */
    const adaptiveTriangles = new Map();
    const stats = runHce(hce, ['subdivide', path.join(REPO, 'conformance/valid/cornell-box.glb'), '--stats', '-o', path.join(os.tmpdir(), `hce-three-${process.pid}.glb`)]);
    for (const m of stats.matchAll(/^object '([^']+)' \(flat, adaptive\): \d+ vertices, (\d+) triangles$/gm)) adaptiveTriangles.set(m[1], Number(m[2]));
    assert.equal(adaptiveTriangles.size, 8, stats);
    for (const flat of ['adaptive', 'uniform']) {
      /** @type {any} */
      const box = await b.page.evaluate(([f]) => /** @type {any} */ (window).hceThree('/conformance/valid/cornell-box.glb', 3, f), [flat]);
      assert.ok(box.ok, box.error);
      assert.equal(box.meshes.length, 8);
      for (const mesh of box.meshes) {
        assert.ok(mesh.hce, `${mesh.name} refined`);
        const r = box.report.find((/** @type {any} */ x) => x.name === mesh.hce.object);
        assert.equal(mesh.indices, 3 * r.triangles);
        assert.equal(r.adaptive, flat === 'adaptive');
        if (flat === 'adaptive') {
          assert.equal(mesh.hce.level, 0, `${mesh.name}: an adaptive refinement has no level`);
          assert.equal(r.triangles, adaptiveTriangles.get(mesh.hce.object), mesh.name);
        } else {
          const level1 = cornell.refined.find((/** @type {any} */ x) => x.name === mesh.hce.object && x.level === 1);
          // The coarse triangle count, from the manifest's level 1 (four per coarse triangle).
          assert.equal(r.triangles, (level1.triangle_count / 4) * 4 ** mesh.hce.level, mesh.name);
        }
        assert.ok(mesh.lit > 0.5, `${mesh.name} is lit (${(100 * mesh.lit).toFixed(1)}% of its vertices)`);
      }
      t.diagnostic(`Cornell box, flat ${flat}: ${box.report.map((/** @type {any} */ x) => `${x.name} ${x.triangles}`).join(', ')}`);
    }
    // Level of detail: `level: 'auto'` and `plugin.update(camera, height)` each frame. The
    // triangle (one multiresolution object) from near, from far, from far again and near
    // again: its level follows the distance, only a change refines, and the drawn triangles
    // are those of the level.
    /** @type {any} */
    const lod = await b.page.evaluate(() => /** @type {any} */ (window).hceThreeLod('/conformance/valid/triangle.glb', [0.4, 40, 40, 0.4]));
    assert.ok(lod.ok, lod.error);
    const levels = lod.steps.map((/** @type {any} */ s) => s.report[0].level);
    t.diagnostic(`triangle.glb with level 'auto': levels ${levels.join(', ')} at distances ${lod.steps.map((/** @type {any} */ s) => s.distance).join(', ')}; refined ${lod.steps.map((/** @type {any} */ s) => s.refined).join(', ')}; pixels drawn ${lod.steps.map((/** @type {any} */ s) => s.drawn).join(', ')}`);
    assert.ok(levels[0] > levels[1], `nearer is finer: ${levels}`);
    assert.equal(levels[2], levels[1]);
    assert.equal(levels[3], levels[0]);
    assert.deepEqual(lod.steps.map((/** @type {any} */ s) => s.refined), [1, 1, 0, 1]);
    for (const step of lod.steps) {
      const m = step.meshes[0];
      assert.equal(m.hce.level, step.report[0].level);
      assert.equal(m.indices, 3 * 4 ** m.hce.level, `distance ${step.distance}: the triangles of level ${m.hce.level}`);
      assert.ok(m.lit > 0.99, `distance ${step.distance}: lit`);
      assert.equal(step.report[0].path, 'gpu');
      assert.ok(step.drawn > 0, `distance ${step.distance}: the frame shows the triangle`);
    }
    assert.deepEqual(b.pageErrors, []);
  } finally {
    await b.close();
  }
});
