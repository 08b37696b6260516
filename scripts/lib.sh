# Small helpers the scripts share (sourced; paths relative to the repository root or absolute).

# index_field INDEX KEY FIELD: the FIELD of entry KEY in the JSON object INDEX (testdata/refs/index.json, the shared
# scenes' refs/index.json).
index_field() {
  python3 -c "import json,sys; print(json.load(open(sys.argv[1]))[sys.argv[2]][sys.argv[3]])" "$1" "$2" "$3"
}

# unpack_deb TAG PACKAGE DIR: Debian's PACKAGE downloaded (apt-get download) and unpacked into DIR/deb/root; the
# caller copies what it needs and removes DIR/deb. Exits 1, saying so as TAG, when the download fails.
unpack_deb() {
  mkdir -p "$3/deb"
  (cd "$3/deb" && rm -f "$2"_*.deb && apt-get download "$2" >/dev/null 2>&1) || {
    echo "$1: apt-get download $2 failed (run apt-get update?)" >&2
    exit 1
  }
  dpkg -x "$3/deb/$2"_*.deb "$3/deb/root"
}

# bench_environment: what the benchmark scripts run under: HRTAO_SHARED (default /work/shared, the shared scenes),
# Mesa's shader cache kept in target/ (from the repository root).
bench_environment() {
  : "${HRTAO_SHARED:=/work/shared}"
  export MESA_SHADER_CACHE_DISABLE=false MESA_SHADER_CACHE_DIR=$PWD/target/mesa-shader-cache
}
