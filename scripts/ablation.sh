#!/usr/bin/env bash
# The ablation of our additions (docs/algorithm.md): each configuration's one-frame and 32-frame MAE, flicker,
# first-frame and navigation cost on the shared scenes, one JSON per configuration in docs/bench/ablation/.
#
#   HRTAO_SHARED=DIR scripts/ablation.sh [NAME...]   runs the listed configurations (default: all, in order)
#   scripts/ablation.sh --report                      prints the Markdown table of what has been measured
#   scripts/ablation.sh --list                        lists the configurations
#
# A configuration whose JSON exists is skipped unless FORCE=1, so a run resumes where it stopped. The first run,
# on the code before the level blend's deletion, is kept in docs/bench/ablation/v1 (OUT=... --report shows it). Set KEYS to
# measure fewer scenes (e.g. KEYS="rod cycloidal"; the JSON then holds only those).
set -euo pipefail
cd "$(dirname "$0")/.."

OUT=${OUT:-docs/bench/ablation}
: "${HRTAO_SHARED:=/work/shared}"
export HRTAO_SHARED
export MESA_SHADER_CACHE_DISABLE=false MESA_SHADER_CACHE_DIR=$PWD/target/mesa-shader-cache
unset HRTAO_VALIDATION

cargo build --release -q -p hrtao-core --example ablation
BIN=target/release/examples/ablation

# name | base | AoSettings overrides, from the settings (`ablation --configs`): the baselines, then every
# addition of ours off on the default settings ("no-" rows) and alone on the paper's mode ("paper+" rows). (Rows
# of additions since deleted, measured before their deletion: no-level-blend, with-linear-cells,
# with-adaptive-prior; their JSON records the commit they ran on.)
CONFIGS=$("$BIN" --configs)

case "${1:-}" in
--report)
    exec "$BIN" --report "$OUT"
    ;;
--list)
    echo "$CONFIGS"
    exit 0
    ;;
esac

mkdir -p "$OUT"
# The run uses its own copy of the binary, so rebuilding the example meanwhile does not change it.
RUN_BIN=target/release/ablation-run-$$
cp "$BIN" "$RUN_BIN"
trap 'rm -f "$RUN_BIN"' EXIT
# shellcheck disable=SC2206
KEYS_ARR=(${KEYS:-})
while IFS='|' read -r name base set; do
    if [ $# -gt 0 ] && ! printf '%s\n' "$@" | grep -qx -- "$name"; then
        continue
    fi
    if [ -e "$OUT/$name.json" ] && [ "${FORCE:-0}" != 1 ]; then
        echo "== $name: $OUT/$name.json exists, skipped (FORCE=1 reruns it)"
        continue
    fi
    echo "== $name ($base $set) $(date -u +%H:%M:%S)"
    start=$(date +%s)
    "$RUN_BIN" --name "$name" --base "$base" --set "$set" --out "$OUT" "${KEYS_ARR[@]}"
    echo "== $name done in $(($(date +%s) - start)) s"
    if [ "${COMMIT:-0}" = 1 ]; then
        { git add "$OUT/$name.json" && git commit -q -m "ablation: $name measured" -- "$OUT/$name.json"; } ||
            echo "== $name: commit failed, $OUT/$name.json left uncommitted"
    fi
done <<<"$CONFIGS"
