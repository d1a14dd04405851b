#!/usr/bin/env bash
# The real-GPU figures of BENCHMARKS.md in one run of a few minutes: the kernels' throughput
# (`hce bench-gpu`, flat and Loop, levels 1-5) as a fraction of the store-only kernel and of the
# device's memory bandwidth, the Teatime and Chesstime flights of `hce view --offscreen`, and
# the batched scenes of many small flat and multiresolution objects.
#
# A lent GPU machine is bare and cannot reach the registries, so the work is split in two:
#
#   tools/scripts/gpu-figures.sh --prepare DIR   # here: a stripped release `hce` and the baked
#                                                # samples into DIR (about 30 MB)
#   tools/scripts/gpu-figures.sh --run DIR OUT   # there: every figure into OUT (text, JSON and
#                                                # summary.md, the tables BENCHMARKS.md takes)
#
# `--run` also works on this machine's lavapipe (add HCE_SOFTWARE=1 to force a software
# adapter), which is how the script itself is checked before a GPU is lent. The device's peak
# memory bandwidth comes from its name (H100/H200 figures below) or from PEAK_GBPS.
set -euo pipefail

usage() {
  sed -n '2,/^set -euo/p' "$0" | sed '$d' | sed 's/^# \{0,1\}//' >&2
  exit 2
}

# The Chesstime flight of BENCHMARKS.md ("A viewer's frames"); Teatime flies its scene camera
# towards its target.
CHESS_PATH="0.35,0.32,0.45:0,0.03,0:45;0.12,0.1,0.12:-0.05,0.04,-0.05:45;-0.02,0.07,-0.02:-0.3,0.05,-0.3:45;-0.2,0.15,-0.3:-0.5,0.0,-0.6:45"
TEA_PATH="approach:0.8"

prepare() {
  local dir=$1
  cd "$(dirname "$0")/../.."
  mkdir -p "$dir"
  echo "== building the release hce (cargo build --release -p hce-tools)"
  cargo build --release -p hce-tools
  cp target/release/hce "$dir/hce"
  strip "$dir/hce"
  echo "== baking the samples (samples/README.md's commands)"
  "$dir/hce" bake samples/teatime.glb -o "$dir/teatime-baked.glb" --creases auto
  "$dir/hce" bake samples/chesstime.glb -o "$dir/chesstime-baked.glb" --creases auto
  git rev-parse --short HEAD >"$dir/commit"
  du -sh "$dir"
}

# Peak memory bandwidth in GB/s from the adapter's name (vendor data sheets), or PEAK_GBPS.
peak_gbps() {
  if [ -n "${PEAK_GBPS:-}" ]; then
    echo "$PEAK_GBPS"
    return
  fi
  case "$1" in
    *H200*) echo 4800 ;;
    *"H100 NVL"*) echo 3900 ;;
    *"H100 PCIe"*) echo 2000 ;;
    *H100*) echo 3350 ;;
    *) echo "" ;;
  esac
}

run() {
  local dir out
  dir=$(cd "$1" && pwd)
  mkdir -p "$2"
  out=$(cd "$2" && pwd)
  local hce="$dir/hce"
  [ -x "$hce" ] || { echo "$hce: not found (run --prepare first)" >&2; exit 2; }
  local sw=()
  [ "${HCE_SOFTWARE:-0}" = 1 ] && sw=(--software)
  local levels=${LEVELS:-1,2,3,4,5}
  local repeats=${REPEATS:-5}

  {
    echo "commit: $(cat "$dir/commit" 2>/dev/null || echo unknown)"
    echo "date: $(date -u +%Y-%m-%dT%H:%MZ)"
    echo "host: $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg)"
    command -v nvidia-smi >/dev/null && nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader
  } >"$out/env.txt"
  cat "$out/env.txt"

  echo "== bench-gpu: flat and Loop, levels $levels"
  "$hce" bench-gpu "${sw[@]}" --kernel both --levels "$levels" --repeats "$repeats" \
    --reconstruction smooth --patch both | tee "$out/kernels.txt"
  if [ -n "${MESH:-}" ]; then
    echo "== bench-gpu: Loop on $MESH"
    "$hce" bench-gpu "${sw[@]}" --kernel loop --mesh "$MESH" --levels "${MESH_LEVELS:-1,2,3}" \
      --repeats 3 --reconstruction smooth | tee "$out/kernels-mesh.txt"
  fi

  echo "== bench-gpu: many small flat and multiresolution objects"
  "$hce" bench-gpu "${sw[@]}" --kernel scene --levels 2,3 --objects "${OBJECTS:-200,1000,5000}" \
    --repeats "${SCENE_REPEATS:-7}" | tee "$out/scene.txt"

  local frames=${FRAMES:-60}
  for budget in 0 4; do
    echo "== hce view --offscreen: Teatime and Chesstime, refine budget $budget ms"
    "$hce" view "$dir/teatime-baked.glb" "${sw[@]}" --offscreen --frames "$frames" \
      --size 800x600 --camera-path "$TEA_PATH" --refine-budget "$budget" \
      --stats "$out/flight-teatime-$budget.json"
    "$hce" view "$dir/chesstime-baked.glb" "${sw[@]}" --offscreen --frames "$frames" \
      --size 800x600 --camera-path "$CHESS_PATH" --refine-budget "$budget" \
      --stats "$out/flight-chesstime-$budget.json"
  done

  local adapter
  adapter=$(sed -n 's/^adapter: //p' "$out/kernels.txt" | head -1)
  summarise "$out" "$(peak_gbps "$adapter")" >"$out/summary.md"
  cat "$out/summary.md"
}

# summary.md: the kernels' rows with % of peak bandwidth, and each flight's frame statistics.
summarise() {
  python3 - "$1" "$2" <<'EOF'
import json, pathlib, re, statistics, sys

out, peak = pathlib.Path(sys.argv[1]), sys.argv[2]
peak = float(peak) if peak else None
env = (out / "env.txt").read_text().strip().splitlines()
print("# GPU figures\n")
for line in env:
    print(f"- {line}")
text = (out / "kernels.txt").read_text()
adapter = re.search(r"^adapter: (.*)$", text, re.M)
fill = re.search(r"device write bandwidth .*?: ([\d.]+) GB/s", text)
print(f"- adapter: {adapter.group(1) if adapter else '?'}")
print(f"- store-only kernel: {fill.group(1) if fill else '?'} GB/s; peak memory bandwidth: "
      f"{f'{peak:.0f} GB/s' if peak else 'unknown (set PEAK_GBPS)'}")
print("\n## Kernels (bytes written per second)\n")
print("| kernel | level | out tris | ms | Mtris/s | GB/s | % fill | % of peak |")
print("|---|---|---|---|---|---|---|---|")
kernel = None
for line in text.splitlines():
    if line.startswith("kernel: "):
        kernel = line[len("kernel: "):].split(" (")[0]
        continue
    f = line.split()
    if kernel and len(f) >= 9 and f[0].isdigit() and f[5] in ("gpu-ts", "wall"):
        gbps = float(f[7])
        of_peak = f"{100 * gbps / peak:.2f}%" if peak else "-"
        print(f"| {kernel} | {f[0]} | {int(f[2]):,} | {f[4]} | {f[6]} | {f[7]} | {f[8]}% | {of_peak} |")
print("\n## Flights (`hce view --offscreen`, 800 x 600; first frame left out)\n")
print("| scene | refine budget | frame mean | draw mean | refine mean | refine GPU mean | median / p90 / max frame | triangles (mean) | frames with a level not drawn yet |")
print("|---|---|---|---|---|---|---|---|---|")
for p in sorted(out.glob("flight-*.json")):
    scene, budget = p.stem.split("-")[1:]
    frames = json.loads(p.read_text())["frames"][1:]
    if not frames:
        continue
    ft = sorted(f["frame_ms"] for f in frames)
    mean = lambda k: statistics.fmean(f[k] for f in frames)
    gpu = [f["refine_gpu_ms"] for f in frames if f.get("refine_gpu_ms") is not None]
    print(f"| {scene} | {budget} ms | {mean('frame_ms'):.2f} ms | {mean('draw_ms'):.2f} ms | "
          f"{mean('refine_ms'):.2f} ms | {f'{statistics.fmean(gpu):.3f} ms' if gpu else '-'} | "
          f"{statistics.median(ft):.2f} / {ft[int(0.9 * (len(ft) - 1))]:.2f} / {ft[-1]:.2f} ms | "
          f"{mean('triangles'):,.0f} | {sum(1 for f in frames if f['pending'])} |")
print("\n## Many small flat objects\n")
print("```")
print((out / "scene.txt").read_text().strip())
print("```")
EOF
}

case "${1:-}" in
  --prepare) [ $# -eq 2 ] || usage; prepare "$2" ;;
  --run) [ $# -eq 3 ] || usage; run "$2" "$3" ;;
  *) usage ;;
esac
