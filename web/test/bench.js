// BENCHMARKS.md "hce in the browser": `node test/bench.js BAKED.glb [OBJECT]` prints the Loop
// kernel's refine time per level in headless Chromium (SwiftShader) for OBJECT's control mesh
// with `hce bench-gpu`'s random trees; run `hce bench-gpu --mesh` on the same mesh beside it.
import { openBrowser } from './browser.js';
import path from 'node:path';

const [file, object] = process.argv.slice(2);
if (!file) throw new Error('usage: node test/bench.js BAKED.glb [OBJECT]');
const b = await openBrowser(/** @type {any} */ ({ skip: () => {} }), { '/bench/': path.dirname(path.resolve(file)) });
if (!b) throw new Error('no chromium');
try {
  await b.page.goto(`${b.url}/web/test/pages/bench.html`);
  /** @type {any} */
  const r = await b.page.evaluate(([u, o]) => /** @type {any} */ (window).hceBench(u, [1, 2, 3], 3, o), [`/bench/${path.basename(file)}`, object]);
  if (!r.ok) throw new Error(r.error);
  console.log(`adapter: ${r.adapter}; ${r.coarse} coarse triangles, ${r.vertices} vertices`);
  for (const row of r.rows) console.log(`${row.recon} level ${row.level}: ${row.triangles} triangles, ${row.vertices} vertices, ${row.ms.toFixed(1)} ms`);
} finally {
  await b.close();
}
