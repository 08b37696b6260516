#!/usr/bin/env bash
# Installs what is missing, builds hrtao (release) and opens the viewer on the bundled default scene.
# Extra arguments go to `hrtao` (e.g. `./scripts/run.sh view model.glb`).
# With no display (neither DISPLAY nor WAYLAND_DISPLAY) and no arguments, it runs the viewer under Xvfb until the
# image has converged and saves the window to target/hrtao-viewer.png, its frame statistics to
# target/hrtao-viewer-stats.json.
# HRTAO_BIN=path/to/hrtao: run that binary, without the install and the build (the tests pass their own build).
set -euo pipefail
bin="${HRTAO_BIN:-}"
case "$bin" in
  "" | /*) ;;
  *) bin="$PWD/$bin" ;;
esac
cd "$(dirname "$0")/.."
if [ -z "$bin" ]; then
  bash scripts/install-deps.sh
  cargo build --release -p hrtao-viewer
  bin=./target/release/hrtao
fi
if [ -z "${DISPLAY:-}" ] && [ -z "${WAYLAND_DISPLAY:-}" ] && [ $# -eq 0 ]; then
  echo "No display found: running the viewer under Xvfb until the image has converged and saving a screenshot to target/hrtao-viewer.png (frame statistics: target/hrtao-viewer-stats.json)"
  mkdir -p target
  exec xvfb-run -a -s "-screen 0 1280x800x24" "$bin" view --orbit 0 --screenshot-ui target/hrtao-viewer.png \
    --stats target/hrtao-viewer-stats.json --exit
fi
exec "$bin" "$@"
