#!/usr/bin/env bash
# Input latency of the viewer, driven like a user: drags sent with xdotool at random times (right after opening
# and during still refinement) into `hrtao view` under Xvfb at 1280x800 with the panel; the latency of each drag
# is the presentation of the first frame answering it minus the drag's monotonic stamp (scripts/bench_latency.py).
#
#   scripts/bench-latency.sh [--scene PATH] [--drags 20] [--runs 2] [--orbit 20] [--out [JSON]] [--seed 1]
#                            [--no-build] [other options of scripts/bench_latency.py]
#
# --out alone writes docs/bench/latency_<scene>.json. Run it on an otherwise idle machine: the JSON records the
# load average, and the times are the CPU's.
set -euo pipefail
cd "$(dirname "$0")/.."

build=1
args=()
for a in "$@"; do
    case "$a" in
        --no-build) build=0 ;;
        *) args+=("$a") ;;
    esac
done

for tool in xdotool python3; do
    command -v "$tool" >/dev/null || { echo "bench-latency: $tool is missing (scripts/install-deps.sh)" >&2; exit 1; }
done

if [ -z "${DISPLAY:-}" ]; then
    command -v xvfb-run >/dev/null || { echo "bench-latency: no DISPLAY and no xvfb-run" >&2; exit 1; }
    exec xvfb-run -a -s "-screen 0 1280x800x24" "$0" "$@"
fi

if [ "$build" = 1 ]; then
    cargo build --release -p hrtao-viewer >&2
fi
export MESA_SHADER_CACHE_DISABLE=${MESA_SHADER_CACHE_DISABLE:-false}
export MESA_SHADER_CACHE_DIR=${MESA_SHADER_CACHE_DIR:-$PWD/target/mesa-shader-cache}
exec python3 scripts/bench_latency.py --hrtao target/release/hrtao ${args[@]+"${args[@]}"}
