#!/usr/bin/env bash
# Builds hrtao (release), benchmarks the test scenes and generated server rooms with `hrtao bench`, and writes
# docs/benchmarks.md plus PNG plots in docs/bench/ (`bench-report`, the workspace's report tool).
# The rod and the cycloidal gearbox come from the repository (testdata/, assets/). Extra scenes that are not in the
# repository (engine, duplex, sf) and the Cycles references as PFM (what `hrtao bench --reference` reads) come from
# a folder named by HRTAO_SHARED (with scenes/ and refs/ as listed in its refs/index.json), when it is set.
# About 80 minutes on Mesa lavapipe with 2 cores at the defaults with all scenes (san_francisco alone about 55);
# BENCH_SIZE=320x180 takes about 15. Environment:
#   HRTAO_SHARED=DIR (unset: the repository's scenes only, without the external Cycles reference column)
#   BENCH_SIZE=WxH (640x360, the viewer's working size here)   BENCH_RAYS=B (8)   BENCH_SCENES="rod cycloidal ..."
#   BENCH_SCALE="rows:cols ..." (racks sizes)   BENCH_QUICK=1 (tiny settings, to check the script itself)
#   BENCH_HRTAO_FRAMES=N (32: still frames of HRTAO, ours and the paper's mode, for the error curves and flicker)
set -euo pipefail
cd "$(dirname "$0")/.."
SHARED=${HRTAO_SHARED:-}
OUT=docs/bench
SIZE=${BENCH_SIZE:-640x360}
W=${SIZE%x*}
H=${SIZE#*x}
RAYS=${BENCH_RAYS:-8}
# key:scene file:AO radius:folder (radii from refs/index.json; "repo" = this repository, "shared" = $HRTAO_SHARED)
ALL_SCENES="rod:testdata/scenes/rod_assembly/rod.glb:10:repo cycloidal:assets/default.glb:8:repo \
engine:scenes/2CylinderEngine/2CylinderEngine.gltf:40:shared duplex:scenes/duplex_apartment/duplex.glb:1:shared \
sf:scenes/san_francisco/san_francisco.glb:15:shared"
if [ -n "$SHARED" ]; then
  SCENES=${BENCH_SCENES:-rod cycloidal engine duplex sf}
else
  SCENES=${BENCH_SCENES:-rod cycloidal}
fi
# racks rows:cols (40 servers per rack of 2500 triangles): ~1e3 to ~4e5 instances, 2.5M to 1e9 triangles.
SCALE=${BENCH_SCALE:-"5:5 10:25 25:40 50:50 100:100"}
QUALITY="--max-rays 384 --ref-rays 768 --hrtao-frames ${BENCH_HRTAO_FRAMES:-32}"
NAV="--orbit 16 --repeat 3"
if [ -n "${BENCH_QUICK:-}" ]; then
  QUALITY="--max-rays 16 --ref-rays 32 --hrtao-frames 2"
  NAV="--orbit 3 --repeat 1 --settle 4"
fi

export MESA_SHADER_CACHE_DISABLE=${MESA_SHADER_CACHE_DISABLE:-true}
cargo build --release -p hrtao-viewer -p bench-report
BIN=${CARGO_TARGET_DIR:-target}/release/hrtao
REPORT=${CARGO_TARGET_DIR:-target}/release/bench-report
mkdir -p "$OUT"
# Only this script's own results: the STEP benchmark (scripts/bench-step.sh) writes step_*.json beside them.
rm -f "$OUT"/scene_*.json "$OUT"/scale_*.json "$OUT"/*.png
start=$(date +%s)

for key in $SCENES; do
  entry=$(tr ' ' '\n' <<<"$ALL_SCENES" | grep "^$key:" || true)
  [ -n "$entry" ] || { echo "unknown scene key $key" >&2; exit 1; }
  IFS=: read -r _ file radius where <<<"$entry"
  if [ "$where" = shared ]; then
    [ -n "$SHARED" ] || { echo "scene $key is not in the repository: set HRTAO_SHARED" >&2; exit 1; }
    file="$SHARED/$file"
    cam="$SHARED/refs/${key}_${W}x${H}.camera.json"
  else
    cam="testdata/refs/${key}_${W}x${H}.camera.json"
  fi
  # The same images as testdata/refs/*.cycles.exr, as PFM (what --reference reads).
  ref=""
  if [ -n "$SHARED" ]; then ref="$SHARED/refs/${key}_${W}x${H}.cycles.pfm"; fi
  args=(--scene "$file" --radius "$radius" --rays "$RAYS" --width "$W" --height "$H" --label "$key")
  [ -f "$cam" ] && args+=(--camera "$cam")
  [ -n "$ref" ] && [ -f "$ref" ] && [ -f "$cam" ] && args+=(--reference "$ref")
  echo "== $key"
  # shellcheck disable=SC2086
  "$BIN" bench "${args[@]}" $NAV $QUALITY --json "$OUT/scene_$key.json"
done

for rc in $SCALE; do
  rows=${rc%:*}
  cols=${rc#*:}
  spec="gen:racks?rows=$rows&cols=$cols&units=40&detail=2500"
  echo "== $spec"
  # shellcheck disable=SC2086
  "$BIN" bench --scene "$spec" --auto-camera corner --rays "$RAYS" --width "$W" --height "$H" \
    --group scale --label "racks ${rows}x${cols}" --no-quality $NAV \
    --json "$OUT/scale_racks_${rows}x${cols}.json"
done

"$REPORT" "$OUT" --markdown docs/benchmarks.md
echo "bench-docs: done in $(( $(date +%s) - start )) s"
