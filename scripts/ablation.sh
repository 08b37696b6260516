#!/usr/bin/env bash
# The ablation of our additions (docs/algorithm.md): each configuration's one-frame and 32-frame MAE, flicker,
# first-frame and navigation cost on the shared scenes, one JSON per configuration in docs/bench/ablation/.
#
#   HRTAO_SHARED=DIR scripts/ablation.sh [NAME...]   runs the listed configurations (default: all, in order)
#   scripts/ablation.sh --report                      prints the Markdown table of what has been measured
#   scripts/ablation.sh --list                        lists the configurations
#
# A configuration whose JSON exists is skipped unless FORCE=1, so a run resumes where it stopped. Set KEYS to
# measure fewer scenes (e.g. KEYS="rod cycloidal"; the JSON then holds only those).
set -euo pipefail
cd "$(dirname "$0")/.."

OUT=${OUT:-docs/bench/ablation}
: "${HRTAO_SHARED:=/work/shared}"
export HRTAO_SHARED
export MESA_SHADER_CACHE_DISABLE=false MESA_SHADER_CACHE_DIR=$PWD/target/mesa-shader-cache
unset HRTAO_VALIDATION

# name | base | AoSettings overrides. "Off" rows turn one addition off on the default settings, "with-" rows
# turn on one that is off by default, "paper+" rows turn one on alone on the paper's mode.
CONFIGS=$(cat <<'EOF'
default|default|{}
default-rerun|default|{}
paper|paper|{}
no-contact-detail|default|{"contact_detail":0}
no-pooled-residual|default|{"pooled_residual":0}
no-level-blend|default|{"level_blend":0}
no-near-field|default|{"near_weight":0}
no-adaptive-rays|default|{"adaptive_rays":false}
no-variance-filter|default|{"filter_sigma":0}
no-cell-cap|default|{"max_cell_fraction":1e30}
no-normal-offset|default|{"normal_offset":0}
no-residual-pooling|default|{"residual_sigma":0}
no-still-smoothing|default|{"still_smoothing":1}
no-refine|default|{"refine":false}
with-linear-cells|default|{"cell_gradient":2}
with-adaptive-prior|default|{"prior_rays_max":1024}
paper+contact-detail|paper|{"contact_detail":1}
paper+pooled-residual|paper|{"pooled_residual":16}
paper+level-blend|paper|{"level_blend":1}
paper+near-field|paper|{"near_weight":1}
paper+adaptive-rays|paper|{"adaptive_rays":true}
paper+variance-filter|paper|{"filter_sigma":1}
paper-cell-cap|paper|{"max_cell_fraction":1e30}
paper+normal-offset|paper|{"normal_offset":0.25}
paper+refine|paper|{"refine":true}
EOF
)

cargo build --release -q -p hrtao-core --example ablation
BIN=target/release/examples/ablation

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
