#!/usr/bin/env bash
# Writes the compressed twins of the rod assembly that the tests read, so that tests need no npm:
#   testdata/scenes/rod_assembly/rod.meshopt.glb  gltfpack 1.3.0 -cc (EXT_meshopt_compression with filters,
#                                                 KHR_mesh_quantization)
#   testdata/scenes/rod_assembly/rod.draco.glb    gltf-pipeline 4.3.1 -d (KHR_draco_mesh_compression)
# Needs node and npm (Debian: nodejs, npm); the tools' versions are pinned.
set -euo pipefail
cd "$(dirname "$0")/.."
dir=testdata/scenes/rod_assembly
command -v npx >/dev/null || { echo "make-compressed-gltf: npx is missing (apt install npm)" >&2; exit 1; }
npx -y gltfpack@1.3.0 -i "$dir/rod.glb" -o "$dir/rod.meshopt.glb" -cc
npx -y gltf-pipeline@4.3.1 -i "$dir/rod.glb" -o "$dir/rod.draco.glb" -d
ls -l "$dir"/rod.*.glb
