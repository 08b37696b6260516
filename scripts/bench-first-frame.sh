#!/usr/bin/env bash
# First frame against the paper's mode, per addition (docs/benchmarks.md, "First frame against the paper's mode"):
# our defaults and our defaults with each addition of ours off (the ablation's "no-" rows, from the settings:
# `examples/ablation.rs --configs`), on the shared scenes' reference views at 640x360, 8 rays per pixel. Each run
# is `hrtao bench --repeat 5 --settle 0`, which renders the first frame from an empty map with ours and the
# paper's mode alternating, so that the paired ratios see the same load. One JSON per configuration and scene in
# docs/bench/first_frame/<config>_<key>.json; `cargo run -p bench-report -- docs/bench` tabulates them.
#
#   HRTAO_SHARED=DIR scripts/bench-first-frame.sh [NAME...]   (default: every configuration; KEYS="sf duplex")
#
# A JSON that exists is skipped unless FORCE=1, so a run resumes where it stopped. Run it on an idle machine.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/lib.sh

OUT=${OUT:-docs/bench/first_frame}
KEYS=${KEYS:-"sf duplex"}
bench_environment
unset HRTAO_VALIDATION

cargo build --release -q -p hrtao-viewer
cargo build --release -q -p hrtao-core --example ablation
CONFIGS=$(target/release/examples/ablation --configs | awk -F'|' '$1 == "default" || ($2 == "default" && $1 ~ /^no-/)')

mkdir -p "$OUT"
for key in $KEYS; do
    scene=$(index_field "$HRTAO_SHARED/refs/index.json" "$key" scene)
    radius=$(index_field "$HRTAO_SHARED/refs/index.json" "$key" radius)
    while IFS='|' read -r name _base set; do
        if [ $# -gt 0 ] && ! printf '%s\n' "$@" | grep -qx -- "$name"; then
            continue
        fi
        out="$OUT/${name}_${key}.json"
        if [ -e "$out" ] && [ "${FORCE:-0}" != 1 ]; then
            echo "== $name $key: $out exists, skipped (FORCE=1 reruns it)"
            continue
        fi
        echo "== $name $key ($set) $(date -u +%H:%M:%S)"
        target/release/hrtao bench --scene "$HRTAO_SHARED/$scene" --label "$key" \
            --camera "$HRTAO_SHARED/refs/${key}_640x360.camera.json" --radius "$radius" --rays 8 \
            --repeat 5 --settle 0 --orbit 1 --no-quality --set "$set" --json "$out"
    done <<<"$CONFIGS"
done
