// The three.js GLTFLoader plugin: on a WebGPURenderer's own device, every linked primitive of
// a baked glTF gets its refined surface with the baked lighting as vertex colours, at the
// requested level (flat objects at their tree depth), agreeing with the conformance manifest.
import test from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';
import { openBrowser, REPO } from './browser.js';

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
    // The Cornell box: eight flat objects, each at its tree depth.
    /** @type {any} */
    const box = await b.page.evaluate(() => /** @type {any} */ (window).hceThree('/conformance/valid/cornell-box.glb', 3));
    assert.ok(box.ok, box.error);
    assert.equal(box.meshes.length, 8);
    const cornell = manifest.cases.find((/** @type {any} */ c) => c.file === 'valid/cornell-box.glb');
    for (const mesh of box.meshes) {
      assert.ok(mesh.hce, `${mesh.name} refined`);
      const r = box.report.find((/** @type {any} */ x) => x.name === mesh.hce.object);
      assert.equal(mesh.indices, 3 * r.triangles);
      const level1 = cornell.refined.find((/** @type {any} */ x) => x.name === mesh.hce.object && x.level === 1);
      // The coarse triangle count, from the manifest's level 1 (four per coarse triangle).
      assert.equal(r.triangles, (level1.triangle_count / 4) * 4 ** mesh.hce.level, mesh.name);
      assert.ok(mesh.colour0.slice(0, 3).some((/** @type {number} */ x) => x > 0), `${mesh.name} is lit`);
    }
    assert.deepEqual(b.pageErrors, []);
  } finally {
    await b.close();
  }
});
