#!/usr/bin/env bash
# Renders the Blender Cycles sky-light references (headless; not run in CI). By default those of testdata/refs/sky:
# the testdata scenes (rod, cycloidal) from their 160x90 reference cameras, lit by `uniform`, `gradient` and the
# test environment testdata/env/sky_lobe_64x32.hdr (scripts/make-sky-hdr.py), each at rotations 0 and 90 degrees.
#
# usage: scripts/make-sky-references.sh [--samples N] [--out-dir DIR] [--refs DIR] [--size WxH] [--views LIST] [KEY ...]
#          writes DIR/KEY_WxH_ENV_ROT.exr and .json (default DIR: testdata/refs/sky) and DIR/index.json
#   --refs DIR   where index.json lists the scenes (paths relative to DIR/..) and KEY_WxH.camera.json lie
#                (default testdata/refs; the shared scenes' are ../shared/refs)
#   --views LIST the views as ENV:ROT, space separated (default: each environment at 0 and 90; ENV uniform,
#                gradient or lobe)
# The zenith (--up) is the camera file's up axis (z or y). Installs Blender and NumPy from the distribution's
# packages when missing (Debian/Ubuntu; sudo when not root).
# Environment: BLENDER (default: blender on PATH), THREADS (default: all cores). The value's contract is in
# scripts/blender_sky.py and testdata/README.md.
set -euo pipefail
CALLER=$PWD
cd "$(dirname "$0")/.."
ROOT=$PWD
# abs, ensure_blender, run_blender.
. scripts/blender-lib.sh
. scripts/lib.sh
usage() { sed -n '5,16p' "$0" | sed 's/^# \{0,1\}//'; }

samples=2048
out_dir=testdata/refs/sky
refs=testdata/refs
size=160x90
views_list="uniform:0 uniform:90 gradient:0 gradient:90 lobe:0 lobe:90"
keys=()
while [ $# -gt 0 ]; do
  case "$1" in
    -h|--help) usage; exit 0 ;;
    --samples) samples=$2; shift ;;
    --out-dir) out_dir=$(abs "$2"); shift ;;
    --refs) refs=$(abs "$2"); shift ;;
    --size) size=$2; shift ;;
    --views) views_list=$2; shift ;;
    -*) usage >&2; echo "error: unknown option $1" >&2; exit 2 ;;
    *) keys+=("$1") ;;
  esac
  shift
done
[ ${#keys[@]} -gt 0 ] || keys=(rod cycloidal)

ensure_blender make-sky-references

hdr=testdata/env/sky_lobe_64x32.hdr
[ -f "$hdr" ] || python3 scripts/make-sky-hdr.py "$hdr"
mkdir -p "$out_dir"
views=()
for key in "${keys[@]}"; do
  scene=$(index_field "$refs/index.json" "$key" scene)
  camera="$refs/${key}_${size}.camera.json"
  up=$(python3 -c "import json,sys; u=json.load(open(sys.argv[1]))['up']; print('z' if abs(u[2]) > abs(u[1]) else 'y')" "$camera")
  for v in $views_list; do
    env=${v%%:*}
    rot=${v##*:}
    [ "$env" = lobe ] && env=$hdr
    name=$(basename "$env" .hdr)
    view="${key}_${size}_${name}_${rot}"
    run_blender make-sky-references blender_sky "$out_dir/$view" --scene "$refs/../$scene" --camera "$camera" \
      --environment "$env" --rotation "$rot" --up "$up"
    views+=("$key|$scene|$name|$rot|$view|$up")
  done
done
python3 - "$out_dir/index.json" "$refs" "$size" "${views[@]}" <<'EOF'
import json, os, sys
out, refs, size, rows = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4:]
index = {}
here = os.path.dirname(os.path.abspath(out))
scenes = os.path.relpath(os.path.dirname(os.path.abspath(refs)), here)
cameras = os.path.relpath(os.path.abspath(refs), here)
for row in rows:
    key, scene, env, rot, view, up = row.split("|")
    e = index.setdefault(key, {"scene": os.path.join(scenes, scene), "up": up,
                               "camera": os.path.join(cameras, "%s_%s.camera.json" % (key, size)), "views": []})
    e["views"].append({"environment": env, "rotation_deg": float(rot), "file": view + ".exr"})
json.dump(index, open(out, "w"), indent=1)
print("wrote", out)
EOF
