#!/usr/bin/env bash
# First frame and navigation frame with each way to trace (ray queries in compute shaders, or ray-tracing
# pipelines), side by side: `hrtao bench --ray-backend query|pipeline` on the shared scenes' reference views at
# 640x360 (8 rays per pixel, 5 first frames from an empty map and 8 orbit frames per run), the two backends
# alternating run by run so that both see the same load. One JSON per backend, scene and run in
# docs/bench/ray_backend/<backend>_<key>_<run>.json; `cargo run -p bench-report -- docs/bench` tabulates them.
#
#   HRTAO_SHARED=DIR scripts/bench-ray-backends.sh   (KEYS="duplex rod", RUNS=3, ORBIT=8, HRTAO=target/release/hrtao)
#
# Run it on an idle machine; a backend the device lacks is an error of `hrtao bench`.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/lib.sh

OUT=${OUT:-docs/bench/ray_backend}
KEYS=${KEYS:-"duplex rod"}
RUNS=${RUNS:-3}
ORBIT=${ORBIT:-8}
bench_environment
unset HRTAO_VALIDATION HRTAO_RAY_BACKEND

if [ -z "${HRTAO:-}" ]; then
    cargo build --release -q -p hrtao-viewer
    HRTAO=target/release/hrtao
fi

mkdir -p "$OUT"
for key in $KEYS; do
    scene=$(index_field "$HRTAO_SHARED/refs/index.json" "$key" scene)
    radius=$(index_field "$HRTAO_SHARED/refs/index.json" "$key" radius)
    for run in $(seq 1 "$RUNS"); do
        for backend in query pipeline; do
            echo "== $key run $run: $backend $(date -u +%H:%M:%S)"
            "$HRTAO" bench --ray-backend "$backend" --scene "$HRTAO_SHARED/$scene" --label "$key" \
                --camera "$HRTAO_SHARED/refs/${key}_640x360.camera.json" --radius "$radius" --rays 8 \
                --repeat 5 --settle 0 --orbit "$ORBIT" --no-quality --json "$OUT/${backend}_${key}_${run}.json"
        done
    done
done
