// Runs gltf-transform's CLI with hce.config.mjs on the three baked samples and a scene with
// instances (the Cornell box with its short block's mesh drawn twice) and checks that the
// baked lighting survives: the root object, the container bytes (byte for byte, 256-aligned in
// the buffer), `hce validate`'s verdict, the Khronos glTF-Validator's (no error, no warning),
// and `hce render` of the output against `hce render` of the original: relative RMS over the
// image (`hce compare`) at most 1.5% where every link is kept (measured: 0 for the commands that
// keep positions; 0-0.81% after quantize and meshopt, whose quantized node transforms move the
// surface within a quantization step, so that silhouettes shift by a pixel here and there). HCE_BIN is the hce binary (default: the workspace's
// dev build); HCE_BAKED_DIR may hold already baked SAMPLE-baked.glb files, otherwise the samples
// are baked here with cheap settings (the extension's structure does not depend on them).
import assert from 'node:assert/strict';
import { execFileSync, spawnSync } from 'node:child_process';
import { mkdtempSync, readFileSync, existsSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { dirname, join, resolve } from 'node:path';
import { test } from 'node:test';
import { fileURLToPath } from 'node:url';
import { createRequire } from 'node:module';

const validator = createRequire(import.meta.url)('gltf-validator');

const here = dirname(fileURLToPath(import.meta.url));
const pkg = resolve(here, '..');
const repo = resolve(pkg, '../..');
const hce = process.env.HCE_BIN ?? join(repo, 'target/debug/hce');
const cli = join(pkg, 'node_modules/@gltf-transform/cli/bin/cli.js');
const config = join(pkg, 'hce.config.mjs');
const work = mkdtempSync(join(tmpdir(), 'hce-gltf-transform-'));

const SAMPLES = { teatime: ['--creases', 'auto'], chesstime: ['--creases', 'auto'], 'cornell-box': [], 'instanced-box': [] };

// Outputs `hce validate` accepts: the same geometry (SPEC.md 2.6) holds through a changed
// triangle or vertex order, quantized positions and meshopt compression.
const VALID = ['copy', 'prune', 'dedup', 'instance', 'flatten', 'join', 'weld', 'reorder', 'quantize', 'meshopt', 'optimize'];
// Outputs hce cannot check (its readers have no Draco decoder, SPEC.md 2.6): valid, each Draco
// primitive a warning, drawn without the baked lighting.
const UNCHECKED = ['draco'];

function readGlb(path) {
  const bytes = readFileSync(path);
  const jsonLength = bytes.readUInt32LE(12);
  const json = JSON.parse(bytes.subarray(20, 20 + jsonLength).toString('utf8'));
  const binStart = 20 + jsonLength + 8;
  const binLength = bytes.readUInt32LE(20 + jsonLength);
  return { json, bin: bytes.subarray(binStart, binStart + binLength) };
}

function container(path) {
  const { json, bin } = readGlb(path);
  const root = json.extensions?.EXT_hce_baked_lighting;
  assert.ok(root, `${path}: no root EXT_hce_baked_lighting object`);
  assert.ok(json.extensionsUsed.includes('EXT_hce_baked_lighting'));
  assert.ok(!(json.extensionsRequired ?? []).includes('EXT_hce_baked_lighting'));
  const view = json.bufferViews[root.bufferView];
  const offset = view.byteOffset ?? 0;
  const links = (json.meshes ?? []).flatMap((m) => m.primitives).filter((p) => p.extensions?.EXT_hce_baked_lighting);
  return { offset, bytes: bin.subarray(offset, offset + view.byteLength), links: links.length, buffer: view.buffer };
}

/**
 * The Cornell box with instances: its short block's mesh drawn by a second node too, moved
 * and turned (a scene whose meshes are shared by several nodes, as instanced props are).
 */
function instancedBox() {
  const { json, bin } = readGlb(join(repo, 'samples', 'cornell-box.glb'));
  const block = json.nodes.findIndex((/** @type {any} */ n) => n.name === 'short_block');
  json.nodes.push({ name: 'short_block_copy', mesh: json.nodes[block].mesh, translation: [-0.25, 0.0, 0.2], rotation: [0, 0.3826834, 0, 0.9238795], scale: [0.5, 0.5, 0.5] });
  json.scenes[json.scene ?? 0].nodes.push(json.nodes.length - 1);
  let text = JSON.stringify(json);
  while (text.length % 4 !== 0) text += ' ';
  const out = join(work, 'instanced-box.glb');
  const chunk = (/** @type {Buffer} */ data, /** @type {string} */ type) => {
    const head = Buffer.alloc(8);
    head.writeUInt32LE(data.length, 0);
    head.write(type, 4);
    return Buffer.concat([head, data]);
  };
  const body = Buffer.concat([chunk(Buffer.from(text), 'JSON'), chunk(Buffer.from(bin), 'BIN\0')]);
  const header = Buffer.alloc(12);
  header.write('glTF', 0);
  header.writeUInt32LE(2, 4);
  header.writeUInt32LE(12 + body.length, 8);
  writeFileSync(out, Buffer.concat([header, body]));
  return out;
}

function baked(name) {
  const dir = process.env.HCE_BAKED_DIR;
  if (dir && existsSync(join(dir, `${name}-baked.glb`))) return join(dir, `${name}-baked.glb`);
  const out = join(work, `${name}-baked.glb`);
  const input = name === 'instanced-box' ? instancedBox() : join(repo, 'samples', `${name}.glb`);
  execFileSync(hce, ['bake', input, '-o', out, '-q', '--detail-level', '4', '--visibility-rays', '2', ...SAMPLES[name]]);
  return out;
}

/** `hce render` of `glb` at a small size, as linear EXR; the path. */
function render(glb) {
  const out = glb.replace(/\.glb$/, '.exr');
  const run = spawnSync(hce, ['render', glb, '--size', '160x120', '-o', out], { encoding: 'utf8' });
  assert.equal(run.status, 0, `hce render ${glb}: ${run.stderr}`);
  return out;
}

/** `hce compare`'s relative RMS of `image` against `reference`. */
function relativeRms(image, reference) {
  const run = spawnSync(hce, ['compare', '--json', image, reference], { encoding: 'utf8' });
  assert.equal(run.status, 0, `hce compare: ${run.stderr}`);
  return JSON.parse(run.stdout).relative_rms;
}

for (const name of Object.keys(SAMPLES)) {
  test(`${name}: gltf-transform commands keep the baked lighting`, async (t) => {
    const input = baked(name);
    const original = container(input);
    const reference = render(input);
    const figures = [];
    for (const command of [...VALID, ...UNCHECKED]) {
      const output = join(work, `${name}-${command}.glb`);
      const run = spawnSync(process.execPath, [cli, command, input, output, '--config', config], { encoding: 'utf8' });
      assert.equal(run.status, 0, `${command}: ${run.stderr}`);
      assert.doesNotMatch(run.stdout + run.stderr, /Missing optional extension/);
      const kept = container(output);
      assert.equal(kept.offset % 256, 0, `${command}: container at byte ${kept.offset}`);
      assert.ok(Buffer.compare(kept.bytes, original.bytes) === 0, `${command}: container bytes differ`);
      const validate = spawnSync(hce, ['validate', output], { encoding: 'utf8' });
      assert.equal(validate.status, 0, `${command}: ${validate.stdout}`);
      // The Khronos glTF-Validator: infos only (the unknown extension is one).
      const report = await validator.validateBytes(new Uint8Array(readFileSync(output)), { uri: output, maxIssues: 20 });
      const faults = report.issues.messages.filter((m) => m.severity < 2).map((m) => `${m.code} ${m.pointer ?? ''}: ${m.message}`);
      assert.equal(report.issues.numErrors + report.issues.numWarnings, 0, `${command}: glTF-Validator: ${faults.join('; ')}`);
      if (VALID.includes(command)) {
        // `join` (and `optimize`, which joins and simplifies) drops the links of the primitives it
        // merges across objects, with a warning; every other command keeps them all.
        if (command === 'join' || command === 'optimize') {
          assert.ok(kept.links > 0 && kept.links <= original.links, `${command}: ${kept.links} links`);
        } else {
          assert.equal(kept.links, original.links, `${command}: links lost`);
        }
        const rms = relativeRms(render(output), reference);
        figures.push(`${command} ${(100 * rms).toFixed(2)}%${kept.links < original.links ? ` (${original.links - kept.links} links dropped)` : ''}`);
        // Where links are dropped, those objects are not drawn: the image differs, as it says.
        if (kept.links === original.links) assert.ok(rms <= 0.015, `${command}: hce render differs from the original's by ${(100 * rms).toFixed(2)}%`);
      } else {
        const warnings = validate.stderr.split('\n').filter((line) => line.startsWith('warning:'));
        assert.ok(warnings.length > 0, `${command}: no warning`);
        for (const line of warnings) {
          assert.match(line, /^warning: meshes\[\d+\]\.primitives\[\d+\]: cannot check: KHR_draco_mesh_compression/,
            `${command}: unexpected warning ${line}`);
        }
        // hce has no Draco decoder: `hce render` refuses the file, saying why.
        const run = spawnSync(hce, ['render', output, '--size', '160x120', '-o', output.replace(/\.glb$/, '.exr')], { encoding: 'utf8' });
        assert.notEqual(run.status, 0);
        assert.match(run.stderr, /^error: .*: meshes\[\d+\]\.primitives\[\d+\]: cannot check: KHR_draco_mesh_compression-compressed data is not decoded by hce/m);
      }
    }
    t.diagnostic(`${name}: hce render against the original's, relative RMS: ${figures.join(', ')}`);
  });
}

// An optimiser without hce's config drops the extension; optimising first and baking the result
// keeps everything: `hce bake` reads gltf-transform's quantized output (KHR_mesh_quantization:
// integer positions and normals dequantized through the node) as it reads the original.
test('hce bake reads quantized input (KHR_mesh_quantization) and bakes the same light', () => {
  const name = 'cornell-box';
  const plain = join(repo, 'samples', `${name}.glb`);
  const quantized = join(work, `${name}-quantized-plain.glb`);
  const run = spawnSync(process.execPath, [cli, 'quantize', plain, quantized], { encoding: 'utf8' });
  assert.equal(run.status, 0, run.stderr);
  const { json } = readGlb(quantized);
  assert.ok((json.extensionsRequired ?? []).includes('KHR_mesh_quantization'));
  const flags = ['-q', '--detail-level', '4', '--visibility-rays', '2'];
  const bakedQuantized = join(work, `${name}-quantized-baked.glb`);
  const bakedPlain = join(work, `${name}-plain-baked.glb`);
  execFileSync(hce, ['bake', quantized, '-o', bakedQuantized, ...flags]);
  execFileSync(hce, ['bake', plain, '-o', bakedPlain, ...flags]);
  const validate = spawnSync(hce, ['validate', bakedQuantized], { encoding: 'utf8' });
  assert.equal(validate.status, 0, validate.stdout + validate.stderr);
  assert.equal(container(bakedQuantized).links, container(bakedPlain).links);
  const rms = relativeRms(render(bakedQuantized), render(bakedPlain));
  assert.ok(rms <= 0.015, `the quantized input's bake renders ${(100 * rms).toFixed(2)}% away from the original's`);
});

// The browser viewer (web/viewer.html, through hce.wasm) opens every output of the Cornell box
// that the first tests wrote: the baked lighting where links are kept, no error on the page.
test('the browser viewer draws every output of the Cornell box', { timeout: 600_000 }, async (t) => {
  const { openBrowser } = await import('../../test/browser.js');
  const b = await openBrowser(t, { '/out/': work });
  if (!b) return;
  try {
    const drawn = [];
    for (const command of VALID) {
      const file = `cornell-box-${command}.glb`;
      if (!existsSync(join(work, file))) {
        t.skip('the Cornell box outputs were not written (run the whole file)');
        return;
      }
      await b.page.goto(`${b.url}/web/viewer.html?url=/out/${file}&size=160x120`);
      await b.page.waitForFunction(() => /** @type {any} */ (window).hceViewer?.frames > 0 || /** @type {any} */ (window).hceViewer?.error, null, { timeout: 120_000 });
      const state = await b.page.evaluate(() => JSON.parse(JSON.stringify(/** @type {any} */ (window).hceViewer)));
      assert.equal(state.error, null, `${command}: ${state.error}`);
      const warnings = (await b.page.textContent('#warnings')) ?? '';
      assert.doesNotMatch(warnings, /no baked lighting/, `${command}: ${warnings}`);
      drawn.push(`${command} ${state.levels.length} objects`);
    }
    assert.deepEqual(b.pageErrors, []);
    t.diagnostic(`drawn: ${drawn.join(', ')}`);
  } finally {
    await b.close();
  }
});

// The conformance files glTF Transform wrote (conformance/manifest.json names each command in
// `generated_by`) are what its commands write today, byte for byte: the suite's meshopt and
// Draco cases are the tools' real streams, and remade by these commands when the grid changes.
test('the conformance files written by gltf-transform are what its commands write', () => {
  const manifest = JSON.parse(readFileSync(join(repo, 'conformance/manifest.json'), 'utf8'));
  const made = manifest.cases.filter((/** @type {any} */ c) => /^@gltf-transform\/cli /.test(c.generated_by ?? ''));
  assert.ok(made.length >= 2, `${made.length} cases made by gltf-transform`);
  for (const c of made) {
    const words = c.generated_by.replace(/^[^:]*: gltf-transform /, '').split(/\s+/);
    const [command, input, output, ...rest] = words;
    assert.equal(output, `conformance/${c.file}`, c.generated_by);
    const out = join(work, `conformance-${command}.glb`);
    const options = rest.map((w) => (w.startsWith('web/') ? join(repo, w) : w));
    const run = spawnSync(process.execPath, [cli, command, join(repo, input), out, ...options], { encoding: 'utf8' });
    assert.equal(run.status, 0, `${command}: ${run.stderr}`);
    assert.ok(Buffer.compare(readFileSync(out), readFileSync(join(repo, output))) === 0, `${c.file} differs from what \`${c.generated_by}\` writes now; remake it (conformance/README.md)`);
  }
});
