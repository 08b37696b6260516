#!/usr/bin/env bash
# Installs the desktop entry and the icon of an installed `hrtao` (e.g. `cargo install --path crates/viewer
# --locked`) for the current user, so that file managers offer it for glTF, OBJ, STL, PLY, STEP and IGES files.
# PREFIX defaults to ~/.local (system-wide: PREFIX=/usr/local, as root).
set -euo pipefail
cd "$(dirname "$0")"
prefix="${PREFIX:-$HOME/.local}"
install -Dm644 hrtao.desktop "$prefix/share/applications/hrtao.desktop"
install -Dm644 hrtao.svg "$prefix/share/icons/hicolor/scalable/apps/hrtao.svg"
if command -v update-desktop-database >/dev/null 2>&1; then
  update-desktop-database "$prefix/share/applications" || true
fi
if command -v gtk-update-icon-cache >/dev/null 2>&1; then
  gtk-update-icon-cache -q -t "$prefix/share/icons/hicolor" || true
fi
command -v hrtao >/dev/null 2>&1 || echo "note: hrtao is not on PATH (cargo install puts it in ~/.cargo/bin)"
echo "installed hrtao.desktop and hrtao.svg under $prefix/share"
