// The npm package in an app: `npm pack` of web/ (hce-web, with its WGSL, hce.wasm and .d.ts),
// installed into a copy of examples/vite/ beside its pinned three and Vite, imported there by
// bare specifier (`hce-web/three`), built by `vite build`; the bundle holds the kernels' WGSL
// and hce.wasm (the package reaches them through import.meta.url), TypeScript resolves the
// package's types for `hce-web` and `hce-web/three`, and the built app refines and draws the
// baked Teatime in Chromium on WebGPU with no wgslBase.
import test from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { execFileSync } from 'node:child_process';
import { openBrowser, hceBinary, REPO } from './browser.js';
import { bakedSample } from './samples.js';

const WEB = path.join(REPO, 'web');
const APP = path.join(WEB, 'examples', 'vite');

/** @param {string} cwd @param {string[]} args */
function npm(cwd, args) {
  return execFileSync('npm', args, { cwd, encoding: 'utf8', stdio: ['ignore', 'pipe', 'inherit'] });
}

test('the npm package installs, type-checks and bundles with Vite, and the built app draws', { timeout: 900_000 }, async (t) => {
  const hce = hceBinary(t);
  if (!hce) return;
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'hce-vite-'));
  try {
    const tarball = path.join(dir, npm(WEB, ['pack', '--pack-destination', dir, '--silent']).trim().split('\n').pop() ?? '');
    assert.ok(fs.existsSync(tarball), `npm pack wrote ${tarball}`);
    const app = path.join(dir, 'app');
    fs.mkdirSync(app);
    for (const f of ['package.json', 'package-lock.json', 'index.html', 'main.js', 'vite.config.js']) fs.copyFileSync(path.join(APP, f), path.join(app, f));
    npm(app, ['ci', '--no-audit', '--no-fund']);
    npm(app, ['install', '--no-save', '--no-audit', '--no-fund', tarball]);

    // TypeScript: both entry points resolve to the package's declarations (no TS7016).
    fs.writeFileSync(path.join(app, 'check.ts'), [
      "import { createRuntime, loadAsset, coarseRangeIndices } from 'hce-web';",
      "import { HceGLTFPlugin } from 'hce-web/three';",
      'export const used: unknown[] = [createRuntime, loadAsset, coarseRangeIndices, HceGLTFPlugin.runtime];',
      '',
    ].join('\n'));
    fs.writeFileSync(path.join(app, 'tsconfig.json'), JSON.stringify({
      compilerOptions: { target: 'es2022', module: 'es2022', moduleResolution: 'bundler', strict: true, noEmit: true, skipLibCheck: true, types: [], lib: ['es2022', 'dom'] },
      files: ['check.ts'],
    }));
    execFileSync(process.execPath, [path.join(WEB, 'node_modules', 'typescript', 'bin', 'tsc'), '-p', path.join(app, 'tsconfig.json')], { cwd: app, stdio: ['ignore', 'inherit', 'inherit'] });

    execFileSync(process.execPath, [path.join(app, 'node_modules', 'vite', 'bin', 'vite.js'), 'build', '--logLevel', 'warn'], { cwd: app, stdio: ['ignore', 'inherit', 'inherit'] });
    const assets = fs.readdirSync(path.join(app, 'dist', 'assets'));
    assert.ok(assets.some((f) => f.endsWith('.wasm')), `the bundle holds hce.wasm: ${assets.join(', ')}`);
    assert.ok(assets.some((f) => /^loop-.*\.wgsl$/.test(f)), `the bundle holds the kernels' WGSL: ${assets.join(', ')}`);
    const size = assets.filter((f) => f.endsWith('.js')).reduce((s, f) => s + fs.statSync(path.join(app, 'dist', 'assets', f)).size, 0);
    t.diagnostic(`bundle: ${assets.length} assets, ${(size / 1024).toFixed(0)} KiB of JavaScript (three.js's WebGPU build and hce-web)`);

    const baked = bakedSample(hce, 'teatime');
    const b = await openBrowser(t, { '/app/': path.join(app, 'dist'), '/files/': path.dirname(baked) });
    if (!b) return;
    try {
      await b.page.goto(`${b.url}/app/index.html?url=/files/${path.basename(baked)}`);
      await b.page.waitForFunction(() => { const s = /** @type {any} */ (window).hceExample; return s && (s.ok || s.error); }, null, { timeout: 600_000 });
      /** @type {any} */
      const s = await b.page.evaluate(() => /** @type {any} */ (window).hceExample);
      assert.equal(s.error, null);
      assert.equal(s.frames, 1);
      assert.equal(s.report.length, 8, JSON.stringify(s.report));
      for (const r of s.report) {
        assert.equal(r.path, 'gpu', `${r.name} refined by the kernels`);
        assert.ok(r.triangles > 0, r.name);
      }
      t.diagnostic(`the built app: ${s.report.map((/** @type {any} */ r) => `${r.name} ${r.triangles}${r.adaptive ? ' (trees)' : ` L${r.level}`}`).join(', ')}`);
      assert.deepEqual(b.pageErrors, []);
    } finally {
      await b.close();
    }
  } finally {
    fs.rmSync(dir, { recursive: true, force: true });
  }
});
