#!/usr/bin/env bash
# Builds web/src/hce.wasm, the browser's reader, validator and table builder (wasm/, the Rust of
# hce-runtime's asset loading, hce-format and hce-geometry), where web/src/native.js loads it.
# It is a build output, not checked in: .ci/run builds it before the browser tests.
set -euo pipefail
cd "$(dirname "$0")/.."
rustup target add wasm32-unknown-unknown >/dev/null 2>&1 || true
# Without debug line tables (the release profile keeps them for native backtraces): they would
# more than double the download.
CARGO_PROFILE_RELEASE_DEBUG=false cargo build --release -p hce-wasm --target wasm32-unknown-unknown
cp target/wasm32-unknown-unknown/release/hce_wasm.wasm web/src/hce.wasm
echo "web/src/hce.wasm: $(wc -c < web/src/hce.wasm) bytes"
