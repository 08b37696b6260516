# Shared by scripts/make-references.sh and scripts/make-sky-references.sh (sourced from the repository root):
# Blender installed when missing, and one headless Blender run of a reference script with its log kept on failure.

# abs PATH: PATH made absolute against $CALLER (where the sourcing script was started).
abs() { case "$1" in /*) echo "$1" ;; *) echo "$CALLER/$1" ;; esac; }

# ensure_blender TAG: sets BLENDER (default: blender on PATH); installs Blender and NumPy from the distribution's
# packages when missing (Debian/Ubuntu; sudo when not root).
ensure_blender() {
  BLENDER=${BLENDER:-blender}
  if ! command -v "$BLENDER" >/dev/null 2>&1; then
    local sudo=""
    if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
    echo "[$1] installing blender and python3-numpy"
    $sudo apt-get update
    $sudo env DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends blender python3-numpy
  fi
}

# run_blender TAG SCRIPT PREFIX ARGS...: scripts/SCRIPT.py in headless Blender with ARGS, then --out PREFIX
# --samples $samples --threads $THREADS (default all cores); prints the script's own log lines, or the end of the
# log (PREFIX.log) and exits 1 when Blender fails.
run_blender() {
  local tag=$1 script=$2 prefix=$3
  shift 3
  local log="$prefix.log"
  mkdir -p "$(dirname "$prefix")"
  if ! "$BLENDER" -b --factory-startup -noaudio --python-exit-code 3 -P "$ROOT/scripts/$script.py" -- \
      "$@" --out "$prefix" --samples "$samples" --threads "${THREADS:-0}" </dev/null >"$log" 2>&1; then
    echo "[$tag] Blender failed on $prefix; the end of $log:" >&2
    tail -n 30 "$log" >&2
    exit 1
  fi
  grep "^\[$script\]" "$log"
  rm -f "$log"
}
