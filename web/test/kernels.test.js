// Test (a): every kernel, assembled from runtime/src/gpu/ as the Rust runtime assembles it,
// compiles in Chromium's WebGPU with no message (getCompilationInfo) and every pipeline of it
// builds (createComputePipelineAsync, layout 'auto', WebGPU's default limits). A WGSL change
// that breaks browsers fails here.
import test from 'node:test';
import assert from 'node:assert/strict';
import { openBrowser } from './browser.js';

test('every assembled kernel compiles and builds its pipelines in Chromium', { timeout: 300_000 }, async (t) => {
  const b = await openBrowser(t);
  if (!b) return;
  try {
    await b.page.goto(`${b.url}/web/test/pages/kernels.html`);
    const out = await b.page.evaluate(() => /** @type {any} */ (window).hceResult);
    assert.equal(out.error, undefined);
    assert.ok(out.ok);
    const labels = out.results.map((/** @type {any} */ r) => r.label);
    for (const want of ['flat', 'loop', 'decode', 'fill', 'render']) assert.ok(labels.includes(want), want);
    assert.equal(labels.filter((/** @type {string} */ l) => l.startsWith('loop workgroup')).length, 6);
    let pipelines = 0;
    for (const r of out.results) {
      assert.deepEqual(r.messages, [], `${r.label}: compilation messages`);
      for (const p of r.pipelines) {
        assert.equal(p.error, null, `${r.label} ${p.entryPoint}`);
        pipelines += 1;
        t.diagnostic(`${r.label} ${p.entryPoint}: ${(p.ms / 1000).toFixed(2)} s`);
      }
    }
    // flat 3, loop 3, workgroup 6, decode, fill, render.
    assert.equal(pipelines, 15);
    assert.deepEqual(b.pageErrors, []);
  } finally {
    await b.close();
  }
});
