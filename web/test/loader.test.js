// The loader (hce.wasm) and the table checks on the conformance suite, in node (no browser, no GPU):
// every valid file loads and passes every check the kernels rely on; every invalid file is
// refused with the HceError whose message is the one the CLI gives for it (the same Rust, in
// WebAssembly).
import test from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { spawnSync } from 'node:child_process';
import { loadAsset, objectTables } from '../src/native.js';
import { HceError } from '../src/errors.js';
import { hceBinary, REPO } from './browser.js';

const manifest = JSON.parse(fs.readFileSync(path.join(REPO, 'conformance/manifest.json'), 'utf8'));
/** @param {string} file */
const bytes = (file) => new Uint8Array(fs.readFileSync(path.join(REPO, 'conformance', file)));

// A valid file with a warning has a primitive that cannot be checked (Draco, SPEC.md 2.6): the
// loader must not apply its lighting, so loading it for the baked lighting fails, saying why.
for (const c of manifest.cases.filter((/** @type {any} */ c) => c.valid && c.warnings)) {
  test(`valid with a warning: ${c.file} is not drawn with its lighting, and says why`, async () => {
    await assert.rejects(loadAsset(bytes(c.file)), (/** @type {any} */ e) => e instanceof HceError && /cannot check/.test(e.message));
  });
}

for (const c of manifest.cases.filter((/** @type {any} */ c) => c.valid && !c.warnings)) {
  test(`valid: ${c.file} loads, passes the checks and gets its tables`, async () => {
    const asset = await loadAsset(bytes(c.file));
    const objects = new Set(c.refined.map((/** @type {any} */ r) => r.object));
    assert.equal(asset.objects.length, objects.size);
    for (const o of asset.objects) {
      const m = o.object.mesh;
      for (const recon of /** @type {const} */ (['smooth', 'nearest', 'gouraud'])) {
        const t = objectTables(o.object, recon);
        assert.equal(t.treeDepth, o.object.treeDepth);
        assert.equal(t.topology.vertexCount, m.positions.length / 3);
        assert.equal(t.topology.triangleCount, m.triangles.length / 3);
        assert.equal(t.topology.edgeCount, Math.max(...m.edges) + 1);
        assert.equal(t.loop === null, o.object.kind === 'flat');
        if (recon === 'nearest') {
          assert.deepEqual(Array.from(t.light), [0]);
          continue;
        }
        // Header words point inside the table, in order.
        const words = t.light;
        assert.ok(words[0] > 2 && words[0] <= words[1] && words[1] < words.length);
      }
      assert.ok(o.instances.length >= 1, `${o.object.name} has an instance`);
    }
  });
}

for (const c of manifest.cases.filter((/** @type {any} */ c) => !c.valid)) {
  test(`invalid: ${c.file} is refused with the CLI's message`, async (t) => {
    const hce = hceBinary(t);
    if (!hce) return;
    const run = (/** @type {string[]} */ args) => spawnSync(hce, args, { cwd: path.join(REPO, 'conformance'), encoding: 'utf8' });
    // `hce reference` opens the asset (Asset::open) before anything else; its message, less the
    // `error: FILE: ` prefix the page does not repeat, is the one the browser must show. A glTF
    // whose root breaks a rule the native loader leaves to `hce validate` (the reference then
    // fails later, on its lights) gets validate's first problem instead.
    const opened = run(['reference', '-o', path.join(os.tmpdir(), 'hce-loader-test.exr'), '--size', '2x2', '--level', '0', c.file]);
    const validated = run(['validate', c.file]);
    assert.notEqual(validated.status, 0, `${c.file}: hce validate accepts it`);
    const wants = [opened.stderr.trim().replace(`error: ${c.file}: `, ''), validated.stdout.split('\n')[0]];
    const dir = path.dirname(path.join(REPO, 'conformance', c.file));
    await assert.rejects(
      async () => {
        const asset = await loadAsset(bytes(c.file), { name: c.file, resolveUri: async (uri) => new Uint8Array(fs.readFileSync(path.join(dir, uri))) });
        for (const o of asset.objects) objectTables(o.object);
      },
      (/** @type {unknown} */ e) => {
        assert.ok(e instanceof HceError, `an HceError, not ${e}`);
        assert.ok(wants.includes(e.message), `${e.message}\n  is neither of the CLI's messages\n  ${wants.join('\n  ')}`);
        return true;
      },
    );
  });
}
