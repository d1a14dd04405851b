// Test (b): the browser runtime's refined meshes against hce's. For every valid file of
// conformance/, at levels 0 to 3, both reconstructions: vertex and triangle counts exactly,
// and the manifest's probe vertices within SPEC.md's tolerances: positions within 1e-5 of the
// refined object's bounding-box diagonal and normals within 1e-5 per component (F.1), colours
// within 1e-4 of the vertex's brightest channel (G: a GPU's colours against the CPU
// reference's). Level 0 is the control mesh itself, bit for bit.
import test from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';
import { openBrowser, REPO } from './browser.js';

const manifest = JSON.parse(fs.readFileSync(path.join(REPO, 'conformance/manifest.json'), 'utf8'));
// Valid files with a warning (a Draco primitive that cannot be checked) are refused by the
// strict loader, as by `hce subdivide`: loader.test.js checks that.
const valid = manifest.cases.filter((/** @type {any} */ c) => c.valid && !c.warnings);

/** @param {number[]} positions */
function diagonal(positions) {
  const lo = [Infinity, Infinity, Infinity];
  const hi = [-Infinity, -Infinity, -Infinity];
  for (let i = 0; i < positions.length; i += 3) {
    for (let k = 0; k < 3; k++) {
      lo[k] = Math.min(lo[k], positions[i + k]);
      hi[k] = Math.max(hi[k], positions[i + k]);
    }
  }
  return Math.hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
}

/** @param {number[]} a @param {number[]} b */
const maxDiff = (a, b) => Math.max(...a.map((x, i) => Math.abs(x - b[i])));

test('refined meshes in Chromium agree with the conformance manifest', { timeout: 600_000 }, async (t) => {
  const b = await openBrowser(t, { '/conformance/': path.join(REPO, 'conformance') });
  if (!b) return;
  try {
    await b.page.goto(`${b.url}/web/test/pages/refine.html`);
    let probes = 0;
    for (const c of valid) {
      /** @type {any} */
      const r = await b.page.evaluate(([url]) => /** @type {any} */ (window).hceRefine(url, [0, 1, 2, 3], ['smooth', 'nearest'], true), [`/conformance/${c.file}`]);
      assert.ok(r.ok, `${c.file}: ${r.error}`);
      assert.equal(r.lost, null, `${c.file}: the device was lost or reported an error`);
      for (const m of r.out) {
        const at = `${c.file} object ${m.object} level ${m.level} ${m.recon}`;
        const full = m.full;
        if (m.level === 0) {
          // Level 0 is the control mesh, numbered as the tables number it (F.5), followed by
          // the copies of control points split at sharp edges, which repeat their positions.
          assert.equal(m.triangleCount, m.coarseTriangles, at);
          assert.deepEqual(full.positions.slice(0, m.coarse.length), m.coarse, `${at}: positions`);
          const coarse = new Set();
          for (let i = 0; i < m.coarse.length; i += 3) coarse.add(m.coarse.slice(i, i + 3).join());
          for (let i = m.coarse.length; i < full.positions.length; i += 3) {
            assert.ok(coarse.has(full.positions.slice(i, i + 3).join()), `${at}: copy ${i / 3} is no control point`);
          }
          continue;
        }
        const want = c.refined.find((/** @type {any} */ x) => x.object === m.object && x.level === m.level);
        assert.ok(want, `${at}: not in the manifest`);
        assert.equal(m.vertexCount, want.vertex_count, `${at}: vertex count`);
        assert.equal(m.triangleCount, want.triangle_count, `${at}: triangle count`);
        const diag = diagonal(full.positions);
        for (const p of want.probes) {
          const k = p.vertex;
          const pos = full.positions.slice(3 * k, 3 * k + 3);
          assert.ok(maxDiff(pos, p.position.xyz) <= 1e-5 * diag, `${at} vertex ${k}: position ${pos} against ${p.position.xyz}`);
          if (full.normals) {
            const n = full.normals.slice(3 * k, 3 * k + 3);
            assert.ok(maxDiff(n, p.normal.xyz) <= 1e-5, `${at} vertex ${k}: normal ${n} against ${p.normal.xyz}`);
          }
          const expected = m.recon === 'smooth' ? p.colour_smooth.xyz : p.colour_nearest.xyz;
          const col = full.colours.slice(4 * k, 4 * k + 3);
          const tol = 1e-4 * Math.max(...expected.map(Math.abs), 1e-30);
          assert.ok(maxDiff(col, expected) <= tol, `${at} vertex ${k}: colour ${col} against ${expected}`);
          probes += 1;
        }
      }
      t.diagnostic(`${c.file}: ${r.out.length} refinements agree`);
    }
    assert.ok(probes > 0);
    t.diagnostic(`${probes} probe vertices agree`);
    assert.deepEqual(b.pageErrors, []);
  } finally {
    await b.close();
  }
});
