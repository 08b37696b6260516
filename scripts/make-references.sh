#!/usr/bin/env bash
# Renders the Blender Cycles ambient-occlusion references of testdata/refs (headless; not run in CI).
#
# usage: scripts/make-references.sh [--samples N] [--out-dir DIR] [KEY[_WxH] ...]
#          every view of testdata/refs/index.json (or only the keys / views named), written to DIR
#          (default testdata/refs) as KEY_WxH.cycles.exr and KEY_WxH.cycles.json
#        scripts/make-references.sh --scene FILE.glb --camera CAM.json --radius R --out PREFIX [--samples N]
#          one view: PREFIX.exr and PREFIX.json
#
# Installs Blender and NumPy from the distribution's packages when missing (Debian/Ubuntu; sudo when not root).
# Environment: BLENDER (default: blender on PATH), THREADS (default: all cores).
# The AO convention is described in testdata/README.md and scripts/blender_ao.py. At 1024 rays per pixel on
# two cores a 160x90 view takes 3-5 s, a 640x360 view 1-2 minutes.
set -euo pipefail
CALLER=$PWD
cd "$(dirname "$0")/.."
ROOT=$PWD
# abs (paths given on the command line are relative to where the script was started), ensure_blender, run_blender.
. scripts/blender-lib.sh

usage() { sed -n '4,13p' "$0" | sed 's/^# \{0,1\}//'; }

samples=1024
out_dir=testdata/refs
scene="" camera="" radius="" out=""
views=()
while [ $# -gt 0 ]; do
  case "$1" in
    -h|--help) usage; exit 0 ;;
    --samples) samples=$2; shift ;;
    --out-dir) out_dir=$(abs "$2"); shift ;;
    --scene) scene=$(abs "$2"); shift ;;
    --camera) camera=$(abs "$2"); shift ;;
    --radius) radius=$2; shift ;;
    --out) out=$(abs "$2"); shift ;;
    -*) usage >&2; echo "error: unknown option $1" >&2; exit 2 ;;
    *) views+=("$1") ;;
  esac
  shift
done

ensure_blender make-references

# render SCENE CAMERA RADIUS PREFIX
render() {
  run_blender make-references blender_ao "$4" --scene "$1" --camera "$2" --radius "$3"
}

if [ -n "$scene$camera$radius$out" ]; then
  if [ -z "$scene" ] || [ -z "$camera" ] || [ -z "$radius" ] || [ -z "$out" ]; then
    usage >&2; echo "error: --scene, --camera, --radius and --out go together" >&2; exit 2
  fi
  render "$scene" "$camera" "$radius" "$out"
  exit 0
fi

# Every view of the index (the cameras stay where they are; the images go to the output folder).
index=testdata/refs/index.json
python3 - "$index" "${views[@]}" <<'EOF' >"${TMPDIR:-/tmp}/hrtao-refs-$$.txt"
import json, os, sys
index_path, wanted = sys.argv[1], sys.argv[2:]
base = os.path.dirname(os.path.dirname(index_path))  # testdata/
for key, entry in json.load(open(index_path)).items():
    for cam in entry["cameras"]:
        view = cam[: -len(".camera.json")]
        if wanted and key not in wanted and view not in wanted:
            continue
        print(os.path.normpath(os.path.join(base, entry["scene"])), os.path.join(os.path.dirname(index_path), cam),
              entry["radius"], view)
EOF
list="${TMPDIR:-/tmp}/hrtao-refs-$$.txt"
if [ ! -s "$list" ]; then echo "error: no view of $index matches ${views[*]:-}" >&2; rm -f "$list"; exit 2; fi
while read -r s c r v; do
  render "$s" "$c" "$r" "$out_dir/$v.cycles"
done <"$list"
rm -f "$list"
