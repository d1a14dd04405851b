// The Babylon.js glTF loader extension: on Babylon's WebGL2 Engine and on its WebGPUEngine it
// refines on the CPU in hce.wasm, and the baked Teatime drawn through its camera agrees with the
// three.js plugin drawing it on WebGLRenderer (the same CPU refinement, three_webgl.test.js).
// Headless Chromium's WebGPU on SwiftShader loses Babylon's device within a second once a canvas
// context is configured ("A valid external Instance reference no longer exists"; an
// OffscreenCanvas too), so the page gives WebGPUEngine a context whose frames are never presented
// (babylon-draw.html) and reads the float target.
//
// Metric (as three_webgl.test.js): per pixel, the largest difference over R, G, B of the 8-bit
// sRGB values, both images tone-mapped by present.wgsl's curve from a float render target. They
// agree when the mean of that difference is at most 0.5 levels and at most 0.5% of the pixels
// differ by more than 24 levels. Both draw the same refined meshes with the same colours; what
// remains is rasterisation by two engines. Measured: mean 0.000 levels, 0.00% over 24, on both engines.
// Damaged copies of the file, and a missing hce.wasm, reject the load with hce's message and no
// exception escapes; a file whose container is gone draws its COLOR_0 unlit, with a warning.
// The images are written to target/hce-web/babylon-*.png.
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

/**
 * The GLB `bytes` with its JSON chunk rewritten by `edit` (the binary chunk kept).
 * @param {Buffer} bytes @param {(json: any) => void} edit
 */
function editGlb(bytes, edit) {
  const jsonLength = bytes.readUInt32LE(12);
  const json = JSON.parse(bytes.subarray(20, 20 + jsonLength).toString('utf8'));
  edit(json);
  let text = Buffer.from(JSON.stringify(json), 'utf8');
  text = Buffer.concat([text, Buffer.alloc((4 - (text.length % 4)) % 4, 0x20)]);
  const rest = bytes.subarray(20 + jsonLength);
  const header = Buffer.alloc(20);
  header.writeUInt32LE(0x46546c67, 0);
  header.writeUInt32LE(2, 4);
  header.writeUInt32LE(20 + text.length + rest.length, 8);
  header.writeUInt32LE(text.length, 12);
  header.writeUInt32LE(0x4e4f534a, 16);
  return Buffer.concat([header, text, rest]);
}

/**
 * The GLB `bytes` with one byte of the container (the root extension's buffer view) flipped.
 * @param {Buffer} bytes
 */
function damageContainer(bytes) {
  const jsonLength = bytes.readUInt32LE(12);
  const json = JSON.parse(bytes.subarray(20, 20 + jsonLength).toString('utf8'));
  const view = json.bufferViews[json.extensions.EXT_hce_baked_lighting.bufferView];
  const copy = Buffer.from(bytes);
  copy[20 + jsonLength + 8 + (view.byteOffset ?? 0) + (view.byteLength >> 1)] ^= 0x5a;
  return copy;
}

test('the Babylon.js extension draws Teatime as the three.js plugin does', { timeout: 900_000 }, async (t) => {
  const hce = hceBinary(t);
  if (!hce) return;
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'hce-babylon-'));
  const baked = fs.readFileSync(bakedSample(hce, 'teatime'));
  fs.writeFileSync(path.join(dir, 'teatime.glb'), baked);
  fs.writeFileSync(path.join(dir, 'truncated.glb'), baked.subarray(0, baked.length >> 1));
  fs.writeFileSync(path.join(dir, 'container-damaged.glb'), damageContainer(baked));
  fs.writeFileSync(path.join(dir, 'no-container.glb'), editGlb(baked, (json) => { delete json.extensions.EXT_hce_baked_lighting; }));
  /** @param {any} b @param {string} url @param {string} engine */
  const babylon = async (b, url, engine) => /** @type {any} */ (await b.page.evaluate((/** @type {[string, number, string, number, number]} */ [u, l, k, w, h]) => /** @type {any} */ (window).hceBabylonDraw(u, l, k, w, h), /** @type {[string, number, string, number, number]} */ ([url, LEVEL, engine, W, H])));
  const page = `/web/test/pages/babylon-draw.html`;
  try {
    const b = await openBrowser(t, { '/files/': dir });
    if (!b) return;
    try {
      await b.page.goto(`${b.url}/web/test/pages/three-draw-webgl.html`);
      /** @type {any} */
      const three = await b.page.evaluate((/** @type {[string, number, number, number]} */ [u, l, w, h]) => /** @type {any} */ (window).hceThreeDraw(u, l, 'webgl', w, h), /** @type {[string, number, number, number]} */ (['/files/teatime.glb', LEVEL, W, H]));
      assert.ok(three.ok, `three.js: ${three.error}`);
      savePng(three, 'babylon-reference-three.png');
      // Babylon's modules are many files: a slow first load on a loaded machine.
      await b.page.goto(`${b.url}${page}`, { timeout: 240_000 });
      /** @type {any} */
      let r = null;
      for (const engine of ['webgl', 'webgpu']) {
        const e = await babylon(b, '/files/teatime.glb', engine);
        assert.ok(e.ok, `${engine}: ${e.error}`);
        savePng(e, `babylon-${engine}.png`);
        t.diagnostic(`${engine}: ${e.backend}, ${e.meshes} refined meshes, loaded and refined in ${e.loadMs.toFixed(0)} ms (${e.report.map((/** @type {any} */ x) => `${x.name} ${x.path} L${x.level}`).join(', ')})`);
        assert.equal(e.backend, engine === 'webgpu' ? 'WebGPU' : 'WebGL2');
        assert.deepEqual(e.report.map((/** @type {any} */ x) => [x.name, x.level, x.triangles]), three.report.map((/** @type {any} */ x) => [x.name, x.level, x.triangles]));
        assert.equal(e.meshes, three.meshes, `${engine}: the same meshes refined`);
        assert.equal(e.unlit, e.meshes, `${engine}: every refined mesh unlit`);
        assert.deepEqual(e.warnings, []);
        const d = difference(e.pixels, three.pixels);
        t.diagnostic(`${engine} against three.js on WebGLRenderer: mean difference ${d.mean.toFixed(3)} levels, ${(100 * d.over).toFixed(2)}% of pixels over 24, ${(100 * d.lit).toFixed(0)}% lit`);
        assert.ok(d.lit > 0.2, `${engine}: only ${(100 * d.lit).toFixed(1)}% of the pixels are lit`);
        assert.ok(d.mean <= 0.5, `${engine}: mean difference ${d.mean} levels`);
        assert.ok(d.over <= 0.005, `${engine}: ${(100 * d.over).toFixed(2)}% of the pixels differ by more than 24 levels`);
        r ??= e;
      }

      // Damaged files reject the load with a message; nothing escapes.
      const truncated = await babylon(b, '/files/truncated.glb', 'webgl');
      assert.equal(truncated.ok, false);
      assert.match(truncated.error, /^Unable to load from \/files\/truncated\.glb: /);
      t.diagnostic(`truncated: ${truncated.error}`);
      const damaged = await babylon(b, '/files/container-damaged.glb', 'webgl');
      assert.equal(damaged.ok, false);
      t.diagnostic(`container damaged: ${damaged.error}`);
      assert.match(damaged.error, /\/extensions\/EXT_hce_baked_lighting: the container fails validation .*checksum mismatch/);
      // Without its container the file draws its coarse bake unlit, and says so.
      const fallback = await babylon(b, '/files/no-container.glb', 'webgl');
      assert.ok(fallback.ok, fallback.error);
      savePng(fallback, 'babylon-no-container.png');
      assert.equal(fallback.meshes, 0);
      assert.equal(fallback.unlit, r.meshes, 'every linked primitive drawn unlit');
      assert.ok(fallback.warnings.some((/** @type {string} */ w) => w.includes('the file has no container') && w.includes('COLOR_0')), fallback.warnings.join('\n'));
      const f = difference(fallback.pixels, r.pixels);
      t.diagnostic(`no container: COLOR_0 against the refined draw: mean ${f.mean.toFixed(3)} levels, ${(100 * f.lit).toFixed(0)}% lit`);
      assert.ok(f.lit > 0.2, 'the coarse bake is drawn, not black');
      assert.deepEqual(b.pageErrors, []);

      // Without hce.wasm the load is rejected with what to do.
      await b.page.route('**/hce.wasm', (route) => route.fulfill({ status: 404, body: 'not found' }));
      await b.page.goto(`${b.url}${page}`, { timeout: 240_000 });
      const noWasm = await babylon(b, '/files/teatime.glb', 'webgl');
      assert.equal(noWasm.ok, false);
      t.diagnostic(`no hce.wasm: ${noWasm.error}`);
      assert.match(noWasm.error, /cannot start the WebAssembly reader: cannot load .*hce\.wasm: HTTP 404 \(build it with web\/build-wasm\.sh\)/);
      assert.deepEqual(b.pageErrors, []);
    } finally {
      await b.close();
    }
  } finally {
    fs.rmSync(dir, { recursive: true, force: true });
  }
});
