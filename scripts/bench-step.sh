#!/usr/bin/env bash
# STEP/IGES against F3D: wall time from process start to a PNG, hrtao (`hrtao render`) and Debian's F3D
# (`f3d FILE --output`, the same OpenCASCADE kernel), run in turn (one warm-up each, then RUNS pairs), and the
# triangles each draws. Writes docs/bench/step_<file>_<quality>.json, which
# `cargo run -p bench-report -- docs/bench --markdown docs/benchmarks.md` renders as the "STEP/IGES: load to image
# against F3D" table. Three tessellations per file: F3D's (goal: triangles within ±20 % and wall time <= 1.5x F3D's),
# hrtao's default (0.5 % of each part's size and 35 degrees; goal <= 3x) and hrtao's fine one (CadTessellation::FINE,
# 0.1 % and 10 degrees, the default before B-rep faces carried surface normals; goal <= 3x). F3D 1.3 meshes with
# OpenCASCADE's per-edge relative deflection 0.1 and 0.5 rad; the nearest of hrtao's flags is one deflection of 1 mm
# and 28.65 degrees (the same triangles on AS1).
#
# Needs f3d (scripts/install-deps.sh --bench), the files of scripts/fetch-step-data.sh, and Xvfb when no DISPLAY
# is set (F3D opens an X window even for --output). Environment: RUNS (default 5), OUT (default docs/bench),
# HRTAO (default target/release/hrtao, built when missing), WIDTH/HEIGHT (default F3D's 1000x600).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
runs=${RUNS:-5}
out=${OUT:-$root/docs/bench}
width=${WIDTH:-1000}
height=${HEIGHT:-600}
hrtao=${HRTAO:-$root/target/release/hrtao}
command -v f3d >/dev/null || { echo "bench-step: f3d is missing (scripts/install-deps.sh --bench)" >&2; exit 1; }
if [ ! -x "$hrtao" ]; then
  (cd "$root" && cargo build --release -p hrtao-viewer)
fi
data=$("$root/scripts/fetch-step-data.sh")
mkdir -p "$out"
tmp=$(mktemp -d)
xvfb_pid=
cleanup() {
  [ -n "$xvfb_pid" ] && kill "$xvfb_pid" 2>/dev/null
  rm -rf "$tmp"
}
trap cleanup EXIT
if [ -z "${DISPLAY:-}" ]; then
  command -v Xvfb >/dev/null || { echo "bench-step: no DISPLAY and no Xvfb for F3D" >&2; exit 1; }
  Xvfb -displayfd 3 -screen 0 1280x800x24 3>"$tmp/display" >/dev/null 2>&1 &
  xvfb_pid=$!
  for _ in $(seq 50); do [ -s "$tmp/display" ] && break; sleep 0.1; done
  [ -s "$tmp/display" ] || { echo "bench-step: Xvfb did not start" >&2; exit 1; }
  export DISPLAY=":$(cat "$tmp/display")"
fi
f3d_version=$(f3d --version 2>/dev/null | awk '/^f3d/ {print $2; exit}')
cpu=$(awk -F': ' '/model name/ {print $2; exit}' /proc/cpuinfo)

# Seconds the command takes, from its start to its end (its output thrown away); fails when it fails.
seconds() {
  local t0=$EPOCHREALTIME
  "$@" >/dev/null 2>&1 || { echo "bench-step: failed: $*" >&2; return 1; }
  local t1=$EPOCHREALTIME
  awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.4f", b - a }'
}

# One file at one tessellation: QUALITY GOAL FILE HRTAO_FLAGS...
bench() {
  local quality=$1 goal=$2 file=$3
  shift 3
  local flags=("$@")
  local ours=(render --scene "$data/$file" --out "$tmp/ours.png" --width "$width" --height "$height" "${flags[@]}")
  local theirs=("$data/$file" --output "$tmp/f3d.png" --resolution "$width,$height")
  # Triangles: hrtao's instanced count from --stats, F3D's polygons summed over its blocks (--verbose).
  "$hrtao" "${ours[@]}" --stats "$tmp/stats.json" >/dev/null 2>&1
  local tri_ours tri_f3d
  tri_ours=$(grep -o '"instanced_triangles": *[0-9]*' "$tmp/stats.json" | grep -o '[0-9]*$')
  tri_f3d=$(f3d "${theirs[@]}" --verbose 2>&1 | awk '/Number of polygons:/ {s += $NF} END {print s + 0}')
  rm -f "$tmp/ours.png" "$tmp/f3d.png"
  seconds "$hrtao" "${ours[@]}" >/dev/null
  seconds f3d "${theirs[@]}" >/dev/null
  local a=() b=()
  for _ in $(seq "$runs"); do
    a+=("$(seconds "$hrtao" "${ours[@]}")")
    b+=("$(seconds f3d "${theirs[@]}")")
  done
  [ -s "$tmp/ours.png" ] && [ -s "$tmp/f3d.png" ] || { echo "bench-step: $file: an image is missing" >&2; exit 1; }
  local stem=${file%.*}
  local json="$out/step_${stem//[^A-Za-z0-9_]/_}_$quality.json"
  local list_a list_b
  list_a=$(IFS=,; echo "${a[*]}")
  list_b=$(IFS=,; echo "${b[*]}")
  cat >"$json" <<EOF
{
  "schema": "hrtao-step-bench/1",
  "file": "$file",
  "quality": "$quality",
  "tessellation": "${flags[*]}",
  "width": $width,
  "height": $height,
  "goal_ratio": $goal,
  "ours": {"wall_s": [$list_a], "triangles": $tri_ours},
  "f3d": {"wall_s": [$list_b], "triangles": $tri_f3d},
  "f3d_version": "$f3d_version",
  "date": "$(date -u +%Y-%m-%d)",
  "cpu": "$cpu"
}
EOF
  echo "$json: hrtao [$list_a] s, F3D [$list_b] s; triangles $tri_ours / $tri_f3d"
}

for file in as1-tu-203.stp t20_data.step step_boundary_colors.stp; do
  bench f3d 1.5 "$file" --deflection-mm 1 --angular-deflection 28.65
  bench default 3 "$file" --deflection 0.005 --angular-deflection 35
  bench fine 3 "$file" --deflection 0.001 --angular-deflection 10
done
