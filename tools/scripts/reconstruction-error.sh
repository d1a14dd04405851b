#!/usr/bin/env bash
# How far `hce render` is from path-traced ground truth on multiresolution objects, per
# subdivision level: for each mesh, a test room around it (`gen-samples room`), baked twice
# (default normal sets, and `--max-normals 0`: the geometric normal alone), each bake drawn at
# levels 0..LEVELS with `hce render --cpu-reference --level L` (the smooth reconstruction, and
# for the default bake also the paper's nearest-normal rule), against `hce reference` of the
# same level; prints the relative RMS difference and bias over the reference's mask (pixels
# of the multiresolution object away from its silhouette), one row per mesh and level.
# The reference's own noise adds in quadrature: two 256-path references of the spot room differ
# by 5.4% RMS, so each carries about 3.8%; raise SAMPLES to resolve smaller errors. On the
# Cornell box (flat objects only) `hce render` is within 1.2% RMS and 0.1% bias of a 1024-path
# reference, which checks units, camera and pixel alignment.
#
# Usage: tools/scripts/reconstruction-error.sh [MESH ...]
#   MESH: names in $HCE_EXTRA_MESHES (default: spot suzanne teapot stanford-bunny), or paths.
# Environment (defaults in brackets):
#   HCE_EXTRA_MESHES  folder of the shared meshes [/work/shared/meshes]
#   SIZE [320x240]  SAMPLES [256]  LEVELS [3]  OUT [target/reconstruction-error]
#   HCE, GEN  the binaries [target/release/hce, target/release/gen-samples]
# Build first: cargo build --release -p hce-tools -p hce-samples
set -euo pipefail

root="$(cd "$(dirname "$0")/../.." && pwd)"
meshes_dir="${HCE_EXTRA_MESHES:-/work/shared/meshes}"
size="${SIZE:-320x240}"
samples="${SAMPLES:-256}"
levels="${LEVELS:-3}"
out="${OUT:-$root/target/reconstruction-error}"
hce="${HCE:-$root/target/release/hce}"
gen="${GEN:-$root/target/release/gen-samples}"
for bin in "$hce" "$gen"; do
    if [[ ! -x "$bin" ]]; then
        echo "error: $bin is missing; run: cargo build --release -p hce-tools -p hce-samples" >&2
        exit 2
    fi
done
if [[ $# -eq 0 ]]; then
    set -- spot suzanne teapot stanford-bunny
fi
mkdir -p "$out"
start=$SECONDS
rows=()
for mesh in "$@"; do
    if [[ -f "$mesh" ]]; then path="$mesh"; else path="$meshes_dir/$mesh.obj"; fi
    name="$(basename "$path" .obj)"
    dir="$out/$name"
    mkdir -p "$dir"
    echo "== $name" >&2
    # Turn the meshes that face away from +Z towards the camera.
    case "$name" in
        spot) turn=180 ;;
        teapot) turn=-30 ;;
        *) turn=0 ;;
    esac
    "$gen" room --mesh "$path" --turn "$turn" -o "$dir/room.glb" >&2
    "$hce" bake "$dir/room.glb" -o "$dir/baked-default.glb" --max-level "$levels" -q
    "$hce" bake "$dir/room.glb" -o "$dir/baked-n0.glb" --max-level "$levels" --max-normals 0 -q
    for level in $(seq 0 "$levels"); do
        # Both bakes share the geometry, so one reference (and mask) serves both.
        "$hce" reference "$dir/baked-default.glb" --level "$level" --size "$size" \
            --samples "$samples" -o "$dir/reference-$level.exr" --mask "$dir/mask-$level.png" \
            -q >/dev/null
        row="$name $level"
        for variant in default:smooth n0:smooth default:nearest; do
            bake="${variant%%:*}"
            rec="${variant##*:}"
            "$hce" render "$dir/baked-$bake.glb" --cpu-reference --level "$level" \
                --reconstruction "$rec" --size "$size" -o "$dir/$bake-$rec-$level.exr" \
                >/dev/null 2>&1
            row="$row $("$hce" compare "$dir/$bake-$rec-$level.exr" "$dir/reference-$level.exr" \
                --mask "$dir/mask-$level.png" | awk '
                    /^pixels:/ { p = $2 }
                    /^relative RMS:/ { r = $3 }
                    /^relative bias:/ { b = $3 }
                    END { printf "%s %.4f %+.4f", p, r, b }')"
        done
        rows+=("$row")
        echo "$row" >&2
    done
done
echo
printf '%-16s %5s %7s | %-19s | %-19s | %-19s\n' "" "" "" "default bake, smooth" \
    "--max-normals 0" "default, nearest"
printf '%-16s %5s %7s | %9s %9s | %9s %9s | %9s %9s\n' mesh level pixels "rel RMS" "bias" \
    "rel RMS" "bias" "rel RMS" "bias"
for row in "${rows[@]}"; do
    read -r name level px1 rms1 bias1 _px2 rms2 bias2 _px3 rms3 bias3 <<<"$row"
    printf '%-16s %5s %7s | %9s %9s | %9s %9s | %9s %9s\n' "$name" "$level" "$px1" "$rms1" \
        "$bias1" "$rms2" "$bias2" "$rms3" "$bias3"
done
echo
echo "($size, $samples paths per pixel, $((SECONDS - start)) s; images in $out)"
