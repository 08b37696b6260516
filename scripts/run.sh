#!/usr/bin/env bash
# Installs what is missing, builds hrtao and opens it on the bundled default scene.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
cargo build --release -p hrtao-viewer
exec ./target/release/hrtao "$@"
