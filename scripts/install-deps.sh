#!/usr/bin/env bash
# Installs the system packages hrtao needs on Debian 12 (bookworm) / Ubuntu, skipping what is present.
# Vulkan loader, Mesa lavapipe with VK_KHR_ray_query (Mesa >= 23; on Debian 12 from bookworm-backports),
# glslc (shader compiler), Xvfb (windows without a display), xdotool (X input in tests), zenity (the Open…
# dialog without a desktop portal), Khronos validation layers; OpenCASCADE 7.6 development packages (STEP/IGES
# through XCAF, the `occt` feature), desktop-file-utils (the desktop entry's test), python3-venv (IFC: then
# scripts/install-ifc.sh puts IfcOpenShell, pinned, in a venv under the user's data folder). The STEP test files come from
# Debian's gmsh-doc package (scripts/fetch-step-data.sh).
# `install-deps.sh --bench` also installs what only measurements use: gmsh (the comparison mesher of the STEP AO
# check, an ignored test) and f3d (the reference viewer of the STEP benchmark).
set -euo pipefail

extra=()
for arg in "$@"; do
  case "$arg" in
    --bench) extra+=(gmsh f3d) ;;
    *) echo "install-deps: unknown option $arg (known: --bench)" >&2; exit 2 ;;
  esac
done

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi

need=()
have_pkg() { dpkg-query -W -f='${Status}' "$1" 2>/dev/null | grep -q "install ok installed"; }
# xdotool: the window tests send real X input events. zenity: the Open… dialog when no desktop portal runs
# (rfd's fallback; the window tests drive it).
# OpenCASCADE: libocct-data-exchange-dev (STEP/IGES readers, XCAF), libocct-ocaf-dev (the XCAF document),
# libocct-modeling-*-dev (B-rep, BRepMesh), libocct-foundation-dev (TKernel, TKMath); a C++ compiler for the bridge.
for p in libvulkan1 vulkan-tools glslc xvfb vulkan-validationlayers xauth libxkbcommon-x11-0 libx11-xcb1 xdotool zenity \
  g++ libocct-data-exchange-dev libocct-ocaf-dev libocct-modeling-algorithms-dev libocct-modeling-data-dev \
  libocct-foundation-dev desktop-file-utils python3-venv ${extra[@]+"${extra[@]}"}; do
  have_pkg "$p" || need+=("$p")
done

# lavapipe must be new enough to expose VK_KHR_ray_query (Mesa 25 in bookworm-backports).
lavapipe_ok() {
  command -v vulkaninfo >/dev/null 2>&1 || return 1
  local out
  out=$(vulkaninfo 2>/dev/null || true)
  [[ "$out" == *VK_KHR_ray_query* ]]
}

. /etc/os-release
backports=""
if [ "${ID:-}" = "debian" ] && [ "${VERSION_CODENAME:-}" = "bookworm" ]; then
  backports="bookworm-backports"
  if ! grep -rqs "bookworm-backports" /etc/apt/sources.list /etc/apt/sources.list.d/; then
    echo "[install-deps] adding bookworm-backports to apt sources"
    echo "deb http://deb.debian.org/debian bookworm-backports main" | $SUDO tee /etc/apt/sources.list.d/hrtao-backports.list >/dev/null
    updated_needed=1
  fi
fi

mesa_need=0
if ! have_pkg mesa-vulkan-drivers; then mesa_need=1
elif ! lavapipe_ok; then mesa_need=1; fi

ifc() { bash "$(dirname "$0")/install-ifc.sh"; }

if [ ${#need[@]} -eq 0 ] && [ $mesa_need -eq 0 ] && [ -z "${updated_needed:-}" ]; then
  echo "[install-deps] system packages present"
  ifc
  exit 0
fi

echo "[install-deps] installing: ${need[*]} $( [ $mesa_need -eq 1 ] && echo mesa-vulkan-drivers)"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
if [ ${#need[@]} -gt 0 ]; then
  $SUDO apt-get install -y -qq --no-install-recommends "${need[@]}"
fi
if [ $mesa_need -eq 1 ]; then
  if [ -n "$backports" ]; then
    $SUDO apt-get install -y -qq --no-install-recommends -t "$backports" mesa-vulkan-drivers
  else
    $SUDO apt-get install -y -qq --no-install-recommends mesa-vulkan-drivers
  fi
fi
if ! lavapipe_ok; then
  echo "[install-deps] WARNING: no Vulkan device with VK_KHR_ray_query found after install." >&2
  echo "[install-deps] hrtao needs Mesa >= 23 lavapipe (mesa-vulkan-drivers) or a GPU driver with ray queries." >&2
fi
ifc
echo "[install-deps] done"
