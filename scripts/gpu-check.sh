#!/usr/bin/env bash
# The GPU check: one prepared command for a bare Linux machine with a GPU (no display, no network, maybe no Vulkan
# loader installed), made here and run there.
#
#   scripts/gpu-check.sh bundle [DIR]            (here) a release hrtao without OpenCASCADE, stripped, with
#                                                libvulkan.so.1, the X client libraries NVIDIA's driver needs, the
#                                                Khronos validation layer, the scenes, the Cycles references and
#                                                this driver, in DIR (default .gpu-check/, at most 64 MiB)
#   DIR/gpu-check.sh run [--small] [--out OUT]   (there) checks the machine (python3, glibc, a GPU), then
#       [--allow-cpu] [--step-timeout S]         correctness against the references, the hash map overloaded,
#       [--budget S]                             small renders under the validation layer (GPU-assisted too), and
#                                                `hrtao bench` at 1920x1080 (--small: 160x90); each step is killed
#                                                at S seconds (240), the run stops starting steps at its budget
#                                                (540 s); OUT/report.json and OUT/report.md are rewritten after
#                                                each step (default OUT: ./gpu-check-out). A CPU device (lavapipe)
#                                                is refused unless --allow-cpu.
#   scripts/gpu-check.sh run ...                 the same from the repository (HRTAO_BIN, else target/release/hrtao)
#
# Exit status of run: 0 every check passed, 1 a check failed or a step timed out, 2 the machine lacks what hrtao
# needs, or its device is not a GPU.
# Environment: HRTAO_BIN (run: the binary; bundle: use it instead of building), HRTAO_SHARED (bundle: the folder of
# extra scenes, default ../shared next to the repository), GPU_CHECK_MAX_MIB (bundle: the size limit, 64),
# HRTAO_GPU_CHECK_HANG_STEP (run, a test hook: that step hangs, to prove its timeout).
set -euo pipefail
HERE=$(cd "$(dirname "$0")" && pwd)

usage() {
  sed -n '2,23p' "$0" | sed 's/^# \{0,1\}//' >&2
  exit 2
}

# ---------------------------------------------------------------- bundle (on the development machine)

# The highest GLIBC_x.y the files need: the target's glibc must be at least that.
glibc_needed() {
  objdump -T "$@" | grep -o 'GLIBC_[0-9.]*' | sort -u -V | tail -1
}

# Where the dynamic linker finds library $1 here (x86-64), from ldconfig's cache (awk reads the whole list: leaving
# early would end ldconfig by SIGPIPE, a failure under pipefail).
lib_path() {
  "$(command -v ldconfig || echo /sbin/ldconfig)" -p | awk -v l="$1" '$1 == l && /x86-64/ && !n++ {print $NF}'
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
  # The Vulkan loader of this machine (Debian 12): the target may have none.
  local loader lib path dep
  loader=$(lib_path libvulkan.so.1)
  [ -n "$loader" ] || { echo "gpu-check: no libvulkan.so.1 here to bundle (apt install libvulkan1)" >&2; exit 1; }
  cp -L "$loader" "$dir/lib/libvulkan.so.1"
  # The C++ runtime the glTF decoders link (they need only CXXABI_1.3, which every libstdc++ has) and the validation
  # layer: used there only when the machine has none (or one too old for the layer), so that a newer system copy,
  # which the GPU driver may need, is never shadowed.
  mkdir -p "$dir/lib/fallback"
  for lib in libstdc++.so.6 libgcc_s.so.1; do
    cp -L "$(lib_path "$lib")" "$dir/lib/fallback/"
  done
  # NVIDIA's Vulkan driver is its GLX library (libGLX_nvidia.so.0), which links the X client libraries (libX11,
  # libXext) and glvnd's libGLdispatch: a bare headless machine often lacks them, and the loader then says only
  # that it found no driver. Their copies, with what they link (glibc's own libraries aside), are used there only
  # when the machine lacks one of them.
  mkdir -p "$dir/lib/x11"
  for lib in libX11.so.6 libXext.so.6 libGLdispatch.so.0; do
    path=$(lib_path "$lib")
    [ -n "$path" ] || { echo "gpu-check: no $lib here to bundle (apt install libx11-6 libxext6 libglvnd0)" >&2; exit 1; }
    cp -L "$path" "$dir/lib/x11/$lib"
    while read -r dep path; do
      case $dep in
        libc.so.* | libm.so.* | libdl.so.* | libpthread.so.* | librt.so.* | ld-linux*) ;;
        *) [ -e "$dir/lib/x11/$dep" ] || cp -L "$path" "$dir/lib/x11/$dep" ;;
      esac
    done < <(ldd "$dir/lib/x11/$lib" | awk '$2 == "=>" && $3 ~ /^\// {print $1, $3}')
  done
  # The Khronos validation layer of this machine (22 MiB, gzip'd to 7: `run` unpacks it into OUT), with its
  # manifest naming the library beside it.
  local layer_json=/usr/share/vulkan/explicit_layer.d/VkLayer_khronos_validation.json layer
  [ -f "$layer_json" ] || {
    echo "gpu-check: no Khronos validation layer here to bundle (apt install vulkan-validationlayers)" >&2
    exit 1
  }
  layer=$(lib_path libVkLayer_khronos_validation.so)
  [ -n "$layer" ] || layer=/usr/lib/x86_64-linux-gnu/libVkLayer_khronos_validation.so
  mkdir -p "$dir/layers"
  gzip -6 -c "$layer" >"$dir/layers/libVkLayer_khronos_validation.so.gz"
  python3 -c 'import json, sys
m = json.load(open(sys.argv[1]))
m["layer"]["library_path"] = "./libVkLayer_khronos_validation.so"
json.dump(m, open(sys.argv[2], "w"), indent=1)' "$layer_json" "$dir/layers/VkLayer_khronos_validation.json"
  # What the bundle's binary and libraries need of glibc: `run` checks it first.
  glibc_needed "$dir/bin/hrtao" "$dir/lib/libvulkan.so.1" "$dir"/lib/x11/* "$dir"/lib/fallback/* "$layer" |
    sed 's/GLIBC_//' >"$dir/glibc-needed"
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

  echo "gpu-check: the binary and the bundled libraries need glibc >= $(cat "$dir/glibc-needed"); the binary links" \
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

# A report saying why the run could not start (python3 may be missing: written by the shell).
early_report() {
  local e=${1//\\/\\\\}
  e=${e//\"/\\\"}
  mkdir -p "$out"
  printf '{"schema": "hrtao-gpu-check/1", "passed": false, "complete": true, "error": "%s", "device": {},
 "checks": [], "benches": [], "skipped": [], "steps": []}\n' "$e" >"$out/report.json"
  printf '# GPU check: not run\n\n**%s**\n' "$1" >"$out/report.md"
}

# Exit status 2 with what the machine lacks, on stderr and in the report.
missing() {
  echo "gpu-check: missing: $1" >&2
  early_report "missing: $1"
  exit 2
}

# python3 runs the check (gpu_check.py: the standard library of Python 3.6 or newer).
check_python() {
  command -v python3 >/dev/null ||
    missing "python3 (3.6 or newer): the check itself (gpu_check.py) runs on it; install python3"
  python3 -c 'import sys; sys.exit(sys.version_info < (3, 6))' ||
    missing "python3 3.6 or newer, for gpu_check.py (this machine has $(python3 --version 2>&1))"
}

# The machine's glibc against $1, the version the binary and its libraries need.
check_glibc() {
  local have
  have=$(getconf GNU_LIBC_VERSION 2>/dev/null | awk '{print $2}') || true
  [ -n "$have" ] || have=$(ldd --version 2>/dev/null | awk 'NR == 1 {print $NF}') || true
  if [ -z "$have" ]; then
    echo "gpu-check: warning: this machine's glibc version is unknown (the binary needs glibc >= $1)"
  elif [ "$(printf '%s\n%s\n' "$1" "$have" | sort -V | head -n 1)" != "$1" ]; then
    missing "glibc >= $1 (the bundled hrtao and its libraries need GLIBC_$1; this machine has glibc $have): make the \
bundle on a machine with an older glibc, or run it on one with a newer glibc"
  else
    echo "gpu-check: glibc $have (the binary needs >= $1)"
  fi
}

run() {
  local out=$PWD/gpu-check-out args=() bin root needed
  while [ $# -gt 0 ]; do
    case $1 in
      --small | --allow-cpu) args+=("$1") ;;
      --out) [ $# -ge 2 ] || usage; out=$2; shift ;;
      --step-timeout | --budget) [ $# -ge 2 ] || usage; args+=("$1" "$2"); shift ;;
      *) usage ;;
    esac
    shift
  done
  mkdir -p "$out"
  out=$(cd "$out" && pwd)
  check_python
  if [ -x "$HERE/bin/hrtao" ]; then
    # A bundle: its binary, and its loader ahead of any other.
    root=$HERE
    bin=${HRTAO_BIN:-$HERE/bin/hrtao}
    needed=$(cat "$HERE/glibc-needed" 2>/dev/null || true)
    export LD_LIBRARY_PATH="$HERE/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
  else
    root=$(cd "$HERE/.." && pwd)
    bin=${HRTAO_BIN:-${CARGO_TARGET_DIR:-$root/target}/release/hrtao}
    needed=$( (glibc_needed "$bin" | sed 's/GLIBC_//') 2>/dev/null || true)
  fi
  [ -x "$bin" ] || missing "an hrtao binary at $bin (set HRTAO_BIN, or build it)"
  if [ -n "$needed" ]; then check_glibc "$needed"; fi
  if [ "$root" = "$HERE" ]; then
    # The validation layer, unpacked into OUT and found there first.
    local layer=""
    if [ -f "$HERE/layers/libVkLayer_khronos_validation.so.gz" ]; then
      mkdir -p "$out/vk-layer"
      layer=$out/vk-layer/libVkLayer_khronos_validation.so
      python3 -c 'import gzip, shutil, sys; shutil.copyfileobj(gzip.open(sys.argv[1]), open(sys.argv[2], "wb"))' \
        "$HERE/layers/libVkLayer_khronos_validation.so.gz" "$layer"
      cp "$HERE/layers/VkLayer_khronos_validation.json" "$out/vk-layer/"
      export VK_LAYER_PATH=$out/vk-layer
    fi
    if ! python3 -c 'import ctypes, sys
for lib in ["libstdc++.so.6", "libgcc_s.so.1"] + sys.argv[1:]:
    ctypes.CDLL(lib)' ${layer:+"$layer"} 2>/dev/null; then
      echo "gpu-check: no C++ runtime on this machine, or one too old for the validation layer: the bundle's" \
        "(lib/fallback)"
      export LD_LIBRARY_PATH="$LD_LIBRARY_PATH:$HERE/lib/fallback"
    fi
    # The X client libraries and libGLdispatch that NVIDIA's driver library links.
    if [ -d "$HERE/lib/x11" ] && ! python3 -c 'import ctypes
for lib in ("libX11.so.6", "libXext.so.6", "libGLdispatch.so.0"):
    ctypes.CDLL(lib)' 2>/dev/null; then
      echo "gpu-check: this machine lacks libX11, libXext or libGLdispatch, which NVIDIA's Vulkan driver links:" \
        "the bundle's (lib/x11)"
      export LD_LIBRARY_PATH="$LD_LIBRARY_PATH:$HERE/lib/x11"
    fi
  fi
  # NVIDIA's container layout: the driver's ICD file outside the loader's search path.
  local nvidia=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
  if [ -z "${VK_DRIVER_FILES:-}" ] && [ -f "$nvidia" ]; then
    export VK_DRIVER_FILES=$nvidia
  fi
  # The driver library that file names (libGLX_nvidia.so.0) lives beside it, maybe off the linker's path.
  if [ -d /usr/local/nvidia/lib64 ]; then
    export LD_LIBRARY_PATH="${LD_LIBRARY_PATH:+$LD_LIBRARY_PATH:}/usr/local/nvidia/lib64"
  fi
  # The caller's backend choice must not narrow the check (each backend is tried in turn).
  unset HRTAO_RAY_BACKEND
  exec python3 "$HERE/gpu_check.py" --bin "$bin" --root "$root" --out "$out" ${args[@]+"${args[@]}"}
}

case ${1:-} in
  bundle) shift; bundle "$@" ;;
  run) shift; run "$@" ;;
  *) usage ;;
esac
