// BENCHMARKS.md "Flat objects drawn from their trees", the browser's rows:
// `node test/viewer_bench.js BAKED.glb [FRAMES] [webgpu|webgl2]` opens the viewer in headless
// Chromium on BAKED with flat objects drawn from their trees (SPEC.md F.7.1) and, as the peer,
// uniformly to their tree depth (`?flat=uniform`), and prints per mode the triangles drawn, the
// first frame (upload, refinements and drawing) and the mean and worst of FRAMES (default 10)
// more frames, each a small orbit (drawing only: the levels stay), all wall time to the GPU done.
import path from 'node:path';
import { openBrowser } from './browser.js';

const [file, framesArg, present = 'webgpu'] = process.argv.slice(2);
if (!file) throw new Error('usage: node test/viewer_bench.js BAKED.glb [FRAMES] [webgpu|webgl2]');
const frames = Number(framesArg ?? 10);
const b = await openBrowser(/** @type {any} */ ({ skip: () => {} }), { '/bench/': path.dirname(path.resolve(file)) }, { webgpu: present === 'webgpu' });
if (!b) throw new Error('no chromium');
try {
  for (const flat of ['uniform', 'adaptive']) {
    const page = b.page;
    const url = `${b.url}/web/viewer.html?url=/bench/${path.basename(file)}&size=800x600&flat=${flat}${present === 'webgl2' ? '&present=webgl2' : ''}`;
    await page.goto(url);
    /** @returns {Promise<any>} */
    const state = () => page.evaluate(() => JSON.parse(JSON.stringify(/** @type {any} */ (window).hceViewer)));
    /** @param {number} n */
    const frameAfter = (n) => page.waitForFunction((k) => /** @type {any} */ (window).hceViewer.frames > k, n, { timeout: 600_000, polling: 20 });
    await frameAfter(0);
    const first = await state();
    if (first.state !== 'ready') throw new Error(`${flat}: ${first.error}`);
    const box = await page.locator('canvas').boundingBox();
    if (!box) throw new Error('no canvas');
    const times = [];
    let seen = first.frames;
    for (let i = 0; i < frames; i++) {
      // A drag of a few pixels: the camera orbits, the levels stay, so the frame only draws.
      await page.mouse.move(box.x + 400, box.y + 300);
      await page.mouse.down();
      await page.mouse.move(box.x + 403, box.y + 300);
      await page.mouse.up();
      await frameAfter(seen);
      const s = await state();
      seen = s.frames;
      times.push(s.frameMs);
    }
    const last = await state();
    const mean = times.reduce((a, x) => a + x, 0) / times.length;
    console.log(`${path.basename(file)} ${flat} (${first.present || present}): ${last.triangles} triangles drawn; first frame ${first.frameMs.toFixed(0)} ms; ${frames} frames: mean ${mean.toFixed(1)} ms, worst ${Math.max(...times).toFixed(1)} ms`);
  }
  if (b.pageErrors.length > 0) throw new Error(`page errors: ${b.pageErrors.join('; ')}`);
} finally {
  await b.close();
}
