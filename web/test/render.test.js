// Test (c): the viewer's image at a fixed camera against `hce render` of the same file, camera
// (the file's, or the automatic one, both resolved as hce resolves them), size and level.
//
// Metric: per pixel, the largest difference over R, G, B of the 8-bit sRGB values. The images
// agree when the mean of that difference is at most 0.5 levels and at most 0.5% of the
// pixels differ by more than 24 levels (measured: 0.05-0.07 levels and 0.01-0.02%). The viewer and hce render draw the same refined triangles
// with the same view-projection matrix and tone curve; what remains is rasterisation on two
// different software adapters (SwiftShader in Chromium, lavapipe for hce): pixels on triangle
// edges and depth ties, and a 16-bit against a 32-bit float target before tone mapping.
import test from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { openBrowser, hceBinary } from './browser.js';
import { bakedSample, runHce } from './samples.js';

const W = 320;
const H = 240;

test('the viewer draws what hce render draws', { timeout: 600_000 }, async (t) => {
  const hce = hceBinary(t);
  if (!hce) return;
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'hce-render-'));
  /** @type {[string, string, string][]} file, level, what */
  const cases = [
    [bakedSample(hce, 'teatime'), '2', 'Teatime (three multiresolution objects, flat table and room)'],
    [bakedSample(hce, 'cornell-box'), '3', 'Cornell box (flat walls, a multiresolution block)'],
  ];
  for (const [file] of cases) fs.copyFileSync(file, path.join(dir, path.basename(file)));
  const b = await openBrowser(t, { '/files/': dir });
  if (!b) return;
  try {
    for (const [file, level, what] of cases) {
      const name = path.basename(file);
      const png = path.join(dir, `${name}.png`);
      // One sample per pixel, as the viewer draws (hce render multisamples by default).
      runHce(hce, ['render', file, '-o', png, '--size', `${W}x${H}`, '--level', level, '--msaa', '1']);
      await b.page.goto(`${b.url}/web/viewer.html?url=/files/${name}&size=${W}x${H}&level=${level}`);
      await b.page.waitForFunction(() => /** @type {any} */ (window).hceViewer.frames > 0 || /** @type {any} */ (window).hceViewer.state === 'error', null, { timeout: 300_000 });
      /** @type {any} */
      const result = await b.page.evaluate(async (url) => {
        const w = /** @type {any} */ (window);
        if (w.hceViewer.state === 'error') return { error: w.hceViewer.error };
        const canvas = /** @type {HTMLCanvasElement} */ (document.getElementById('canvas'));
        // The page's pixels: the 2D canvas it drew the read-back into, else a copy of the
        // WebGPU canvas.
        const copy = document.createElement('canvas');
        copy.width = canvas.width;
        copy.height = canvas.height;
        const cx = /** @type {CanvasRenderingContext2D} */ (copy.getContext('2d'));
        cx.drawImage(canvas, 0, 0);
        const ours = cx.getImageData(0, 0, copy.width, copy.height).data;
        const img = new Image();
        img.src = url;
        await img.decode();
        cx.clearRect(0, 0, copy.width, copy.height);
        cx.drawImage(img, 0, 0);
        const theirs = cx.getImageData(0, 0, copy.width, copy.height).data;
        let sum = 0;
        let over = 0;
        for (let i = 0; i < ours.length; i += 4) {
          const d = Math.max(Math.abs(ours[i] - theirs[i]), Math.abs(ours[i + 1] - theirs[i + 1]), Math.abs(ours[i + 2] - theirs[i + 2]));
          sum += d;
          if (d > 24) over += 1;
        }
        const pixels = ours.length / 4;
        let lit = 0;
        for (let i = 0; i < ours.length; i += 4) if (ours[i] + ours[i + 1] + ours[i + 2] > 30) lit += 1;
        return { mean: sum / pixels, over: over / pixels, lit: lit / pixels, size: [copy.width, copy.height], levels: w.hceViewer.levels, present: w.hceViewer.present };
      }, `/files/${name}.png`);
      assert.equal(result.error, undefined, `${what}: ${result.error}`);
      t.diagnostic(`${what}: mean difference ${result.mean.toFixed(3)} levels, ${(100 * result.over).toFixed(2)}% of pixels over 24, ${(100 * result.lit).toFixed(0)}% lit, levels ${result.levels}, presented by ${result.present}`);
      assert.deepEqual(result.size, [W, H]);
      // An image with something in it: a black page must not pass for a black render.
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
