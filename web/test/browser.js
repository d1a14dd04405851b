// Chromium for the browser tests: Debian's `chromium` driven by playwright-core, with WebGPU
// on (SwiftShader, a CPU fallback, where there is no GPU).
import fs from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { chromium } from 'playwright-core';
import { serve } from './server.js';

/** The repository root (web/ is one of its folders). */
export const REPO = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../..');

/** Where the browser is: `$CHROMIUM` when set, else the first of the usual Debian paths. */
export function chromiumPath() {
  const candidates = process.env.CHROMIUM ? [process.env.CHROMIUM] : ['/usr/bin/chromium', '/usr/bin/chromium-browser'];
  return candidates.find((p) => fs.existsSync(p)) ?? null;
}

/**
 * Whether a test without a browser must fail rather than skip: in CI (`CI=true`) or when
 * `HCE_REQUIRE_BROWSER=1`.
 */
export function browserRequired() {
  const yes = (/** @type {string | undefined} */ v) => v !== undefined && ['1', 'true', 'yes'].includes(v.trim());
  return yes(process.env.CI) || yes(process.env.HCE_REQUIRE_BROWSER);
}

/**
 * Starts the static server (web/, runtime/src/gpu/ and `extra` mounts) and a headless
 * Chromium with WebGPU (or, with `webgpu: false`, with WebGPU switched off: navigator.gpu
 * gives no adapter, as in a browser without WebGPU). Returns null, having said why, when there is no browser and
 * none is required; throws when one is required.
 * @param {import('node:test').TestContext} t
 * @param {Record<string, string>} [extra]
 * @param {{ webgpu?: boolean }} [options]
 */
export async function openBrowser(t, extra = {}, options = {}) {
  const exe = chromiumPath();
  if (exe === null) {
    const msg = 'no chromium (install Debian\'s `chromium` or set CHROMIUM)';
    if (browserRequired()) throw new Error(`${msg}; CI=true or HCE_REQUIRE_BROWSER=1 makes this a failure`);
    t.skip(msg);
    return null;
  }
  const server = await serve({
    '/web/': path.join(REPO, 'web'),
    '/runtime/src/gpu/': path.join(REPO, 'runtime/src/gpu'),
    ...extra,
  });
  const browser = await chromium.launch({
    executablePath: exe,
    args: ['--headless=new', '--no-sandbox', ...(options.webgpu ?? true ? ['--enable-unsafe-webgpu'] : ['--disable-features=WebGPU'])],
  });
  const page = await browser.newPage();
  /** @type {string[]} */
  const pageErrors = [];
  page.on('pageerror', (e) => pageErrors.push(String(e)));
  page.on('console', (m) => {
    if (process.env.HCE_BROWSER_LOG) console.log(`[page ${m.type()}] ${m.text()}`);
  });
  const close = async () => {
    await browser.close();
    await server.close();
  };
  return { page, url: server.url, pageErrors, close };
}

/**
 * The `hce` binary the comparisons run: `$HCE_BIN`, else the workspace's debug or release
 * build. Returns null, having said why, when there is none and none is required (a test run
 * before `cargo build -p hce-tools`); throws when CI requires the comparisons.
 * @param {import('node:test').TestContext} t
 */
export function hceBinary(t) {
  const candidates = [process.env.HCE_BIN, path.join(REPO, 'target/debug/hce'), path.join(REPO, 'target/release/hce')];
  const found = candidates.find((p) => p && fs.existsSync(p));
  if (found) return found;
  const msg = 'no hce binary (run `cargo build -p hce-tools` or set HCE_BIN)';
  if (browserRequired()) throw new Error(`${msg}; CI=true or HCE_REQUIRE_BROWSER=1 makes this a failure`);
  t.skip(msg);
  return null;
}
