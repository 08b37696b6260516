#!/usr/bin/env bash
# The STEP tessellation sweep behind CadTessellation's default: each file rendered by `hrtao render` at
# a list of linear (fraction of each part's diagonal) and angular deflections, AO on (the default HRTAO mode, 32
# still frames at 640x360 from a fixed camera, shading normals from the kernel), against the finest tessellation:
# triangles, the MAE of the linear AO and of the shaded image over the pixels the model covers (scripts/image-mae.py),
# and the load (read, transfer, tessellation, scene) and BVH build times of `--stats`.
# Writes docs/bench/step/sweep_<file>.json and prints a markdown table.
#
# Needs the files of scripts/fetch-step-data.sh and component8.step (SHARED, default /work/shared/scenes/step).
# Environment: HRTAO (default target/release/hrtao, else target/debug/hrtao), OUT (default docs/bench/step),
# CONFIGS ("REL:DEG ..."; the first is the finest, the reference), FRAMES (default 32), KEEP (a folder that keeps
# the shaded images, FILE_REL_DEG.png).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
out=${OUT:-$root/docs/bench/step}
frames=${FRAMES:-32}
hrtao=${HRTAO:-}
if [ -z "$hrtao" ]; then
  hrtao=$root/target/release/hrtao
  [ -x "$hrtao" ] || hrtao=$root/target/debug/hrtao
fi
[ -x "$hrtao" ] || { echo "step-tessellation-sweep: no hrtao binary (cargo build -p hrtao-viewer)" >&2; exit 1; }
shared=${SHARED:-/work/shared/scenes/step}
configs=${CONFIGS:-"0.0002:5 0.001:10 0.002:20 0.005:30 0.004:35 0.005:35 0.005:40 0.01:45 0.01:60 0.1:90"}
data=$("$root/scripts/fetch-step-data.sh")
mkdir -p "$out"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# FILE PATH CAMERA_JSON RADIUS
sweep() {
  local name=$1 path=$2 cam=$3 radius=$4
  echo "$cam" >"$tmp/cam.json"
  local rows=() ref=
  echo "| linear (× diagonal) | angular | triangles (instanced) | unique | AO MAE | shaded MAE | load ms | BLAS+TLAS ms |"
  echo "|---|---|---|---|---|---|---|---|"
  for c in $configs; do
    local rel=${c%%:*} deg=${c##*:} tag="${c//[:.]/_}"
    "$hrtao" render --scene "$path" --camera "$tmp/cam.json" --width 640 --height 360 --frames "$frames" \
      --radius "$radius" --deflection "$rel" --angular-deflection "$deg" -q \
      --out "$tmp/$tag.png" --ao-out "$tmp/$tag.pfm" --stats "$tmp/$tag.json" >/dev/null
    [ -n "$ref" ] || ref=$tag
    [ -z "${KEEP:-}" ] || { mkdir -p "$KEEP" && cp "$tmp/$tag.png" "$KEEP/${name%%.*}_$tag.png"; }
    local mae
    mae=$(python3 "$root/scripts/image-mae.py" "$tmp/$ref.png" "$tmp/$ref.pfm" "$tmp/$tag.png" "$tmp/$tag.pfm")
    local row
    row=$(python3 - "$tmp/$tag.json" "$rel" "$deg" "$mae" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
m = json.loads(sys.argv[4])
b = s["build"]
print(json.dumps({"relative": float(sys.argv[2]), "angular_deg": float(sys.argv[3]),
                  "instanced_triangles": s["instanced_triangles"], "unique_triangles": s["unique_triangles"],
                  "ao_mae": round(m["ao_mae"], 5), "shaded_mae": round(m["shaded_mae"], 5), "covered": m["covered"],
                  "load_ms": round(s["load_ms"], 1), "bvh_ms": round(b["blas_ms"] + b["tlas_ms"], 2)}))
PY
)
    rows+=("$row")
    python3 -c 'import json,sys; r=json.loads(sys.argv[1]); print("| %g | %g° | %d | %d | %.4f | %.4f | %.0f | %.1f |" % (r["relative"], r["angular_deg"], r["instanced_triangles"], r["unique_triangles"], r["ao_mae"], r["shaded_mae"], r["load_ms"], r["bvh_ms"]))' "$row"
  done
  local list
  list=$(IFS=,; echo "${rows[*]}")
  cat >"$out/sweep_${name//[^A-Za-z0-9_]/_}.json" <<JSON
{
  "schema": "hrtao-step-sweep/1",
  "file": "$name",
  "camera": $cam,
  "radius": $radius,
  "frames": $frames,
  "width": 640,
  "height": 360,
  "reference": "${configs%% *}",
  "date": "$(date -u +%Y-%m-%d)",
  "cpu": "$(awk -F': ' '/model name/ {print $2; exit}' /proc/cpuinfo)",
  "rows": [$list]
}
JSON
}

echo "## as1-tu-203.stp"
sweep as1-tu-203.stp "$data/as1-tu-203.stp" \
  '{"eye":[234,186,213],"target":[90,75,38],"up":[0,1,0],"fov_y_deg":40,"width":640,"height":360}' 20
echo "## component8.step"
sweep component8.step "$shared/component8.step" \
  '{"eye":[40,200,46],"target":[0,172.3,0],"up":[0,1,0],"fov_y_deg":40,"width":640,"height":360}' 3.3
