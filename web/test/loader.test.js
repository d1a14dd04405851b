// The loader and the table checks on the conformance suite, in node (no browser, no GPU):
// every valid file loads and passes every check the kernels rely on; every invalid file is
// refused with an HceError at the location `hce validate` reports first.
import test from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';
import { loadAsset } from '../src/asset.js';
import { checkObject } from '../src/tables.js';
import { crc32 } from '../src/container.js';
import { lightingWords, rgb9e5 } from '../src/lighting.js';
import { HceError } from '../src/errors.js';
import { REPO } from './browser.js';

const manifest = JSON.parse(fs.readFileSync(path.join(REPO, 'conformance/manifest.json'), 'utf8'));
/** @param {string} file */
const bytes = (file) => new Uint8Array(fs.readFileSync(path.join(REPO, 'conformance', file)));

test('CRC-32 is the ISO-HDLC one', () => {
  assert.equal(crc32(new TextEncoder().encode('123456789')), 0xcbf43926);
});

test('RGB9E5 decodes as SPEC.md 2.4 says', () => {
  // mantissas (256, 128, 64) with E = 15 + 9 - 8 = 16: (1, 0.5, 0.25).
  assert.deepEqual(rgb9e5(256 | (128 << 9) | (64 << 18) | (16 << 27)), [1, 0.5, 0.25]);
});

for (const c of manifest.cases.filter((/** @type {any} */ c) => c.valid)) {
  test(`valid: ${c.file} loads, passes the checks and gets a lighting table`, async () => {
    const asset = await loadAsset(bytes(c.file));
    const objects = new Set(c.refined.map((/** @type {any} */ r) => r.object));
    assert.equal(asset.objects.length, objects.size);
    for (const o of asset.objects) {
      const checked = checkObject(o.object);
      assert.ok(checked.treeDepth >= 0);
      const words = lightingWords(o.object);
      // Header words point inside the table, in order.
      assert.ok(words[0] > 2 && words[0] <= words[1] && words[1] < words.length);
      assert.ok(o.instances.length >= 1, `${o.object.name} has an instance`);
    }
  });
}

for (const c of manifest.cases.filter((/** @type {any} */ c) => !c.valid)) {
  test(`invalid: ${c.file} is refused with a clear error`, async () => {
    const want = c.problems[0].location;
    await assert.rejects(
      async () => {
        const asset = await loadAsset(bytes(c.file));
        for (const o of asset.objects) checkObject(o.object);
      },
      (/** @type {unknown} */ e) => {
        assert.ok(e instanceof HceError, `an HceError, not ${e}`);
        // The same object or section as hce validate's first problem (the wording differs).
        const head = want.replace(/\..*$/, '').replace(/\[.*$/, '');
        assert.ok(e.location.startsWith(head) || e.message.includes(head), `${e.message} should be at ${want}`);
        return true;
      },
    );
  });
}
