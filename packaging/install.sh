#!/usr/bin/env bash
# Installs what makes an installed `hrtao` (e.g. `cargo install --path crates/viewer --locked`) at home on the
# desktop, for the current user: the desktop entry and the icon (file managers offer hrtao for every format it
# opens), the MIME types the desktop may not know (STEP, PLY, IFC, ...), the thumbnailer (file-manager previews
# with ambient occlusion, `hrtao thumbnail`), the AppStream metainfo, and the shell completions and man pages that
# `hrtao generate-shell-files` writes. PREFIX defaults to ~/.local (system-wide: PREFIX=/usr/local, as root);
# HRTAO_BIN names the binary (default: `hrtao` on PATH).
set -euo pipefail
cd "$(dirname "$0")"
prefix="${PREFIX:-$HOME/.local}"
share="$prefix/share"
bin="${HRTAO_BIN:-$(command -v hrtao || true)}"

install -Dm644 hrtao.desktop "$share/applications/hrtao.desktop"
install -Dm644 hrtao.svg "$share/icons/hicolor/scalable/apps/hrtao.svg"
install -Dm644 hrtao-mime.xml "$share/mime/packages/hrtao.xml"
install -Dm644 io.github.hrtao.hrtao.metainfo.xml "$share/metainfo/io.github.hrtao.hrtao.metainfo.xml"
# The thumbnailer names the binary by its absolute path when it is known: a file manager's PATH often lacks
# ~/.cargo/bin.
thumbnailer="$share/thumbnailers/hrtao.thumbnailer"
install -Dm644 hrtao.thumbnailer "$thumbnailer"
if [ -n "$bin" ]; then
  bin="$(readlink -f "$bin")"
  sed -i -e "s|^TryExec=hrtao\$|TryExec=$bin|" -e "s|^Exec=hrtao |Exec=$bin |" "$thumbnailer"
fi

if [ -n "$bin" ] && [ -x "$bin" ]; then
  gen="$(mktemp -d)"
  trap 'rm -rf "$gen"' EXIT
  "$bin" generate-shell-files "$gen" >/dev/null
  install -Dm644 "$gen/hrtao.bash" "$share/bash-completion/completions/hrtao"
  install -Dm644 "$gen/_hrtao" "$share/zsh/site-functions/_hrtao"
  install -Dm644 "$gen/hrtao.fish" "$share/fish/vendor_completions.d/hrtao.fish"
  for page in "$gen"/man1/*.1; do
    install -Dm644 "$page" "$share/man/man1/$(basename "$page")"
  done
  extras="completions (bash, zsh, fish), man pages"
else
  echo "note: hrtao is not on PATH (cargo install puts it in ~/.cargo/bin): no completions or man pages"
  extras="no completions or man pages"
fi

if command -v update-mime-database >/dev/null 2>&1; then
  update-mime-database "$share/mime" || true
fi
if command -v update-desktop-database >/dev/null 2>&1; then
  update-desktop-database "$share/applications" || true
fi
if command -v gtk-update-icon-cache >/dev/null 2>&1; then
  gtk-update-icon-cache -q -t "$share/icons/hicolor" || true
fi
echo "installed under $share: hrtao.desktop, hrtao.svg, the MIME types, the thumbnailer, the metainfo, $extras"
