#!/usr/bin/env bash
# Unpacks test models of Debian's assimp-testmodels package (assimp's own test models, redistributable; see the
# package's copyright file) into DIR (default target/assimp-models), skipping the download when they are there.
# Prints DIR. Files: box.3mf (3MF, millimetres), 2CylinderEngine.gltf/.bin (the Draco twin of Khronos'
# 2CylinderEngine), AC14-FZK-Haus.ifc (IFC2X3).
set -euo pipefail
dir="${1:-$(cd "$(dirname "$0")/.." && pwd)/target/assimp-models}"
files="3MF/box.3mf glTF2/draco/2CylinderEngine.gltf glTF2/draco/2CylinderEngine.bin IFC/AC14-FZK-Haus.ifc"
missing=0
for f in $files; do [ -s "$dir/$f" ] || missing=1; done
if [ $missing = 0 ]; then
  echo "$dir"
  exit 0
fi
. "$(dirname "$0")/lib.sh"
unpack_deb fetch-assimp-models assimp-testmodels "$dir"
for f in $files; do
  mkdir -p "$dir/$(dirname "$f")"
  cp "$dir/deb/root/usr/share/assimp/models/$f" "$dir/$f"
done
rm -rf "$dir/deb"
echo "$dir"
