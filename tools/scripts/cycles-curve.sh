#!/usr/bin/env bash
# hce against Blender Cycles on the Cornell box: error against time, both baking the light at
# the same points, in one run on one machine.
#
# The points are the level-2 vertices of the baked scene (`hce subdivide --level 2 --merge`:
# every object refined as the runtime refines it, SPEC.md Appendix F). hce's value at a point
# is the radiosity its smooth reconstruction draws there (Appendix G); Cycles' is its diffuse
# bake (direct + indirect light times the colour, the outgoing radiance of the Lambertian
# surface, the same number) into a vertex-colour attribute of the same meshes, on the CPU
# (tools/scripts/cycles-curve.py says how the scene is rebuilt in Blender). Both use every core.
#
#   - the reference: Cycles at REFERENCE_SAMPLES samples per point, REFERENCE_SEEDS seeds,
#     averaged; its noise is the RMS between seeds divided by sqrt(REFERENCE_SEEDS);
#   - for each bake setting in BAKES (`hce bake` options joined by commas, or `default`):
#     the wall time of the whole `hce bake`, and the error of its level-2 vertices;
#   - for each count in SAMPLES: the time of Cycles' bake (the bake operator: scene sync,
#     BVH and paths) and its error (another seed than the reference's);
# each error the relative RMS difference from the reference over the points and channels of
# the objects that do not emit, as measured and with the reference's noise taken out.
#
# Usage: tools/scripts/cycles-curve.sh [SCENE.glb]
# Environment (defaults in brackets):
#   REFERENCE_SAMPLES [2048]  REFERENCE_SEEDS [8]  SAMPLES ["64 256 1024 4096"]
#   BAKES ["--quality,draft --quality,default --quality,high"]
#   OUT [target/cycles-curve]  NUDGE [0.0005] (metres; see cycles-curve.py)
#   HCE  the binary [target/release/hce]; build first: cargo build --release -p hce-tools
#   VENV the virtual environment with bpy [target/bpy-venv]; made from
#        tools/scripts/cycles-curve-requirements.txt when missing (bpy needs Python 3.11)
#   PYTHON the Python that makes it [python3.11]
# Writes OUT/cycles-curve.md (the table) and OUT/cycles-curve.csv.
set -euo pipefail

root="$(cd -P "$(dirname "$0")/../.." && pwd)"
scene="${1:-$root/samples/cornell-box.glb}"
reference_samples="${REFERENCE_SAMPLES:-2048}"
reference_seeds="${REFERENCE_SEEDS:-8}"
samples="${SAMPLES:-64 256 1024 4096}"
bakes="${BAKES:---quality,draft --quality,default --quality,high}"
out="${OUT:-$root/target/cycles-curve}"
nudge="${NUDGE:-0.0005}"
hce="${HCE:-$root/target/release/hce}"
venv="${VENV:-$root/target/bpy-venv}"
python="${PYTHON:-python3.11}"
# shellcheck source=tools/scripts/timing.sh
source "$root/tools/scripts/timing.sh"
require_inputs "$hce" "$scene"
if [[ ! -x "$venv/bin/python" ]]; then
    echo "making $venv (bpy from PyPI)" >&2
    "$python" -m venv "$venv"
    "$venv/bin/pip" install -q -r "$root/tools/scripts/cycles-curve-requirements.txt"
fi
mkdir -p "$out"

hce_args=()
for setting in $bakes; do
    args=()
    if [[ "$setting" != default ]]; then
        IFS=, read -r -a args <<<"$setting"
    fi
    name="${setting//,/ }"
    file="$out/baked-${setting//[^A-Za-z0-9.]/_}"
    echo "hce bake $name" >&2
    t0="$(now)"
    "$hce" bake "$scene" -o "$file.glb" -q ${args[@]+"${args[@]}"}
    seconds="$(elapsed "$t0" "$(now)")"
    "$hce" subdivide "$file.glb" --level 2 --flat uniform --merge --unclamped --stats -o "$file-level2.obj" >"$file-level2.txt"
    hce_args+=(--hce "$name=$seconds=$file-level2.obj")
    points="$file-level2"
done

"$venv/bin/python" "$root/tools/scripts/cycles-curve.py" \
    --points "$points.obj" --stats "$points.txt" --scene "$scene" \
    --reference-samples "$reference_samples" --reference-seeds "$reference_seeds" \
    --samples "$samples" --nudge "$nudge" "${hce_args[@]}" \
    --markdown "$out/cycles-curve.md" --csv "$out/cycles-curve.csv"
cat "$out/cycles-curve.md"
