#!/usr/bin/env bash
# Installs IfcOpenShell (the reader of .ifc files, run by hrtao in a Python worker process) into a venv that hrtao
# owns: $XDG_DATA_HOME/hrtao/ifc-venv (an absolute XDG_DATA_HOME, else ~/.local/share), with the version pinned. Skips the install when that
# version is there. Needs python3-venv (scripts/install-deps.sh installs it and then runs this script).
# The viewer runs the venv's bin/python3 (HRTAO_IFC_PYTHON overrides it).
set -euo pipefail
pin="0.8.4.post1"   # crates/scene/src/ifc_load.rs: IFCOPENSHELL_VERSION
# As hrtao reads it (the dirs crate, the XDG spec): a relative XDG_DATA_HOME is ignored.
data_home="${XDG_DATA_HOME:-}"
case "$data_home" in /*) ;; *) data_home="$HOME/.local/share" ;; esac
venv="$data_home/hrtao/ifc-venv"
py="$venv/bin/python3"
if [ -x "$py" ] && [ "$("$py" -I -c 'import ifcopenshell; print(ifcopenshell.version)' 2>/dev/null)" = "$pin" ]; then
  echo "[install-ifc] IfcOpenShell $pin present in $venv"
  exit 0
fi
# Debian's interpreter first: the wheel is built for its CPython 3.11.
base=/usr/bin/python3
[ -x "$base" ] || base=python3
echo "[install-ifc] installing IfcOpenShell $pin into $venv"
mkdir -p "$(dirname "$venv")"
"$base" -m venv --clear "$venv"
"$venv/bin/pip" install --quiet --disable-pip-version-check "ifcopenshell==$pin"
"$py" -I -c 'import ifcopenshell, ifcopenshell.geom; print("[install-ifc] IfcOpenShell", ifcopenshell.version)'
