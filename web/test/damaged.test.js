// Test (d): damaged files show an error on the viewer page and no exception escapes: every
// invalid file of conformance/, and deterministic damage to valid ones (truncation, flipped
// bytes). After all of them the device is still there: a valid file still draws.
import test from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { openBrowser, REPO } from './browser.js';

const manifest = JSON.parse(fs.readFileSync(path.join(REPO, 'conformance/manifest.json'), 'utf8'));

/** Deterministic damage to `bytes`: truncations and single flipped bytes. @param {Buffer} bytes */
function damage(bytes) {
  /** @type {[string, Buffer][]} */
  const out = [
    ['truncated to half', bytes.subarray(0, bytes.length >> 1)],
    ['truncated by 1 byte', bytes.subarray(0, bytes.length - 1)],
    ['empty', Buffer.alloc(0)],
  ];
  let x = 0x9e3779b9;
  for (let k = 0; k < 12; k++) {
    x ^= x << 13;
    x ^= x >>> 17;
    x ^= x << 5;
    x >>>= 0;
    const at = x % bytes.length;
    const copy = Buffer.from(bytes);
    copy[at] ^= 0x5a;
    out.push([`byte ${at} flipped`, copy]);
  }
  return out;
}

test('damaged files show an error on the page and nothing escapes', { timeout: 300_000 }, async (t) => {
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'hce-damaged-'));
  /** @type {{ url: string, what: string, mustFail: boolean }[]} */
  const cases = [];
  for (const c of manifest.cases.filter((/** @type {any} */ c) => !c.valid)) cases.push({ url: `/conformance/${c.file}`, what: c.file, mustFail: true });
  for (const file of ['valid/triangle.hce', 'valid/triangle.glb', 'valid/cornell-box.glb']) {
    const bytes = fs.readFileSync(path.join(REPO, 'conformance', file));
    damage(bytes).forEach(([what, data], i) => {
      const name = `${i}-${path.basename(file)}`;
      fs.writeFileSync(path.join(dir, name), data);
      // A flip inside the JSON chunk of a GLB may leave a valid file (a name, a number's
      // digit); a container's every byte is under a checksum.
      cases.push({ url: `/damaged/${name}`, what: `${file} ${what}`, mustFail: file.endsWith('.hce') || !what.includes('flipped') });
    });
  }
  const b = await openBrowser(t, { '/conformance/': path.join(REPO, 'conformance'), '/damaged/': dir });
  if (!b) return;
  try {
    await b.page.goto(`${b.url}/web/viewer.html?size=160x120`);
    await b.page.waitForFunction(() => ['idle', 'error'].includes(/** @type {any} */ (window).hceViewer.state), null, { timeout: 240_000 });
    let refused = 0;
    for (const c of cases) {
      /** @type {any} */
      const s = await b.page.evaluate(async (url) => {
        const w = /** @type {any} */ (window);
        await w.hceOpen(url);
        const shown = /** @type {HTMLElement} */ (document.getElementById('error'));
        return { state: w.hceViewer.state, error: w.hceViewer.error, visible: shown.classList.contains('shown') ? shown.textContent : null };
      }, c.url);
      if (c.mustFail) assert.equal(s.state, 'error', `${c.what}: should be refused`);
      if (s.state === 'error') {
        refused += 1;
        assert.ok(s.visible && s.visible.length > 10, `${c.what}: the error is shown on the page`);
        assert.ok(!/undefined|null|\[object/.test(s.error), `${c.what}: a clear message, got ${s.error}`);
      } else {
        assert.equal(s.state, 'ready', `${c.what}: ${JSON.stringify(s)}`);
      }
    }
    t.diagnostic(`${refused} of ${cases.length} damaged files refused with a message on the page`);
    // The device survived: a valid file still draws a frame.
    const frames = await b.page.evaluate(() => /** @type {any} */ (window).hceViewer.frames);
    await b.page.evaluate(() => /** @type {any} */ (window).hceOpen('/conformance/valid/cornell-box.glb'));
    await b.page.waitForFunction((n) => /** @type {any} */ (window).hceViewer.frames > n, frames, { timeout: 60_000 });
    const after = await b.page.evaluate(() => /** @type {any} */ (window).hceViewer);
    assert.equal(after.state, 'ready');
    assert.equal(after.error, null);
    assert.deepEqual(b.pageErrors, [], 'no exception escaped');
  } finally {
    await b.close();
    fs.rmSync(dir, { recursive: true, force: true });
  }
});
