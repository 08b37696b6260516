#!/usr/bin/env bash
# Two builds of the viewer side by side: `hrtao view --orbit 40 --stats` at 1280x800 with the panel, runs
# alternating between the builds (this machine's drift falls on both), each result summarised into
# docs/bench/viewer/<version>_<scene>_<run>.json (schema hrtao-viewer-run/1: the medians `--stats` writes, the
# UI's own cost per frame, the time to converge). `cargo run -p bench-report -- docs/bench` tabulates them.
#
#   BEFORE=path/to/old/hrtao AFTER=target/debug/hrtao scripts/bench-viewer.sh [--runs 3] [SCENE...]
#
# SCENE: `bundled` (the default scene) or a model file; default: bundled and $HRTAO_SHARED's san_francisco.
# Run it on an otherwise idle machine. KEEP=dir keeps each run's raw `--stats` file there (per-frame times).
set -euo pipefail
cd "$(dirname "$0")/.."

runs=3
scenes=()
while [ $# -gt 0 ]; do
    case "$1" in
        --runs) runs=$2; shift 2 ;;
        *) scenes+=("$1"); shift ;;
    esac
done
if [ ${#scenes[@]} -eq 0 ]; then
    scenes=(bundled "${HRTAO_SHARED:-../shared}/scenes/san_francisco/san_francisco.glb")
fi
: "${BEFORE:?BEFORE=the path of the older hrtao binary}"
AFTER=${AFTER:-target/debug/hrtao}

if [ -z "${DISPLAY:-}" ]; then
    command -v xvfb-run >/dev/null || { echo "bench-viewer: no DISPLAY and no xvfb-run" >&2; exit 1; }
    exec xvfb-run -a -s "-screen 0 1280x800x24" "$0" --runs "$runs" "${scenes[@]}"
fi
export MESA_SHADER_CACHE_DISABLE=${MESA_SHADER_CACHE_DISABLE:-false}
unset HRTAO_VALIDATION
out=docs/bench/viewer
mkdir -p "$out"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

for run in $(seq 1 "$runs"); do
    for scene in "${scenes[@]}"; do
        label=$scene
        file=()
        if [ "$scene" != bundled ]; then
            label=$(basename "${scene%.*}")
            file=("$scene")
        fi
        for version in before after; do
            bin=$BEFORE
            [ "$version" = after ] && bin=$AFTER
            stats="$tmp/${version}_${label}_$run.json"
            "$bin" view --no-config --size 1280x800 --orbit 40 --exit --stats "$stats" ${file[@]+"${file[@]}"} \
                >"$tmp/log" 2>&1 || { cat "$tmp/log" >&2; exit 1; }
            python3 scripts/viewer_run_summary.py "$stats" "$out/${version}_${label}_$run.json" "$version" "$label" "$run"
            if [ -n "${KEEP:-}" ]; then mkdir -p "$KEEP" && cp "$stats" "$KEEP/"; fi
        done
    done
done
