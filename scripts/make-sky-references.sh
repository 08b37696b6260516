#!/usr/bin/env bash
# Renders the Blender Cycles sky-light references of testdata/refs/sky (headless; not run in CI): the testdata
# scenes (rod, cycloidal; Z-up) from their 160x90 reference cameras, lit by `uniform`, `gradient` and the test
# environment testdata/env/sky_lobe_64x32.hdr (scripts/make-sky-hdr.py), each at rotations 0 and 90 degrees.
#
# usage: scripts/make-sky-references.sh [--samples N] [--out-dir DIR] [KEY ...]
#          writes DIR/KEY_160x90_ENV_ROT.exr and .json (default DIR: testdata/refs/sky) and DIR/index.json
#
# Installs Blender and NumPy from the distribution's packages when missing (Debian/Ubuntu; sudo when not root).
# Environment: BLENDER (default: blender on PATH), THREADS (default: all cores). The value's contract is in
# scripts/blender_sky.py and testdata/README.md.
set -euo pipefail
CALLER=$PWD
cd "$(dirname "$0")/.."
ROOT=$PWD
abs() { case "$1" in /*) echo "$1" ;; *) echo "$CALLER/$1" ;; esac; }
usage() { sed -n '6,11p' "$0" | sed 's/^# \{0,1\}//'; }

samples=2048
out_dir=testdata/refs/sky
keys=()
while [ $# -gt 0 ]; do
  case "$1" in
    -h|--help) usage; exit 0 ;;
    --samples) samples=$2; shift ;;
    --out-dir) out_dir=$(abs "$2"); shift ;;
    -*) usage >&2; echo "error: unknown option $1" >&2; exit 2 ;;
    *) keys+=("$1") ;;
  esac
  shift
done
[ ${#keys[@]} -gt 0 ] || keys=(rod cycloidal)

BLENDER=${BLENDER:-blender}
if ! command -v "$BLENDER" >/dev/null 2>&1; then
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
  echo "[make-sky-references] installing blender and python3-numpy"
  $SUDO apt-get update
  $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends blender python3-numpy
fi

hdr=testdata/env/sky_lobe_64x32.hdr
[ -f "$hdr" ] || python3 scripts/make-sky-hdr.py "$hdr"
mkdir -p "$out_dir"
views=()
for key in "${keys[@]}"; do
  scene=$(python3 -c "import json,sys; print(json.load(open('testdata/refs/index.json'))[sys.argv[1]]['scene'])" "$key")
  for env in uniform gradient "$hdr"; do
    name=$(basename "$env" .hdr)
    for rot in 0 90; do
      view="${key}_160x90_${name}_${rot}"
      log="$out_dir/$view.log"
      if ! "$BLENDER" -b --factory-startup -noaudio --python-exit-code 3 -P "$ROOT/scripts/blender_sky.py" -- \
          --scene "testdata/$scene" --camera "testdata/refs/${key}_160x90.camera.json" --environment "$env" \
          --rotation "$rot" --up z --out "$out_dir/$view" --samples "$samples" --threads "${THREADS:-0}" \
          </dev/null >"$log" 2>&1; then
        echo "[make-sky-references] Blender failed on $view; the end of $log:" >&2
        tail -n 30 "$log" >&2
        exit 1
      fi
      grep '^\[blender_sky\]' "$log"
      rm -f "$log"
      views+=("$key|$scene|$name|$rot|$view")
    done
  done
done
python3 - "$out_dir/index.json" "${views[@]}" <<'EOF'
import json, sys
out, rows = sys.argv[1], sys.argv[2:]
index = {}
for row in rows:
    key, scene, env, rot, view = row.split("|")
    e = index.setdefault(key, {"scene": "../../" + scene, "up": "z", "camera": "../%s_160x90.camera.json" % key,
                               "views": []})
    e["views"].append({"environment": env, "rotation_deg": float(rot), "file": view + ".exr"})
json.dump(index, open(out, "w"), indent=1)
print("wrote", out)
EOF
