#!/usr/bin/env bash
# hce against a path tracer at equal error: what a user pays for light of a given accuracy,
# baked once by `hce bake` and drawn by `hce render`, or path-traced by `hce reference` (the
# peer: an independent unidirectional path tracer of the same geometry, materials and camera,
# next-event estimation on the emitters, in `bake/src/reference.rs`).
#
# For one scene (default: the bundled Cornell box, flat objects only), two references of
# independent seeds at REFERENCE_SAMPLES paths per pixel; then
#   - for each bake setting in BAKES (`default`, or `hce bake` options joined by commas, e.g.
#     `--bf-epsilon,1e-5`): the wall time of `hce bake`, and the error of `hce render
#     --cpu-reference` of the bake (the smooth reconstruction, the file's camera);
#   - for each count in SAMPLES: the wall time of `hce reference --samples N` (another seed),
#     and its error;
# each error the relative RMS difference from the two references with their own noise taken
# out, sqrt((e1² + e2²)/2 − d²/2), d the relative RMS difference of the two references, as
# tools/scripts/reconstruction-error.sh does; and the bias. Both sides use every core. The
# pixels of the emitters named by EXCLUDE are left out (tools/scripts/fold-masks.py): both
# methods give their emission exactly, and it would swamp the sums.
#
# Usage: tools/scripts/against-path-tracer.sh [SCENE.glb]
# Environment (defaults in brackets):
#   SIZE [160x160]  REFERENCE_SAMPLES [8192]  SAMPLES ["4 16 64 256 1024"]
#   BAKES ["default --bf-epsilon,3e-5 --bf-epsilon,1e-5"]  EXCLUDE [light]
#   OUT [target/against-path-tracer]
#   HCE  the binary [target/release/hce]; build first: cargo build --release -p hce-tools
set -euo pipefail

root="$(cd -P "$(dirname "$0")/../.." && pwd)"
scene="${1:-$root/samples/cornell-box.glb}"
size="${SIZE:-160x160}"
reference_samples="${REFERENCE_SAMPLES:-8192}"
samples="${SAMPLES:-4 16 64 256 1024}"
bakes="${BAKES:-default --bf-epsilon,3e-5 --bf-epsilon,1e-5}"
exclude="${EXCLUDE:-light}"
out="${OUT:-$root/target/against-path-tracer}"
hce="${HCE:-$root/target/release/hce}"
# shellcheck source=tools/scripts/timing.sh
source "$root/tools/scripts/timing.sh"
require_inputs "$hce" "$scene"
mkdir -p "$out"

# The reference path tracer reads a baked file (materials, lights, camera): bake once.
"$hce" bake "$scene" -o "$out/baked-default.glb" -q
for k in 1 2; do
    echo "reference $k: $reference_samples paths per pixel" >&2
    "$hce" reference "$out/baked-default.glb" --level 0 --size "$size" \
        --samples "$reference_samples" --seed "$k" -o "$out/reference-$k.exr" -q \
        >"$out/reference-$k.txt"
done
camera="$(sed -n 's/.*camera \([^)]*\)).*/\1/p' "$out/reference-1.txt")"
python3 "$root/tools/scripts/fold-masks.py" "$scene" --camera "$camera" --size "$size" \
    --objects "$exclude" --exclude "$exclude" --near 0 --far 0 "$out/band.png" "$out/mask.png"
noise="$("$hce" compare "$out/reference-1.exr" "$out/reference-2.exr" --mask "$out/mask.png" |
    awk '/^relative RMS:/ { print $3 }')"

# Error of an image against the two references, their noise taken out: "RMS BIAS".
error() {
    for k in 1 2; do
        "$hce" compare "$1" "$out/reference-$k.exr" --mask "$out/mask.png"
    done | awk -v d="$noise" '
        /^relative RMS:/ { s += $3 * $3 }
        /^relative bias:/ { b += $3 }
        END { e = s / 2 - d * d / 2; printf "%.4f %+.4f", (e > 0 ? sqrt(e) : 0), b / 2 }'
}

rows=()
for setting in $bakes; do
    name="${setting//,/ }"
    args=()
    if [[ "$setting" != default ]]; then
        IFS=, read -r -a args <<<"$setting"
    fi
    file="$out/baked-${setting//[^A-Za-z0-9.]/_}.glb"
    echo "hce bake $name" >&2
    t0="$(now)"
    "$hce" bake "$scene" -o "$file" -q "${args[@]}"
    t1="$(now)"
    "$hce" render "$file" --cpu-reference --size "$size" -o "${file%.glb}.exr" >/dev/null 2>&1
    read -r rms bias <<<"$(error "${file%.glb}.exr")"
    rows+=("hce bake|$name|$(elapsed "$t0" "$t1")|$rms|$bias")
done
for n in $samples; do
    echo "hce reference --samples $n" >&2
    t0="$(now)"
    "$hce" reference "$out/baked-default.glb" --level 0 --size "$size" --samples "$n" \
        --seed 1000 -o "$out/traced-$n.exr" -q >/dev/null
    t1="$(now)"
    read -r rms bias <<<"$(error "$out/traced-$n.exr")"
    rows+=("hce reference|$n paths per pixel|$(elapsed "$t0" "$t1")|$rms|$bias")
done

echo
echo "| method | setting | seconds | relative RMS error | bias |"
echo "|---|---|---|---|---|"
for row in "${rows[@]}"; do
    IFS='|' read -r method setting secs rms bias <<<"$row"
    echo "| $method | $setting | $secs | $rms | $bias |"
done
echo
echo "($(basename "$scene"), $size without the pixels of $exclude, references of $reference_samples paths per pixel whose"
echo " relative RMS difference is $noise (each carries that over sqrt 2, taken out above);"
echo " images in $out)"
