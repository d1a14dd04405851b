// The viewer page's controls: zooming out lowers the automatic levels (the rule of
// choose_level), orbiting keeps the distance, a level forced in the object table is drawn, the reconstruction switch
// re-colours the image, the reset button restores the file's camera, the file picker opens a
// .gltf with its .bin; a file whose baked lighting an optimiser dropped is drawn from its
// COLOR_0, saying so; nothing escapes.
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

/**
 * The viewer canvas's RGBA bytes, through a 2D copy (WebGPU and WebGL2 canvases alike).
 * @param {import('playwright-core').Page} page
 * @returns {Promise<number[]>}
 */
function canvasPixels(page) {
  return page.evaluate(() => {
    const c = /** @type {HTMLCanvasElement} */ (document.getElementById('canvas'));
    const copy = document.createElement('canvas');
    copy.width = c.width;
    copy.height = c.height;
    const cx = /** @type {CanvasRenderingContext2D} */ (copy.getContext('2d'));
    cx.drawImage(c, 0, 0);
    return Array.from(cx.getImageData(0, 0, c.width, c.height).data);
  });
}

test('the viewer orbits, zooms, forces levels and switches the reconstruction', { timeout: 300_000 }, async (t) => {
  const b = await openBrowser(t, { '/conformance/': path.join(REPO, 'conformance') });
  if (!b) return;
  const page = b.page;
  /** @returns {Promise<any>} */
  const state = () => page.evaluate(() => JSON.parse(JSON.stringify(/** @type {any} */ (window).hceViewer)));
  /** @param {number} n */
  const frameAfter = (n) => page.waitForFunction((k) => /** @type {any} */ (window).hceViewer.frames > k, n, { timeout: 120_000 });
  const pixels = () => canvasPixels(page);
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

/**
 * `glb` without EXT_hce_baked_lighting, as an optimiser that does not know the extension writes
 * it (gltf-transform without hce's config, gltfpack): the root and primitive objects and the
 * extensionsUsed entry gone, everything else (COLOR_0 included) kept.
 * @param {string} glb @param {string} out
 */
function stripBakedLighting(glb, out) {
  const bytes = fs.readFileSync(glb);
  const jsonLength = bytes.readUInt32LE(12);
  const json = JSON.parse(bytes.subarray(20, 20 + jsonLength).toString('utf8'));
  const rest = bytes.subarray(20 + jsonLength);
  delete json.extensions.EXT_hce_baked_lighting;
  json.extensionsUsed = json.extensionsUsed.filter((/** @type {string} */ e) => e !== 'EXT_hce_baked_lighting');
  for (const m of json.meshes) for (const p of m.primitives) delete p.extensions?.EXT_hce_baked_lighting;
  let text = JSON.stringify(json);
  while (text.length % 4 !== 0) text += ' ';
  const head = Buffer.alloc(20);
  head.write('glTF', 0);
  head.writeUInt32LE(2, 4);
  head.writeUInt32LE(20 + text.length + rest.length, 8);
  head.writeUInt32LE(text.length, 12);
  head.write('JSON', 16);
  fs.writeFileSync(out, Buffer.concat([head, Buffer.from(text), rest]));
}

test('a file whose baked lighting is gone is drawn from its COLOR_0, saying so', { timeout: 300_000 }, async (t) => {
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'hce-viewer-plain-'));
  try {
    stripBakedLighting(path.join(REPO, 'conformance/valid/cornell-box.glb'), path.join(dir, 'box.glb'));
    for (const webgpu of [true, false]) {
      const b = await openBrowser(t, { '/plain/': dir }, { webgpu });
      if (!b) return;
      try {
        await b.page.goto(`${b.url}/web/viewer.html?url=/plain/box.glb&size=200x150`);
        await b.page.waitForFunction(() => /** @type {any} */ (window).hceViewer.frames > 0, null, { timeout: 120_000 });
        const state = await b.page.evaluate(() => JSON.parse(JSON.stringify(/** @type {any} */ (window).hceViewer)));
        assert.equal(state.error, null);
        assert.equal(state.levels.length, 1, 'the scene as one object');
        assert.match(await b.page.textContent('#warnings') ?? '', /^no baked lighting: the file does not use EXT_hce_baked_lighting.*COLOR_0 vertex colours/);
        // The Cornell box's red and green walls: COLOR_0 (the light arriving) times the base colours.
        const rgba = await canvasPixels(b.page);
        let red = 0;
        let green = 0;
        for (let i = 0; i < rgba.length; i += 4) {
          const [r, g, bl] = [rgba[i], rgba[i + 1], rgba[i + 2]];
          if (r > 60 && r > 1.5 * Math.max(g, bl)) red += 1;
          if (g > 60 && g > 1.2 * r && g > 1.5 * bl) green += 1;
        }
        t.diagnostic(`${webgpu ? 'WebGPU' : 'WebGL2'}: ${red} red and ${green} green pixels of ${rgba.length / 4}`);
        assert.ok(red > 100 && green > 100, `${red} red, ${green} green pixels`);
        assert.deepEqual(b.pageErrors, []);
      } finally {
        await b.close();
      }
    }
  } finally {
    fs.rmSync(dir, { recursive: true, force: true });
  }
});
