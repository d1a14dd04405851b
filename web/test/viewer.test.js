// The viewer page's controls: zooming out lowers the automatic levels (the rule of
// choose_level), orbiting keeps the distance, a level forced in the object table is drawn, the reconstruction switch
// re-colours the image, the reset button restores the file's camera, the file picker opens a
// .gltf with its .bin; nothing escapes.
import test from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { openBrowser, REPO } from './browser.js';

/**
 * A .gltf and its .bin from a GLB (the JSON chunk with the buffer's uri set, and the binary
 * chunk), written to `dir`.
 * @param {string} glb @param {string} dir @param {string} stem
 */
function splitGlb(glb, dir, stem) {
  const bytes = fs.readFileSync(glb);
  const jsonLength = bytes.readUInt32LE(12);
  const json = JSON.parse(bytes.subarray(20, 20 + jsonLength).toString('utf8'));
  const binStart = 20 + jsonLength;
  const bin = bytes.subarray(binStart + 8, binStart + 8 + bytes.readUInt32LE(binStart));
  json.buffers[0].uri = `${stem}.bin`;
  fs.writeFileSync(path.join(dir, `${stem}.gltf`), JSON.stringify(json));
  fs.writeFileSync(path.join(dir, `${stem}.bin`), bin);
  return [path.join(dir, `${stem}.gltf`), path.join(dir, `${stem}.bin`)];
}

test('the viewer orbits, zooms, forces levels and switches the reconstruction', { timeout: 300_000 }, async (t) => {
  const b = await openBrowser(t, { '/conformance/': path.join(REPO, 'conformance') });
  if (!b) return;
  const page = b.page;
  /** @returns {Promise<any>} */
  const state = () => page.evaluate(() => JSON.parse(JSON.stringify(/** @type {any} */ (window).hceViewer)));
  /** @param {number} n */
  const frameAfter = (n) => page.waitForFunction((k) => /** @type {any} */ (window).hceViewer.frames > k, n, { timeout: 120_000 });
  const pixels = () => page.evaluate(() => {
    const c = /** @type {HTMLCanvasElement} */ (document.getElementById('canvas'));
    const copy = document.createElement('canvas');
    copy.width = c.width;
    copy.height = c.height;
    const cx = /** @type {CanvasRenderingContext2D} */ (copy.getContext('2d'));
    cx.drawImage(c, 0, 0);
    return Array.from(cx.getImageData(0, 0, c.width, c.height).data);
  });
  try {
    await page.goto(`${b.url}/web/viewer.html?url=/conformance/valid/triangle.glb&size=200x150`);
    await frameAfter(0);
    const first = await state();
    assert.equal(first.state, 'ready');
    const canvas = page.locator('canvas');
    const box = await canvas.boundingBox();
    assert.ok(box);
    // Zoom out: the eye moves away and the automatic level drops as the triangle's edges
    // cover fewer pixels.
    await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
    for (let i = 0; i < 6; i++) await page.mouse.wheel(0, 400);
    await frameAfter(first.frames);
    await page.waitForTimeout(300);
    const zoomed = await state();
    const dist = (/** @type {any} */ c) => Math.hypot(c.eye[0] - c.target[0], c.eye[1] - c.target[1], c.eye[2] - c.target[2]);
    assert.ok(dist(zoomed.camera) > 2 * dist(first.camera), 'the wheel zooms out');
    assert.ok(zoomed.levels[0] < first.levels[0], `levels ${first.levels} then ${zoomed.levels}`);
    // Orbit: a drag moves the eye around the target at the same distance.
    await page.mouse.move(box.x + 50, box.y + 75);
    await page.mouse.down();
    await page.mouse.move(box.x + 120, box.y + 60, { steps: 5 });
    await page.mouse.up();
    await frameAfter(zoomed.frames);
    await page.waitForTimeout(300);
    const orbited = await state();
    assert.ok(Math.abs(dist(orbited.camera) - dist(zoomed.camera)) < 1e-6 * dist(zoomed.camera));
    assert.notDeepEqual(orbited.camera.eye, zoomed.camera.eye);
    // Force level 5 on the object: it is drawn at 5 whatever the view.
    await page.selectOption('select[data-object="0"]', '5');
    await page.waitForFunction(() => /** @type {any} */ (window).hceViewer.levels[0] === 5, null, { timeout: 120_000 });
    assert.equal((await state()).triangles, 4 ** 5);
    // The reconstruction switch changes the colours drawn.
    const smooth = await pixels();
    const before = (await state()).frames;
    await page.selectOption('#recon', 'nearest');
    await frameAfter(before);
    await page.waitForTimeout(300);
    const nearest = await pixels();
    let differ = 0;
    for (let i = 0; i < smooth.length; i++) if (smooth[i] !== nearest[i]) differ += 1;
    assert.ok(differ > 0, 'the nearest-normal image differs from the smooth one');
    // Reset: back to the camera the file was opened with.
    const beforeReset = (await state()).frames;
    await page.click('#reset');
    await frameAfter(beforeReset);
    assert.deepEqual((await state()).camera.eye, first.camera.eye);
    assert.equal((await state()).error, null);
    // The file picker, with a .gltf and the .bin it names picked together.
    const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'hce-viewer-'));
    try {
      const files = splitGlb(path.join(REPO, 'conformance/valid/cornell-box.glb'), dir, 'box');
      const picked = (await state()).frames;
      await page.setInputFiles('#file', files);
      await frameAfter(picked);
      const opened = await state();
      assert.equal(opened.error, null);
      assert.equal(opened.levels.length, 8, 'the eight objects of the Cornell box');
      assert.match(await page.textContent('#status') ?? '', /box\.gltf: 8 objects \(gltf\)/);
    } finally {
      fs.rmSync(dir, { recursive: true, force: true });
    }
    assert.deepEqual(b.pageErrors, []);
  } finally {
    await b.close();
  }
});
