// The path without WebGPU, refinement: in a Chromium with WebGPU switched off, every object of
// Teatime and the Cornell box, baked by the workspace's hce, refined on the CPU in
// hce.wasm (cpu_refine.js) at levels 1 and 2 (flat objects uniformly) and with flat objects
// from their trees (SPEC.md F.7.1) against `hce subdivide --merge` of the same file, level and
// `--flat`: positions and normals bit-identical, the same indices, and the colours (hce writes
// them clamped to [0, 1]) equal once clamped. The same Rust runs on both sides, so anything
// short of equality is a bug in the frames between them.
import test from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { openBrowser, hceBinary } from './browser.js';
import { bakedSample, runHce } from './samples.js';

test('without WebGPU, the CPU refinement is hce subdivide\'s bit for bit', { timeout: 900_000 }, async (t) => {
  const hce = hceBinary(t);
  if (!hce) return;
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'hce-cpu-refine-'));
  const b = await openBrowser(t, { '/files/': dir }, { webgpu: false });
  if (!b) return;
  try {
    await b.page.goto(`${b.url}/web/test/pages/cpu.html`);
    for (const name of ['teatime', 'cornell-box']) {
      const baked = bakedSample(hce, name);
      fs.copyFileSync(baked, path.join(dir, `${name}.glb`));
      for (const [level, flat] of /** @type {[number, string][]} */ ([[1, 'uniform'], [2, 'uniform'], [2, 'adaptive']])) {
        const ref = `${name}-${level}-${flat}.glb`;
        runHce(hce, ['subdivide', baked, '--level', String(level), '--flat', flat, '--merge', '-o', path.join(dir, ref)]);
        /** @type {any} */
        const r = await b.page.evaluate(([u, l, rf, fl]) => /** @type {any} */ (window).hceCpuCompare(u, l, rf, fl), [`/files/${name}.glb`, level, `/files/${ref}`, flat]);
        const at = `${name} level ${level}, flat ${flat}`;
        assert.ok(r.ok, `${at}: ${r.error}`);
        assert.equal(r.webgpu, false, 'the page gets no WebGPU adapter');
        assert.equal(r.totalVertices, r.refVertices, `${at}: vertex count`);
        assert.equal(r.totalTriangles, r.refTriangles, `${at}: triangle count`);
        for (const o of r.objects) {
          const where = `${at} '${o.name}' (${o.kind})`;
          assert.equal(o.positionsDiffer, 0, `${where}: ${o.positionsDiffer} position words differ`);
          assert.equal(o.normalsDiffer, 0, `${where}: ${o.normalsDiffer} normal words differ`);
          assert.equal(o.indicesDiffer, 0, `${where}: ${o.indicesDiffer} indices differ`);
          assert.equal(o.coloursDiffer, 0, `${where}: ${o.coloursDiffer} colour channels differ`);
        }
        t.diagnostic(`${at}: ${r.objects.length} objects, ${r.totalVertices} vertices, ${r.totalTriangles} triangles bit-identical; refined in ${r.ms.toFixed(0)} ms`);
      }
    }
    assert.deepEqual(b.pageErrors, []);
  } finally {
    await b.close();
    fs.rmSync(dir, { recursive: true, force: true });
  }
});
