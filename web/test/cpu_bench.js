// BENCHMARKS.md "hce.wasm in the browser": `node test/cpu_bench.js BAKED.glb LEVEL
// [REPEATS]` prints the time to refine every object of BAKED at LEVEL on the CPU in hce.wasm
// (cpu_refine.js) in a headless Chromium with WebGPU switched off: the median of REPEATS
// (default 5) after one warm-up, then hce.wasm's load time (fetch, compile, instantiate and a
// first read of BAKED in a fresh module, the median of REPEATS). Run
// `hce subdivide BAKED --level LEVEL --flat uniform --merge --stats` beside it.
import { openBrowser } from './browser.js';
import path from 'node:path';

const [file, level, repeats] = process.argv.slice(2);
if (!file || !level) throw new Error('usage: node test/cpu_bench.js BAKED.glb LEVEL [REPEATS]');
const b = await openBrowser(/** @type {any} */ ({ skip: () => {} }), { '/bench/': path.dirname(path.resolve(file)) }, { webgpu: false });
if (!b) throw new Error('no chromium');
try {
  await b.page.goto(`${b.url}/web/test/pages/cpu.html`);
  /** @type {any} */
  const r = await b.page.evaluate((/** @type {[string, number, number]} */ [u, l, n]) => /** @type {any} */ (window).hceCpuBench(u, l, n), /** @type {[string, number, number]} */ ([`/bench/${path.basename(file)}`, Number(level), Number(repeats ?? 5)]));
  if (!r.ok) throw new Error(r.error);
  console.log(`${r.objects} objects, level ${level}: ${r.triangles} triangles; median ${r.ms.toFixed(1)} ms (runs ${r.times.map((/** @type {number} */ t) => t.toFixed(0)).join(', ')})`);
  // hce.wasm's load: fetch, compile, instantiate and a first read of BAKED, in a fresh module.
  /** @type {any} */
  const w = await b.page.evaluate((/** @type {[string, number]} */ [u, n]) => /** @type {any} */ (window).hceWasmLoad(u, n), /** @type {[string, number]} */ ([`/bench/${path.basename(file)}`, Number(repeats ?? 5)]));
  if (!w.ok) throw new Error(w.error);
  console.log(`hce.wasm load and first read: median ${w.ms.toFixed(1)} ms (runs ${w.times.map((/** @type {number} */ t) => t.toFixed(0)).join(', ')})`);
} finally {
  await b.close();
}
