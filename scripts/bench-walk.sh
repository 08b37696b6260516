#!/usr/bin/env bash
# Walking against orbiting, one build, side by side: `hrtao view --walk-path` (the scripted walk of
# crates/viewer/tests/building.rs through the two-storey IFC building tests/ifc/make_two_storey.py makes: into a
# wall, through the door, up the stair), `--orbit 180` from a camera inside the building (the east room: every
# pixel shows geometry, as in the walk, and the camera moves 87 mm a frame, the walk 140 mm) and `--orbit 180` of
# the fitted view (the building fills about half of it: background pixels take no AO work), all with `--stats`
# at 1280x800 with the panel, runs alternating between the modes (this machine's drift falls on all).
# Each result is summarised into docs/bench/walk/<mode>_building_<run>.json (schema hrtao-viewer-run/1, as
# scripts/bench-viewer.sh's); `cargo run -p bench-report -- docs/bench` tabulates them ("Walking against orbiting").
#
#   HRTAO_BIN=target/release/hrtao scripts/bench-walk.sh [--runs 3]
#
# Needs the IfcOpenShell venv (scripts/install-ifc.sh). Run it on an otherwise idle machine.
set -euo pipefail
cd "$(dirname "$0")/.."

runs=3
while [ $# -gt 0 ]; do
    case "$1" in
        --runs) runs=$2; shift 2 ;;
        *) echo "bench-walk: unknown argument $1" >&2; exit 2 ;;
    esac
done
bin=${HRTAO_BIN:-target/release/hrtao}
if [ -z "${DISPLAY:-}" ]; then
    command -v xvfb-run >/dev/null || { echo "bench-walk: no DISPLAY and no xvfb-run" >&2; exit 1; }
    exec xvfb-run -a -s "-screen 0 1280x800x24" "$0" --runs "$runs"
fi
export MESA_SHADER_CACHE_DISABLE=${MESA_SHADER_CACHE_DISABLE:-false}
unset HRTAO_VALIDATION
python=${HRTAO_IFC_PYTHON:-$HOME/.local/share/hrtao/ifc-venv/bin/python3}
out=docs/bench/walk
mkdir -p "$out"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
"$python" crates/viewer/tests/ifc/make_two_storey.py "$tmp/building.ifc" >/dev/null
cat >"$tmp/walk.json" <<'JSON'
{"start": [2000, 1500, 1200],
 "waypoints": [[6000, 1500], [2000, 3500], [5500, 3500], [6000, 7300], [12500, 7300]]}
JSON
cat >"$tmp/room.camera.json" <<'JSON'
{"eye": [6500, 4000, 1700], "target": [9000, 4000, 1200], "up": [0, 0, 1], "fov_y_deg": 60,
 "width": 1280, "height": 800}
JSON
for run in $(seq 1 "$runs"); do
    for mode in walk room_orbit orbit; do
        stats="$tmp/${mode}_$run.json"
        case "$mode" in
            walk) how=(--walk-path "$tmp/walk.json") ;;
            room_orbit) how=(--camera "$tmp/room.camera.json" --orbit 180) ;;
            orbit) how=(--orbit 180) ;;
        esac
        "$bin" view --no-config --size 1280x800 "${how[@]}" --exit --stats "$stats" "$tmp/building.ifc" \
            >"$tmp/log" 2>&1 || { cat "$tmp/log" >&2; exit 1; }
        python3 scripts/viewer_run_summary.py "$stats" "$out/${mode}_building_$run.json" "$mode" building "$run"
        python3 - "$stats" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
moving = [f for f in s["frames"] if f["moving"]]
print(f"  {len(s['frames'])} frames, {len(moving)} moving")
PY
    done
done
