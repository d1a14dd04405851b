// The baked samples the browser tests compare with hce: samples/*.glb baked by the workspace's
// `hce` (as `hce demo` bakes them), cached in target/hce-web/ beside the binary's other
// outputs and rebaked when the binary is newer.
import fs from 'node:fs';
import path from 'node:path';
import { execFileSync } from 'node:child_process';
import { REPO } from './browser.js';

/** The samples and the `hce bake` flags `hce demo` uses for each (tools/src/cmd/demo.rs). */
export const SAMPLES = /** @type {const} */ ([
  ['teatime', ['--creases', 'auto']],
  ['cornell-box', ['--multires', 'short_block', '--creases', 'auto']],
  ['chesstime', ['--creases', 'auto']],
]);

export const CACHE = path.join(REPO, 'target/hce-web');

/**
 * The baked sample `name`, baked now when missing or older than `hce`.
 * @param {string} hce the binary
 * @param {string} name
 */
export function bakedSample(hce, name) {
  const sample = SAMPLES.find(([n]) => n === name);
  if (!sample) throw new Error(`no sample ${name}`);
  fs.mkdirSync(CACHE, { recursive: true });
  const out = path.join(CACHE, `${name}-baked.glb`);
  const stale = !fs.existsSync(out) || fs.statSync(out).mtimeMs < fs.statSync(hce).mtimeMs;
  if (stale) {
    execFileSync(hce, ['bake', path.join(REPO, 'samples', `${name}.glb`), '-o', out, ...sample[1]], { stdio: ['ignore', 'ignore', 'inherit'] });
  }
  return out;
}

/**
 * Runs `hce` with `args`, returning its standard output.
 * @param {string} hce @param {string[]} args
 */
export function runHce(hce, args) {
  return execFileSync(hce, args, { encoding: 'utf8', stdio: ['ignore', 'pipe', 'inherit'], maxBuffer: 1 << 30 });
}
