#!/usr/bin/env bash
# The sky light on the shared scenes' 640x360 reference views against their Cycles sky references (rendered by
# scripts/make-sky-references.sh --refs $HRTAO_SHARED/refs --size 640x360 into $SKY_REFS), beside the AO mode:
# per view, `hrtao render` at 8 rays per pixel for 1 frame and for 32 still frames with --light-reference (the
# error after each), and per scene the AO mode's 1 and 32 frames with --ao-reference (its first-frame error and
# its cost per frame, measured in the same run of this script). One JSON per render in docs/bench/sky/
# (KEY_MODE_FRAMES.json, MODE `ao` or ENV_ROT); `cargo run -p bench-report -- docs/bench` tabulates them.
#
#   HRTAO_SHARED=DIR SKY_REFS=DIR scripts/bench-sky.sh   (KEYS="cycloidal duplex engine rod sf", HRTAO=target/release/hrtao)
#
# Run it on an idle machine.
set -euo pipefail
cd "$(dirname "$0")/.."

OUT=${OUT:-docs/bench/sky}
: "${HRTAO_SHARED:=/work/shared}"
: "${SKY_REFS:=$HRTAO_SHARED/refs/sky}"
KEYS=${KEYS:-"cycloidal duplex engine rod sf"}
export MESA_SHADER_CACHE_DISABLE=false MESA_SHADER_CACHE_DIR=$PWD/target/mesa-shader-cache
unset HRTAO_VALIDATION

if [ -z "${HRTAO:-}" ]; then
    cargo build --release -q -p hrtao-viewer
    HRTAO=target/release/hrtao
fi

mkdir -p "$OUT"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for key in $KEYS; do
    read -r scene radius < <(python3 -c "import json,sys; e=json.load(open(sys.argv[1]))[sys.argv[2]]; print(e['scene'], e['radius'])" \
        "$HRTAO_SHARED/refs/index.json" "$key")
    common=(render --scene "$HRTAO_SHARED/$scene" --camera "$HRTAO_SHARED/refs/${key}_640x360.camera.json"
            --radius "$radius" --rays 8 --primary ray-query)
    for frames in 1 32; do
        "$HRTAO" "${common[@]}" --frames "$frames" --ao-reference "$HRTAO_SHARED/refs/${key}_640x360.cycles.exr" \
            --stats "$OUT/${key}_ao_${frames}.json" 2>"$tmp/log" || { cat "$tmp/log" >&2; exit 1; }
        echo "$key ao $frames: $(grep -o 'AO MAE against the reference: [0-9.]*' "$tmp/log")"
    done
    views=$(python3 -c "import json,sys; print(' '.join('%s:%s:%s' % (v['environment'], int(v['rotation_deg']), v['file']) for v in json.load(open(sys.argv[1]))[sys.argv[2]]['views']))" \
        "$SKY_REFS/index.json" "$key")
    for v in $views; do
        IFS=: read -r env rot file <<<"$v"
        case "$env" in uniform|gradient) environment=$env ;; *) environment=testdata/env/$env.hdr ;; esac
        for frames in 1 32; do
            "$HRTAO" "${common[@]}" --frames "$frames" --environment "$environment" --environment-rotation "$rot" \
                --light-reference "$SKY_REFS/$file" --stats "$OUT/${key}_${env}_${rot}_${frames}.json" 2>"$tmp/log" \
                || { cat "$tmp/log" >&2; exit 1; }
            echo "$key $env $rot $frames: $(grep -o 'sky light MAE against the reference: [0-9.]*' "$tmp/log")"
        done
    done
done
