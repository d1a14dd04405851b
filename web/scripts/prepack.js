// What `npm pack` (and `npm publish`) runs first: the package's build outputs, none of them
// checked in. wgsl/ gets the kernels' WGSL, copied byte for byte from the directory the Rust
// runtime compiles them from (runtime/src/gpu/: the browser runs the very files the Rust
// runtime runs), types/ the .d.ts of src/ from its JSDoc, and src/hce.wasm must have been
// built (web/build-wasm.sh): the package is refused without it rather than shipped broken.
import { execFileSync } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

const web = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '..');
const gpu = path.join(web, '..', 'runtime', 'src', 'gpu');
const wasm = path.join(web, 'src', 'hce.wasm');
if (!fs.existsSync(wasm)) {
  console.error(`prepack: ${path.relative(process.cwd(), wasm)} is missing; build it with web/build-wasm.sh first`);
  process.exit(1);
}
const out = path.join(web, 'wgsl');
fs.rmSync(out, { recursive: true, force: true });
fs.mkdirSync(out);
const files = fs.readdirSync(gpu).filter((f) => f.endsWith('.wgsl')).sort();
for (const f of files) fs.copyFileSync(path.join(gpu, f), path.join(out, f));
fs.rmSync(path.join(web, 'types'), { recursive: true, force: true });
execFileSync(process.execPath, [path.join(web, 'node_modules', 'typescript', 'bin', 'tsc'), '-p', path.join(web, 'tsconfig.types.json')], { stdio: 'inherit' });
console.error(`prepack: wgsl/ (${files.length} files from runtime/src/gpu/), types/, src/hce.wasm (${fs.statSync(wasm).size} bytes)`);
