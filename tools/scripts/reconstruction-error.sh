#!/usr/bin/env bash
# How far `hce render` is from path-traced ground truth on multiresolution objects, per
# subdivision level: for each mesh, a test room around it (`gen-samples room`), baked twice
# (default normal sets, and `--max-normals 0`: the geometric normal alone), each bake drawn at
# levels 0..LEVELS with `hce render --cpu-reference --level L` (the smooth reconstruction; for
# the default bake also the paper's nearest-normal rule; for the one-normal bake also
# `--reconstruction gouraud`, classic radiosity rendering), against `hce reference` of the
# same level; prints the relative RMS difference and bias over the reference's mask (pixels
# of the multiresolution object away from its silhouette), one row per mesh and level.
# The reference's own noise adds in quadrature: two 256-path references of the spot room differ
# by 5.4% RMS, so each carries about 3.8%; raise SAMPLES to resolve smaller errors, or set
# REFERENCES=2: two references of independent seeds, and the RMS error with their noise taken
# out, sqrt((rms1² + rms2²)/2 − d²/2) with d the relative RMS difference of the two references
# (each carries d²/2 of noise; printed as "noise"). On the Cornell box (flat objects only)
# `hce render` is within 1.2% RMS and 0.1% bias of a 1024-path reference, which checks units,
# camera and pixel alignment.
#
# The shared spot, teapot and bunny are fine meshes (5,900 to 69,000 triangles) whose coarse
# triangles barely turn; TRIANGLES=N simplifies each mesh to at most N triangles first
# (`gen-samples room --triangles N`), so that it is the coarse control mesh a multiresolution
# object is meant to be (suzanne, 966 triangles, already is).
#
# Usage: tools/scripts/reconstruction-error.sh [MESH ...]
#   MESH: names in $HCE_EXTRA_MESHES (default: spot suzanne teapot stanford-bunny), or paths.
# Environment (defaults in brackets):
#   HCE_EXTRA_MESHES  folder of the shared meshes [/work/shared/meshes]
#   SIZE [320x240]  SAMPLES [256]  LEVELS [3]  OUT [target/reconstruction-error]
#   TRIANGLES  simplify every mesh to at most this many triangles [unset: as it is]
#   REFERENCES  1 or 2 references per level (2: the noise is taken out) [1]
#   HCE, GEN  the binaries [target/release/hce, target/release/gen-samples]
# Build first: cargo build --release -p hce-tools -p hce-samples
set -euo pipefail

root="$(cd -P "$(dirname "$0")/../.." && pwd)"
meshes_dir="${HCE_EXTRA_MESHES:-/work/shared/meshes}"
size="${SIZE:-320x240}"
samples="${SAMPLES:-256}"
levels="${LEVELS:-3}"
out="${OUT:-$root/target/reconstruction-error}"
triangles="${TRIANGLES:-}"
references="${REFERENCES:-1}"
if [[ "$references" != 1 && "$references" != 2 ]]; then
    echo "error: REFERENCES must be 1 or 2" >&2
    exit 2
fi
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
    simplify=()
    dir="$out/$name"
    if [[ -n "$triangles" ]]; then
        simplify=(--triangles "$triangles")
        dir="$out/$name-$triangles"
    fi
    mkdir -p "$dir"
    echo "== $name" >&2
    # Turn the meshes that face away from +Z towards the camera.
    case "$name" in
        spot) turn=180 ;;
        teapot) turn=-30 ;;
        *) turn=0 ;;
    esac
    "$gen" room --mesh "$path" --turn "$turn" "${simplify[@]}" -o "$dir/room.glb" >&2
    "$hce" bake "$dir/room.glb" -o "$dir/baked-default.glb" --max-level "$levels" -q
    "$hce" bake "$dir/room.glb" -o "$dir/baked-n0.glb" --max-level "$levels" --max-normals 0 -q
    for level in $(seq 0 "$levels"); do
        # Both bakes share the geometry, so one reference (and mask) serves both.
        for k in $(seq 1 "$references"); do
            "$hce" reference "$dir/baked-default.glb" --level "$level" --size "$size" \
                --samples "$samples" --seed "$((k - 1))" -o "$dir/reference-$level-$k.exr" \
                --mask "$dir/mask-$level.png" -q >/dev/null
        done
        noise=0
        if [[ "$references" == 2 ]]; then
            noise="$("$hce" compare "$dir/reference-$level-1.exr" "$dir/reference-$level-2.exr" \
                --mask "$dir/mask-$level.png" | awk '/^relative RMS:/ { print $3 }')"
        fi
        row="$(basename "$dir") $level $noise"
        for variant in default:smooth n0:smooth default:nearest n0:gouraud; do
            bake="${variant%%:*}"
            rec="${variant##*:}"
            "$hce" render "$dir/baked-$bake.glb" --cpu-reference --level "$level" \
                --reconstruction "$rec" --size "$size" -o "$dir/$bake-$rec-$level.exr" \
                >/dev/null 2>&1
            # Mean square error and bias over the references, less the references' own noise.
            row="$row $(for k in $(seq 1 "$references"); do
                "$hce" compare "$dir/$bake-$rec-$level.exr" "$dir/reference-$level-$k.exr" \
                    --mask "$dir/mask-$level.png"
            done | awk -v d="$noise" -v n="$references" '
                /^pixels:/ { p = $2 }
                /^relative RMS:/ { s += $3 * $3 }
                /^relative bias:/ { b += $3 }
                END {
                    e = s / n - (n == 2 ? d * d / 2 : 0)
                    printf "%s %.4f %+.4f", p, (e > 0 ? sqrt(e) : 0), b / n
                }')"
        done
        rows+=("$row")
        echo "$row" >&2
    done
done
echo
if [[ "$references" == 2 ]]; then
    echo "(relative RMS errors with the references' noise taken out; noise: the relative RMS"
    echo " difference of the two references, each carrying noise/sqrt(2))"
fi
printf '%-20s %5s %7s %7s | %-19s | %-19s | %-19s | %-19s\n' "" "" "" "" \
    "default bake, smooth" "max-normals 0, smooth" "default, nearest" "max-normals 0, gouraud"
printf '%-20s %5s %7s %7s | %9s %9s | %9s %9s | %9s %9s | %9s %9s\n' mesh level pixels noise \
    "rel RMS" "bias" "rel RMS" "bias" "rel RMS" "bias" "rel RMS" "bias"
for row in "${rows[@]}"; do
    read -r name level noise px1 rms1 bias1 _px2 rms2 bias2 _px3 rms3 bias3 _px4 rms4 bias4 \
        <<<"$row"
    printf '%-20s %5s %7s %7s | %9s %9s | %9s %9s | %9s %9s | %9s %9s\n' "$name" "$level" \
        "$px1" "$noise" "$rms1" "$bias1" "$rms2" "$bias2" "$rms3" "$bias3" "$rms4" "$bias4"
done
echo
echo "($size, $samples paths per pixel, $references reference(s) per level, $((SECONDS - start)) s;"
echo " images in $out)"
