#!/usr/bin/env bash
# Compressed files against their uncompressed twins: each pair rendered from one camera with per-pixel RTAO
# (`--mode rtao`, 128 rays, one frame: the image of the geometry, no cache), the AO compared with
# scripts/image-mae.py over the pixels either covers; also the unique triangles, the open time (`load_ms`) and,
# where the Blender Cycles reference of the view exists ($HRTAO_SHARED/refs), each one's MAE against it. Writes
# docs/bench/formats/<name>.json (schema hrtao-format-compare/1), which `cargo run -p bench-report` tabulates.
#
#   scripts/bench-formats.sh [--hrtao target/debug/hrtao]
#
# Pairs: testdata's rod.glb and its gltfpack (meshopt) and gltf-pipeline (Draco) twins; assimp's Draco
# 2CylinderEngine (scripts/fetch-assimp-models.sh) against $HRTAO_SHARED's uncompressed one, when present.
set -euo pipefail
cd "$(dirname "$0")/.."
hrtao=target/debug/hrtao
while [ $# -gt 0 ]; do
    case "$1" in
        --hrtao) hrtao=$2; shift 2 ;;
        *) echo "bench-formats: unknown argument $1" >&2; exit 2 ;;
    esac
done
[ -x "$hrtao" ] || cargo build -p hrtao-viewer >&2
shared=${HRTAO_SHARED:-../shared}
out=docs/bench/formats
mkdir -p "$out"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
export MESA_SHADER_CACHE_DISABLE=${MESA_SHADER_CACHE_DISABLE:-false}

# render NAME SCENE CAMERA-ARGS...: AO, shaded image and stats of one file.
render() {
    local name=$1 scene=$2
    shift 2
    "$hrtao" render --scene "$scene" "$@" --mode rtao --rays 128 --frames 1 \
        --ao-out "$tmp/$name.pfm" --out "$tmp/$name.png" --stats "$tmp/$name.json" >"$tmp/$name.log" 2>&1 || {
        cat "$tmp/$name.log" >&2
        echo "bench-formats: $scene did not render" >&2
        exit 1
    }
}

# compare NAME FORMAT FILE REFERENCE-FILE [CYCLES-PFM] -- CAMERA-ARGS...
compare() {
    local name=$1 format=$2 file=$3 reference=$4 cycles=$5
    shift 6
    render "$name" "$file" "$@"
    render "$name.reference" "$reference" "$@"
    python3 - "$tmp" "$name" "$format" "$file" "$reference" "$cycles" "$out/$name.json" <<'EOF'
import json, subprocess, sys
tmp, name, fmt, file, reference, cycles, dest = sys.argv[1:]
def mae(a, b):
    r = subprocess.run(["python3", "scripts/image-mae.py", f"{a}.png", f"{a}.pfm", f"{b}.png", f"{b}.pfm"],
                       check=True, capture_output=True, text=True)
    return json.loads(r.stdout)
def cycles_mae(a):
    # Against the reference's AO over the pixels it covers (the Cycles PFM has no shaded twin): AO < 0.999.
    if not cycles:
        return None
    import struct
    def pfm(p):
        b = open(p, "rb").read()
        kind, dims, scale, data = b.split(b"\n", 3)
        w, h = map(int, dims.split())
        n = w * h * (3 if kind.strip() == b"PF" else 1)
        v = struct.unpack(("<" if float(scale) < 0 else ">") + f"{n}f", data[:4 * n])
        return v[0::3] if kind.strip() == b"PF" else v
    x, y = pfm(f"{a}.pfm"), pfm(cycles)
    px = [(p, q) for p, q in zip(x, y) if p < 0.999 or q < 0.999]
    return sum(abs(p - q) for p, q in px) / max(len(px), 1)
s, r = (json.load(open(f"{tmp}/{n}.json")) for n in (name, f"{name}.reference"))
m = mae(f"{tmp}/{name}", f"{tmp}/{name}.reference")
json.dump({
    "schema": "hrtao-format-compare/1",
    "name": name,
    "format": fmt,
    "file": file.split("/")[-1],
    "reference": reference.split("/")[-1],
    "width": s["width"], "height": s["height"],
    "unique_triangles": s["unique_triangles"], "reference_unique_triangles": r["unique_triangles"],
    "instances": s["instances"], "reference_instances": r["instances"],
    "load_ms": s["load_ms"], "reference_load_ms": r["load_ms"],
    "ao_mae": m["ao_mae"], "covered": m["covered"],
    "cycles_mae": cycles_mae(f"{tmp}/{name}"),
    "reference_cycles_mae": cycles_mae(f"{tmp}/{name}.reference"),
}, open(dest, "w"), indent=1)
print(f"{name}: AO MAE {m['ao_mae']:.4f} over {m['covered']} pixels", file=sys.stderr)
EOF
}

# The shared reference view of rod.glb where it is there (then also against Cycles), else the framed default.
rod=testdata/scenes/rod_assembly
rod_cam=(--width 640 --height 360)
rod_cycles=""
if [ -f "$shared/refs/rod_640x360.camera.json" ]; then
    radius=$(python3 -c "import json; print(json.load(open('$shared/refs/index.json'))['rod']['radius'])")
    rod_cam+=(--camera "$shared/refs/rod_640x360.camera.json" --radius "$radius")
    rod_cycles="$shared/refs/rod_640x360.cycles.pfm"
fi
compare rod_meshopt "meshopt (gltfpack -cc)" $rod/rod.meshopt.glb $rod/rod.glb "$rod_cycles" -- "${rod_cam[@]}"
compare rod_draco "Draco (gltf-pipeline -d)" $rod/rod.draco.glb $rod/rod.glb "$rod_cycles" -- "${rod_cam[@]}"

engine="$shared/scenes/2CylinderEngine/2CylinderEngine.gltf"
if [ -f "$engine" ]; then
    assimp=$(scripts/fetch-assimp-models.sh)
    radius=$(python3 -c "import json; print(json.load(open('$shared/refs/index.json'))['engine']['radius'])")
    compare engine_draco "Draco (assimp's test model)" "$assimp/glTF2/draco/2CylinderEngine.gltf" "$engine" \
        "$shared/refs/engine_640x360.cycles.pfm" -- \
        --camera "$shared/refs/engine_640x360.camera.json" --width 640 --height 360 --radius "$radius"
else
    echo "bench-formats: no $engine (HRTAO_SHARED): the Draco engine is left out" >&2
fi

# IFC: the open time (worker start, IfcOpenShell's tessellation, transfer, scene) of assimp's FZK-Haus, when the
# IFC worker is installed (scripts/install-ifc.sh). Schema hrtao-format-open/1.
assimp=$(scripts/fetch-assimp-models.sh)
ifc="$assimp/IFC/AC14-FZK-Haus.ifc"
if "$hrtao" render --scene "$ifc" --width 320 --height 180 --mode none --stats "$tmp/ifc.json" >"$tmp/ifc.log" 2>&1; then
    python3 - "$tmp/ifc.json" "$out/ifc_fzk_haus.json" <<'EOF'
import json, os, sys
s = json.load(open(sys.argv[1]))
json.dump({
    "schema": "hrtao-format-open/1",
    "name": "ifc_fzk_haus",
    "format": "IFC2X3 (IfcOpenShell worker)",
    "file": os.path.basename(s["scene"]),
    "load_ms": s["load_ms"],
    "unique_triangles": s["unique_triangles"],
    "instanced_triangles": s["instanced_triangles"],
    "meshes": s["meshes"],
    "instances": s["instances"],
    "load_average": os.getloadavg()[0],
}, open(sys.argv[2], "w"), indent=1)
print(f"ifc_fzk_haus: opened in {s['load_ms']:.0f} ms", file=sys.stderr)
EOF
else
    echo "bench-formats: $ifc did not open (is the IFC worker installed? scripts/install-ifc.sh):" >&2
    tail -3 "$tmp/ifc.log" >&2
fi
