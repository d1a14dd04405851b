// The viewer without WebGPU: in a Chromium with WebGPU switched off, the page refines on the
// CPU in hce.wasm and draws with WebGL2, says so, and its image of Teatime and the Cornell box
// at a fixed camera and level agrees with `hce render` of the same file, camera, size and level.
//
// Metric (as render.test.js): per pixel, the largest difference over R, G, B of the 8-bit sRGB
// values; the images agree when the mean is at most 0.5 levels and at most 0.5% of the pixels
// differ by more than 24 levels (measured: Teatime 0.05 levels and 0.03%, the Cornell box 0.04
// and 0.01%: two rasterisers; both draw flat objects from their trees).
// The viewer's image is written to
// target/hce-web/viewer-webgl2-NAME.png beside hce's (NAME.png).
import test from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { openBrowser, hceBinary } from './browser.js';
import { CACHE, bakedSample, runHce } from './samples.js';

const W = 320;
const H = 240;

test('without WebGPU the viewer draws with WebGL2 what hce render draws', { timeout: 600_000 }, async (t) => {
  const hce = hceBinary(t);
  if (!hce) return;
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'hce-viewer-webgl-'));
  /** @type {[string, string, string][]} file, level, what */
  const cases = [
    [bakedSample(hce, 'teatime'), '2', 'Teatime'],
    [bakedSample(hce, 'cornell-box'), '3', 'Cornell box'],
  ];
  for (const [file] of cases) fs.copyFileSync(file, path.join(dir, path.basename(file)));
  const b = await openBrowser(t, { '/files/': dir }, { webgpu: false });
  if (!b) return;
  try {
    for (const [file, level, what] of cases) {
      const name = path.basename(file);
      const png = path.join(dir, `${name}.png`);
      runHce(hce, ['render', file, '-o', png, '--size', `${W}x${H}`, '--level', level, '--msaa', '1']);
      fs.mkdirSync(CACHE, { recursive: true });
      fs.copyFileSync(png, path.join(CACHE, `hce-render-${name}.png`));
      await b.page.goto(`${b.url}/web/viewer.html?url=/files/${name}&size=${W}x${H}&level=${level}`);
      await b.page.waitForFunction(() => /** @type {any} */ (window).hceViewer.frames > 0 || /** @type {any} */ (window).hceViewer.state === 'error', null, { timeout: 300_000 });
      /** @type {any} */
      const result = await b.page.evaluate(async (url) => {
        const w = /** @type {any} */ (window);
        if (w.hceViewer.state === 'error') return { error: w.hceViewer.error, status: document.getElementById('status')?.textContent };
        const canvas = /** @type {HTMLCanvasElement} */ (document.getElementById('canvas'));
        const copy = document.createElement('canvas');
        copy.width = canvas.width;
        copy.height = canvas.height;
        const cx = /** @type {CanvasRenderingContext2D} */ (copy.getContext('2d'));
        cx.drawImage(canvas, 0, 0);
        const shot = copy.toDataURL('image/png');
        const ours = cx.getImageData(0, 0, copy.width, copy.height).data;
        const img = new Image();
        img.src = url;
        await img.decode();
        cx.clearRect(0, 0, copy.width, copy.height);
        cx.drawImage(img, 0, 0);
        const theirs = cx.getImageData(0, 0, copy.width, copy.height).data;
        let sum = 0;
        let over = 0;
        let lit = 0;
        for (let i = 0; i < ours.length; i += 4) {
          const d = Math.max(Math.abs(ours[i] - theirs[i]), Math.abs(ours[i + 1] - theirs[i + 1]), Math.abs(ours[i + 2] - theirs[i + 2]));
          sum += d;
          if (d > 24) over += 1;
          if (ours[i] + ours[i + 1] + ours[i + 2] > 30) lit += 1;
        }
        const pixels = ours.length / 4;
        return {
          mean: sum / pixels, over: over / pixels, lit: lit / pixels, shot, levels: w.hceViewer.levels, present: w.hceViewer.present,
          webgpu: !!navigator.gpu && (await navigator.gpu.requestAdapter()) !== null, path: document.getElementById('path')?.textContent, status: document.getElementById('status')?.textContent,
        };
      }, `/files/${name}.png`);
      assert.equal(result.error, undefined, `${what}: ${result.error} (status line: ${result.status})`);
      fs.writeFileSync(path.join(CACHE, `viewer-webgl2-${name}.png`), Buffer.from(result.shot.split(',')[1], 'base64'));
      t.diagnostic(`${what}: mean difference ${result.mean.toFixed(3)} levels, ${(100 * result.over).toFixed(2)}% of pixels over 24, ${(100 * result.lit).toFixed(0)}% lit, levels ${result.levels}; "${result.path}"`);
      assert.equal(result.webgpu, false, 'the page gets no WebGPU adapter');
      assert.equal(result.present, 'webgl2');
      assert.match(result.path, /WebGL2, refined on the CPU in WebAssembly: (this browser has no WebGPU|WebGPU gives no adapter)/);
      assert.match(result.status, new RegExp(`${name}: \\d+ objects`));
      assert.ok(result.lit > 0.2, `${what}: only ${(100 * result.lit).toFixed(1)}% of the pixels are lit`);
      assert.ok(result.mean <= 0.5, `${what}: mean difference ${result.mean} levels`);
      assert.ok(result.over <= 0.005, `${what}: ${(100 * result.over).toFixed(2)}% of the pixels differ by more than 24 levels`);
    }
    assert.deepEqual(b.pageErrors, []);
  } finally {
    await b.close();
    fs.rmSync(dir, { recursive: true, force: true });
  }
});
