#!/usr/bin/env bash
# Installs what is missing, then runs the whole test suite on the available Vulkan device with the Khronos
# validation layer on (any validation error or warning fails a test). Windows run under Xvfb.
#
# Pipelines only (a GPU that traces with ray-tracing pipelines and has no ray queries, as NVIDIA data-centre GPUs
# may be lent):
#   HRTAO_HIDE_RAY_QUERY=1 bash scripts/test.sh
# makes every device look like one without VK_KHR_ray_query, for the binary and every test: the pipeline backend
# is chosen, `hrtao devices` lists no ray queries, and each test (or part) that needs ray queries prints
# `skipped: ...` with its reason (see them with `-- --nocapture`, or grep the log for "skipped:").
# Without the validation layer (a bare GPU machine): validation is skipped with a message ("validation skipped:
# VK_LAYER_KHRONOS_validation is not installed") and the tests run unvalidated; to try it where the layer is
# installed, hide it from the loader: VK_LAYER_PATH=$(mktemp -d) bash scripts/test.sh
set -euo pipefail
cd "$(dirname "$0")/.."

bash scripts/install-deps.sh
export HRTAO_VALIDATION=1
export RUST_BACKTRACE=1
# A clean clone builds once: incremental caches would only double target/ (18 of 30 GB) on the CI disk.
export CARGO_INCREMENTAL="${CARGO_INCREMENTAL:-0}"
# Lavapipe compiles every pipeline when first used (~0.4 s each) and every test builds its own device: Mesa's
# shader cache lets later tests reuse the compiled pipelines (a suite twice as fast). It lives in target/, not in
# $HOME, so it cannot grow across checkouts; its keys hash the SPIR-V and the driver, so a stale entry never hits.
export MESA_SHADER_CACHE_DISABLE=false
export MESA_SHADER_CACHE_DIR="${MESA_SHADER_CACHE_DIR:-$PWD/target/mesa-shader-cache}"

echo "== cargo fmt --check"
cargo fmt --all -- --check
echo "== cargo clippy -D warnings"
cargo clippy --workspace --all-targets --quiet -- -D warnings
echo "== cargo test"
if [ -z "${DISPLAY:-}" ] && command -v xvfb-run >/dev/null 2>&1; then
  xvfb-run -a -s "-screen 0 1280x800x24" cargo test --workspace -- --test-threads=2
else
  cargo test --workspace -- --test-threads=2
fi
