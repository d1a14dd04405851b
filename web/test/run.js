// The browser tests' runner for CI (`.ci/run`): every test/*.test.js, one file at a time
// (each starts its own Chromium), the spec report as it goes, then one count line:
//   web: N passed, M failed, K skipped
// The exit status is 1 when any failed (or none ran). With CI=true (or HCE_REQUIRE_BROWSER=1) a missing
// chromium or hce binary is a failure, not a skip.
import { run } from 'node:test';
import { spec } from 'node:test/reporters';
import fs from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

const dir = path.dirname(fileURLToPath(import.meta.url));
const only = process.argv.slice(2);
const files = fs.readdirSync(dir)
  .filter((f) => f.endsWith('.test.js') && (only.length === 0 || only.some((o) => f.includes(o))))
  .sort()
  .map((f) => path.join(dir, f));

const counts = { passed: 0, failed: 0, skipped: 0 };
const stream = run({ files, concurrency: 1 });
stream.on('test:pass', (e) => {
  // Count the tests, not the files that hold them.
  if (e.nesting !== 0 || e.details?.type === 'suite' || e.file === e.name) return;
  if (e.skip || e.todo) counts.skipped += 1;
  else counts.passed += 1;
});
stream.on('test:fail', (e) => {
  if (e.nesting !== 0 || e.details?.type === 'suite') return;
  counts.failed += 1;
});
stream.compose(new spec()).pipe(process.stdout);
// Once every file has run and its report is written.
let printed = false;
process.on('beforeExit', () => {
  if (printed) return;
  printed = true;
  console.log(`web: ${counts.passed} passed, ${counts.failed} failed, ${counts.skipped} skipped`);
  process.exitCode = counts.failed > 0 || counts.passed + counts.skipped === 0 ? 1 : 0;
});
