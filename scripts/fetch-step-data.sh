#!/usr/bin/env bash
# Unpacks the STEP test files of Debian's gmsh-doc package (gmsh's documentation, GPL-2+ with the Gmsh exception)
# into DIR (default target/step-data), skipping the download when they are there. Prints DIR.
# Files: as1-tu-203.stp (the AS1 assembly), t20_data.step (one machined part), step_boundary_colors.stp.
set -euo pipefail
dir="${1:-$(cd "$(dirname "$0")/.." && pwd)/target/step-data}"
if [ -s "$dir/as1-tu-203.stp" ] && [ -s "$dir/t20_data.step" ] && [ -s "$dir/step_boundary_colors.stp" ]; then
  echo "$dir"
  exit 0
fi
. "$(dirname "$0")/lib.sh"
unpack_deb fetch-step-data gmsh-doc "$dir"
for f in as1-tu-203.stp t20_data.step step_boundary_colors.stp; do
  src=$(find "$dir/deb/root" -name "$f" -o -name "$f.gz" | head -n 1)
  [ -n "$src" ] || { echo "fetch-step-data: $f not in gmsh-doc" >&2; exit 1; }
  case "$src" in
    *.gz) gzip -dc "$src" >"$dir/$f" ;;
    *) cp "$src" "$dir/$f" ;;
  esac
done
rm -rf "$dir/deb"
echo "$dir"
