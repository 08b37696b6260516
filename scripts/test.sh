#!/usr/bin/env bash
# Installs what is missing, then runs the whole test suite on the available Vulkan device with the Khronos
# validation layer on (any validation error or warning fails a test). Windows run under Xvfb.
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
