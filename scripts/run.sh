#!/usr/bin/env bash
# Installs what is missing, builds hrtao (release) and opens the viewer on the bundled default scene.
# Extra arguments go to `hrtao` (e.g. `./scripts/run.sh view model.glb`).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
cargo build --release -p hrtao-viewer
if [ -z "${DISPLAY:-}" ] && [ -z "${WAYLAND_DISPLAY:-}" ] && [ $# -eq 0 ]; then
  echo "No display found: running the viewer under Xvfb for 8 frames and saving a screenshot to target/hrtao-viewer.png"
  exec xvfb-run -a -s "-screen 0 1280x800x24" ./target/release/hrtao view --frames 8 --screenshot-ui target/hrtao-viewer.png --exit
fi
exec ./target/release/hrtao "$@"
