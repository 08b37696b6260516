#!/usr/bin/env bash
# Installs what is missing, then runs the whole test suite on the available Vulkan device with the Khronos
# validation layer on (any validation error or warning fails a test). Windows run under Xvfb.
set -euo pipefail
cd "$(dirname "$0")/.."

bash scripts/install-deps.sh
export HRTAO_VALIDATION=1
export RUST_BACKTRACE=1
# Lavapipe: avoid Mesa's shader cache in $HOME growing across runs.
export MESA_SHADER_CACHE_DISABLE=${MESA_SHADER_CACHE_DISABLE:-true}

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
