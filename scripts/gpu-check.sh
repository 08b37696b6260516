#!/usr/bin/env bash
# The GPU check: one prepared command for a bare Linux machine with a GPU (no display, no network, maybe no Vulkan
# loader installed), made here and run there.
#
#   scripts/gpu-check.sh bundle [DIR]            (here) a release hrtao without OpenCASCADE, stripped, with
#                                                libvulkan.so.1, the scenes, the Cycles references and this driver,
#                                                in DIR (default .gpu-check/, at most 64 MiB)
#   DIR/gpu-check.sh run [--small] [--out OUT]   (there) checks the machine, then correctness against the
#                                                references, the hash map overloaded, and `hrtao bench` at
#                                                1920x1080 (--small: 160x90, about a minute on lavapipe);
#                                                writes OUT/report.json and OUT/report.md (default OUT: ./gpu-check-out)
#   scripts/gpu-check.sh run ...                 the same from the repository (HRTAO_BIN, else target/release/hrtao)
#
# Exit status of run: 0 every check passed, 1 a check failed, 2 the machine lacks what hrtao needs.
# Environment: HRTAO_BIN (run: the binary; bundle: use it instead of building), HRTAO_SHARED (bundle: the folder of
# extra scenes, default ../shared next to the repository), GPU_CHECK_MAX_MIB (bundle: the size limit, 64).
set -euo pipefail
HERE=$(cd "$(dirname "$0")" && pwd)

usage() {
  sed -n '2,16p' "$0" | sed 's/^# \{0,1\}//' >&2
  exit 2
}

# ---------------------------------------------------------------- bundle (on the development machine)

# The highest GLIBC_x.y the binary needs: the target's glibc must be at least that.
glibc_needed() {
  objdump -T "$1" | grep -o 'GLIBC_[0-9.]*' | sort -u -V | tail -1
}

bundle() {
  local repo dir max_mib bin shared
  repo=$(cd "$HERE/.." && pwd)
  # Paths given relative to where the command runs, before it moves to the repository.
  dir=$(realpath -m "${1:-$repo/.gpu-check}")
  bin=${HRTAO_BIN:+$(realpath "$HRTAO_BIN")}
  max_mib=${GPU_CHECK_MAX_MIB:-64}
  cd "$repo"
  if [ -z "$bin" ]; then
    # No OpenCASCADE: the target has none of its libraries, and the check reads glTF only.
    cargo build --release -p hrtao-viewer --no-default-features
    bin=${CARGO_TARGET_DIR:-target}/release/hrtao
  fi
  rm -rf "$dir"
  mkdir -p "$dir/bin" "$dir/lib" "$dir/scenes" "$dir/refs"
  cp "$bin" "$dir/bin/hrtao"
  strip "$dir/bin/hrtao"
  # The Vulkan loader of this machine (Debian 12): the target may have none. ldconfig knows where it lives (awk reads
  # the whole list: leaving early would end ldconfig by SIGPIPE, a failure under pipefail).
  local loader ldconfig
  ldconfig=$(command -v ldconfig || echo /sbin/ldconfig)
  loader=$("$ldconfig" -p | awk '/libvulkan\.so\.1 .*x86-64/ && !n++ {print $NF}')
  [ -n "$loader" ] || { echo "gpu-check: no libvulkan.so.1 here to bundle (apt install libvulkan1)" >&2; exit 1; }
  cp -L "$loader" "$dir/lib/libvulkan.so.1"
  # The C++ runtime the glTF decoders link (they need only CXXABI_1.3, which every libstdc++ has): used there only
  # when the machine has none, so that a newer system copy, which the GPU driver may need, is never shadowed.
  mkdir -p "$dir/lib/fallback"
  local lib
  for lib in libstdc++.so.6 libgcc_s.so.1; do
    cp -L "$("$ldconfig" -p | awk -v l="$lib" '$1 == l && /x86-64/ && !n++ {print $NF}')" "$dir/lib/fallback/"
  done
  cp "$HERE/gpu-check.sh" "$HERE/gpu_check.py" "$dir/"
  # The bundled gearbox (the scene `hrtao render` shows by default) with its camera and its Cycles references.
  cp assets/default.glb assets/default.camera.json assets/default.LICENSE.md "$dir/scenes/"
  cp testdata/refs/cycloidal_{160x90,640x360}.{camera.json,cycles.exr} "$dir/refs/"
  local scenes='{"key": "cycloidal", "scene": "scenes/default.glb", "radius": 8.0,
    "camera": "scenes/default.camera.json",
    "cameras": {"160x90": "refs/cycloidal_160x90.camera.json", "640x360": "refs/cycloidal_640x360.camera.json"},
    "references": {"160x90": "refs/cycloidal_160x90.cycles.exr", "640x360": "refs/cycloidal_640x360.cycles.exr"}}'
  # Two scenes of the shared folder for the benchmarks: a city (many meshes, no instancing) and a CAD engine.
  shared=${HRTAO_SHARED:-$repo/../shared}
  if [ -d "$shared/scenes" ]; then
    mkdir -p "$dir/scenes/sf" "$dir/scenes/engine"
    cp "$shared/scenes/san_francisco/san_francisco.glb" "$dir/scenes/sf/"
    cp "$shared/refs/sf_640x360.camera.json" "$dir/scenes/sf/"
    cp "$shared/scenes/2CylinderEngine/"* "$dir/scenes/engine/"
    cp "$shared/refs/engine_640x360.camera.json" "$dir/scenes/engine/"
    scenes="$scenes,
    {\"key\": \"sf\", \"scene\": \"scenes/sf/san_francisco.glb\", \"radius\": 15.0,
     \"camera\": \"scenes/sf/sf_640x360.camera.json\"},
    {\"key\": \"engine\", \"scene\": \"scenes/engine/2CylinderEngine.gltf\", \"radius\": 40.0,
     \"camera\": \"scenes/engine/engine_640x360.camera.json\"}"
  else
    echo "gpu-check: $shared/scenes not found: san_francisco and engine skipped (the gearbox only)"
  fi
  printf '{"scenes": [%s]}\n' "$scenes" >"$dir/manifest.json"
  python3 -c 'import json, sys; json.load(open(sys.argv[1]))' "$dir/manifest.json"

  echo "gpu-check: the binary needs glibc >= $(glibc_needed "$dir/bin/hrtao" | sed 's/GLIBC_//') and the libraries" \
    "$(objdump -p "$dir/bin/hrtao" | awk '/NEEDED/ {printf "%s ", $2}')(libvulkan.so.1 dlopened)"
  local bytes
  bytes=$(du -sb "$dir" | cut -f1)
  echo "gpu-check: bundle $dir: $((bytes / 1024)) KiB"
  if [ "$bytes" -gt $((max_mib * 1024 * 1024)) ]; then
    echo "gpu-check: error: the bundle is $((bytes / 1024 / 1024)) MiB, over the limit of $max_mib MiB" >&2
    exit 1
  fi
  echo "gpu-check: on the GPU machine: $dir/gpu-check.sh run [--small] [--out OUT]"
}

# ---------------------------------------------------------------- run (on the GPU machine, or here)

run() {
  local out=$PWD/gpu-check-out small=() bin root
  while [ $# -gt 0 ]; do
    case $1 in
      --small) small=(--small) ;;
      --out) out=$2; shift ;;
      *) usage ;;
    esac
    shift
  done
  if [ -x "$HERE/bin/hrtao" ]; then
    # A bundle: its binary, and its loader ahead of any other.
    root=$HERE
    bin=${HRTAO_BIN:-$HERE/bin/hrtao}
    export LD_LIBRARY_PATH="$HERE/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
    if ! python3 -c 'import ctypes; ctypes.CDLL("libstdc++.so.6"); ctypes.CDLL("libgcc_s.so.1")' 2>/dev/null; then
      echo "gpu-check: no C++ runtime on this machine: the bundle's (lib/fallback)"
      export LD_LIBRARY_PATH="$LD_LIBRARY_PATH:$HERE/lib/fallback"
    fi
  else
    root=$(cd "$HERE/.." && pwd)
    bin=${HRTAO_BIN:-${CARGO_TARGET_DIR:-$root/target}/release/hrtao}
  fi
  [ -x "$bin" ] || { echo "gpu-check: no hrtao binary at $bin (set HRTAO_BIN, or build it)" >&2; exit 2; }
  command -v python3 >/dev/null || { echo "gpu-check: python3 is missing" >&2; exit 2; }
  # NVIDIA's container layout: the driver's ICD file outside the loader's search path.
  local nvidia=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
  if [ -z "${VK_DRIVER_FILES:-}" ] && [ -f "$nvidia" ]; then
    export VK_DRIVER_FILES=$nvidia
    # The driver library that file names (libGLX_nvidia.so.0) lives beside it, maybe off the linker's path.
    if [ -d /usr/local/nvidia/lib64 ]; then
      export LD_LIBRARY_PATH="${LD_LIBRARY_PATH:+$LD_LIBRARY_PATH:}/usr/local/nvidia/lib64"
    fi
  fi
  # The caller's backend choice must not narrow the check (each backend is tried in turn).
  unset HRTAO_RAY_BACKEND
  exec python3 "$HERE/gpu_check.py" --bin "$bin" --root "$root" --out "$out" ${small[@]+"${small[@]}"}
}

case ${1:-} in
  bundle) shift; bundle "$@" ;;
  run) shift; run "$@" ;;
  *) usage ;;
esac
