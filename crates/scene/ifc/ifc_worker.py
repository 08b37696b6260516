# hrtao's IFC worker: reads an IFC file with IfcOpenShell and writes the frames of crates/scene/src/cad.rs to
# stdout (tag byte, little-endian u64 length, payload): 'P' progress, 'E' an error, 'M' the model (layout version
# 2). Run by the loader (crates/scene/src/ifc_load.rs) as `PYTHON -I -c SCRIPT PATH` under a CPU-time and an
# address-space limit; it embeds this file, so an installed hrtao needs only the venv.
#
# One part per representation (the geometry iterator with local coordinates shares a mapped representation
# between the products that place it: one mesh, many instances), one primitive per style colour. Nodes: the
# spatial tree (IfcProject -> IfcSite -> IfcBuilding -> IfcBuildingStorey -> elements, through IfcRelAggregates,
# IfcRelNests and IfcRelContainedInSpatialStructure), labelled "Name (IfcClass)"; a product with geometry outside
# that tree is a root.
#
# Before tessellating, what the products' representations expand to is counted (mapped_expansion: mapped items
# multiplied through their nesting, a map shared by products once): past the loader's cap (HRTAO_IFC_MAX_ITEMS) the
# answer is an error naming the count and the cap, in seconds, not a tessellation of 10^9 boxes. A file cut short
# is read up to its last whole statement (HRTAO_IFC_COMPLETE_BYTES, open_whole_statements).
#
# Units: the file's length unit is the one its IfcProject declares (IfcUnitAssignment: an IfcSIUnit with its
# prefix, or an IfcConversionBasedUnit such as the inch), found here. The iterator converts positions to metres
# with the unit it finds itself (it.unit_magnitude()), and IfcOpenShell 0.8.4 finds none when an
# IfcProjectLibrary is beside the project: then it leaves them in the file's unit, as metres. (Its
# convert-back-units setting is no way out: it converts the vertices back but not the placements.) So the header
# reports the metres per unit of the positions sent (the project's unit over the iterator's) and the file's unit,
# or 0.0 when the file declares none (the loader then warns and takes metres).
import os
import struct
import sys

MODEL_FRAME_VERSION = 2
PINNED = "0.8.4.post1"
SPATIAL = ("IfcProject", "IfcSite", "IfcBuilding", "IfcBuildingStorey", "IfcFacility", "IfcFacilityPart")


def frame(tag, payload):
    out = sys.stdout.buffer
    out.write(tag + struct.pack("<Q", len(payload)))
    out.write(payload)
    out.flush()


def text(s):
    b = (s or "").encode("utf-8", "replace")
    return struct.pack("<Q", len(b)) + b


def progress(stage, fraction):
    frame(b"P", text(stage) + struct.pack("<d", fraction))


def error(message):
    frame(b"E", text(message))


def colour(c):
    if c is None:
        return b"\x00" + struct.pack("<4f", 0, 0, 0, 0)
    return b"\x01" + struct.pack("<4f", *c)


def label(entity):
    name = getattr(entity, "Name", None) or ""
    cls = entity.is_a()
    return f"{name} ({cls})" if name else cls


def part_payload(np, geometry):
    """A part's primitives: the triangles grouped by style, with the iterator's per-corner normals."""
    verts = np.frombuffer(geometry.verts_buffer, dtype="<f8").reshape(-1, 3).astype("<f4")
    normals = np.frombuffer(geometry.normals_buffer, dtype="<f8").reshape(-1, 3).astype("<f4")
    if len(normals) != len(verts):
        normals = np.zeros((0, 3), dtype="<f4")
    faces = np.frombuffer(geometry.faces_buffer, dtype="<i4").reshape(-1, 3)
    ids = np.frombuffer(geometry.material_ids_buffer, dtype="<i4")
    materials = list(geometry.materials)
    if len(ids) != len(faces):
        ids = np.full(len(faces), -1, dtype="<i4")
    prims = []
    for m in sorted(set(ids.tolist())):
        tri = faces[ids == m]
        if len(tri) == 0:
            continue
        used = np.unique(tri)
        remap = np.full(len(verts), 0, dtype="<u4")
        remap[used] = np.arange(len(used), dtype="<u4")
        c = None
        if 0 <= m < len(materials):
            d = materials[m].diffuse
            t = materials[m].transparency
            alpha = 1.0 - t if t == t and 0.0 <= t <= 1.0 else 1.0
            c = (d.r(), d.g(), d.b(), alpha)
        n = normals[used] if len(normals) else normals
        p = colour(c) + b"\x01"
        p += struct.pack("<Q", len(used)) + verts[used].tobytes()
        p += struct.pack("<Q", len(n)) + n.tobytes()
        p += struct.pack("<Q", tri.size) + remap[tri].astype("<u4").tobytes()
        prims.append(p)
    return struct.pack("<Q", len(prims)) + b"".join(prims)


SI_PREFIX = {
    None: 1.0, "EXA": 1e18, "PETA": 1e15, "TERA": 1e12, "GIGA": 1e9, "MEGA": 1e6, "KILO": 1e3, "HECTO": 1e2,
    "DECA": 1e1, "DECI": 1e-1, "CENTI": 1e-2, "MILLI": 1e-3, "MICRO": 1e-6, "NANO": 1e-9, "PICO": 1e-12,
    "FEMTO": 1e-15, "ATTO": 1e-18,
}


def length_unit_m(unit, depth=0):
    """Metres per `unit` (an IfcSIUnit, or an IfcConversionBasedUnit such as the inch, through its factor's unit),
    or None where it is not a length unit."""
    if unit is None or depth > 8:
        return None
    if unit.is_a("IfcSIUnit"):
        return SI_PREFIX.get(unit.Prefix) if unit.Name == "METRE" else None
    if unit.is_a("IfcConversionBasedUnit"):
        factor = unit.ConversionFactor
        value = getattr(factor.ValueComponent, "wrappedValue", None) if factor else None
        inner = length_unit_m(factor.UnitComponent, depth + 1) if factor else None
        if isinstance(value, (int, float)) and inner is not None:
            return float(value) * inner
    return None


def project_length_unit(f):
    """Metres per length unit of the IfcProject's IfcUnitAssignment, or None where it declares none (or one that
    is not a length, or not positive)."""
    for project in f.by_type("IfcProject"):
        assignment = getattr(project, "UnitsInContext", None)
        for unit in (assignment.Units or ()) if assignment else ():
            if getattr(unit, "UnitType", None) != "LENGTHUNIT":
                continue
            try:
                m = length_unit_m(unit)
            except Exception:  # noqa: BLE001 - a malformed unit is no unit
                m = None
            if m is not None and m == m and 0.0 < m < float("inf"):
                return float(m)
    return None


def storey_world(storey, iterator_unit):
    """A translation to the storey's height in the positions' unit: its placement's z (file units), else its
    Elevation attribute, else 0."""
    z = None
    try:
        import ifcopenshell.util.placement

        if storey.ObjectPlacement is not None:
            z = float(ifcopenshell.util.placement.get_local_placement(storey.ObjectPlacement)[2][3])
    except Exception:  # noqa: BLE001 - a placement IfcOpenShell cannot compose: the attribute
        z = None
    if z is None or z != z:
        e = getattr(storey, "Elevation", None)
        z = float(e) if isinstance(e, (int, float)) else 0.0
    return struct.pack("<16d", 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, z * iterator_unit, 1)


def children(entity):
    out = []
    for rel in getattr(entity, "IsDecomposedBy", None) or ():
        out.extend(rel.RelatedObjects)
    for rel in getattr(entity, "IsNestedBy", None) or ():
        out.extend(rel.RelatedObjects)
    for rel in getattr(entity, "ContainsElements", None) or ():
        out.extend(rel.RelatedElements)
    return out


BODY = ("Body", "Facetation")
MAX_MAP_DEPTH = 64
SATURATED = 10**18


class ExpansionError(Exception):
    """The file's mapped items expand past the cap, or nest too deep: the message says which."""


def mapped_expansion(f, cap):
    """Counts what the products' representations expand to before anything is tessellated: each IfcMappedItem
    stands for every item of its representation map's representation, multiplied through the nesting. A product
    whose body is one mapped item shares its map's mesh with the other products mapping it (counted once: they are
    instances); any other representation is tessellated on its own. Returns (items, products, deepest nesting), or
    raises ExpansionError past `cap` items or past MAX_MAP_DEPTH levels."""
    memo = {}  # representation id -> items it expands to
    depth_of = {}  # representation id -> mapped-item levels below it

    def expand(rep, depth):
        rid = rep.id()
        if rid in memo:
            return memo[rid], depth_of[rid]
        if depth > MAX_MAP_DEPTH:
            raise ExpansionError(
                f"mapped items nest deeper than {MAX_MAP_DEPTH} levels (IfcMappedItem in representation #{rid})"
            )
        memo[rid], depth_of[rid] = 0, 0  # a cycle adds nothing
        n, deepest = 0, 0
        for item in rep.Items or ():
            if item.is_a("IfcMappedItem"):
                source = item.MappingSource
                inner = getattr(source, "MappedRepresentation", None) if source is not None else None
                if inner is not None:
                    k, d = expand(inner, depth + 1)
                    n += k
                    deepest = max(deepest, d + 1)
            else:
                n += 1
            n = min(n, SATURATED)
        memo[rid], depth_of[rid] = n, deepest
        return n, deepest

    shared = {}  # ("map" or "rep", id) -> items
    products = 0
    deepest = 0
    for product in f.by_type("IfcProduct"):
        if product.is_a("IfcOpeningElement") or product.is_a("IfcSpace"):
            continue
        shape = getattr(product, "Representation", None)
        reps = [r for r in (getattr(shape, "Representations", None) or ()) if r.is_a("IfcShapeRepresentation")]
        body = [r for r in reps if r.RepresentationIdentifier in BODY]
        if not (body or reps):
            continue
        products += 1
        for rep in body or reps:
            items = rep.Items or ()
            if len(items) == 1 and items[0].is_a("IfcMappedItem") and items[0].MappingSource is not None:
                key = ("map", items[0].MappingSource.id())
            else:
                key = ("rep", rep.id())
            if key not in shared:
                n, d = expand(rep, 0)
                shared[key] = n
                deepest = max(deepest, d)
                total = min(sum(shared.values()), SATURATED)
                if total > cap:
                    raise ExpansionError(
                        f"its representations expand to {'more than ' if total >= SATURATED else ''}{total} "
                        f"geometry items (IfcMappedItem nested {deepest} levels deep), over the cap of {cap} "
                        f"items (at most {MAX_ITEMS_DEFAULT}, and {ITEM_BYTES} bytes each within the scene memory "
                        "limit, HRTAO_MAX_SCENE_MB): refused before tessellating"
                    )
    return min(sum(shared.values()), SATURATED), products, deepest


# The loader passes the cap (HRTAO_IFC_MAX_ITEMS: crates/scene/src/ifc_load.rs); these defaults name it.
MAX_ITEMS_DEFAULT = 10_000_000
ITEM_BYTES = 4096


def open_whole_statements(ifcopenshell, path):
    """Opens the file; one cut short (the loader sets HRTAO_IFC_COMPLETE_BYTES: the length of its whole
    statements) is read up to its last whole statement and closed, from a temporary copy: IfcOpenShell's parser
    crashes on a string left open at the end of the file."""
    complete = os.environ.get("HRTAO_IFC_COMPLETE_BYTES")
    if not complete:
        return ifcopenshell.open(path)
    import tempfile

    with open(path, "rb") as src:
        data = src.read(int(complete))
    tail = b"END-ISO-10303-21;\n" if data.rstrip().endswith(b"ENDSEC;") else b"\nENDSEC;\nEND-ISO-10303-21;\n"
    with tempfile.NamedTemporaryFile(prefix="hrtao-cut-", suffix=".ifc") as copy:
        copy.write(data)
        copy.write(tail)
        copy.flush()
        del data
        return ifcopenshell.open(copy.name)


def main():
    if len(sys.argv) != 2:
        error("usage: ifc_worker.py FILE")
        return 2
    path = sys.argv[1]
    hook = os.environ.get("HRTAO_IFC_WORKER_TEST_HOOK", "")
    # Out of memory, the system kills this process before the viewer (as the OpenCASCADE worker does).
    try:
        with open("/proc/self/oom_score_adj", "w") as adj:
            adj.write("500")
    except OSError:
        pass
    progress("read", 0.0)
    try:
        import numpy as np
        import ifcopenshell
        import ifcopenshell.geom
    except Exception as e:  # noqa: BLE001 - any import failure means the venv is not usable
        error(f"IfcOpenShell is not installed for {sys.executable} ({e}): run scripts/install-deps.sh")
        return 1
    if hook == "spin":
        while True:
            pass
    if hook == "sleep":
        import time

        time.sleep(3600)
    try:
        f = open_whole_statements(ifcopenshell, path)
    except Exception as e:  # noqa: BLE001
        error(f"IfcOpenShell cannot read the file: {e}")
        return 1
    try:
        cap = int(os.environ.get("HRTAO_IFC_MAX_ITEMS", MAX_ITEMS_DEFAULT))
    except ValueError:
        cap = MAX_ITEMS_DEFAULT
    try:
        mapped_expansion(f, cap)
    except ExpansionError as e:
        error(str(e))
        return 1
    progress("transfer", 0.0)
    settings = ifcopenshell.geom.settings()
    settings.set("use-world-coords", False)
    settings.set("weld-vertices", False)
    settings.set("apply-default-materials", True)
    threads = max(1, min(8, os.cpu_count() or 1))
    # Openings are voids (cut from their elements) and spaces are room volumes: neither is drawn (IfcConvert's
    # defaults).
    it = ifcopenshell.geom.iterator(settings, f, threads, exclude=("IfcOpeningElement", "IfcSpace"))
    parts = {}  # representation id -> (index, payload)
    placed = []  # (product id, part index, 16 doubles)
    if it.initialize():
        while True:
            shape = it.get()
            g = shape.geometry
            key = g.id
            if key not in parts:
                parts[key] = (len(parts), text(shape.name or shape.type) + part_payload(np, g))
            placed.append((shape.id, parts[key][0], bytes(shape.transformation_buffer)))
            progress("tessellate", it.progress() / 100.0)
            if not it.next():
                break
    # Metres per unit of the positions the iterator gave (the unit it found, metres where it found none).
    try:
        iterator_unit = float(it.unit_magnitude())
    except Exception:  # noqa: BLE001
        iterator_unit = 1.0
    if not (iterator_unit == iterator_unit and 0.0 < iterator_unit < float("inf")):
        iterator_unit = 1.0
    file_unit = project_length_unit(f)
    if file_unit is None and iterator_unit != 1.0:
        file_unit = iterator_unit  # found by the iterator where this search did not
    # Positions are file coordinates times iterator_unit; in metres they are file coordinates times file_unit.
    model_unit = file_unit / iterator_unit if file_unit else 1.0
    if not placed:
        schema = f.schema
        products = len(f.by_type("IfcProduct"))
        error(f"no geometry: IfcOpenShell found no product with a shape ({products} products, schema {schema})")
        return 1
    by_product = {}
    for pid, part, world in placed:
        by_product.setdefault(pid, []).append((part, world))

    # The spatial tree, pre-order: spatial containers always, elements when they or their parts have geometry.
    nodes = []  # (label, parent, part or None, world bytes)
    identity = struct.pack("<16d", 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1)
    visited = set()

    memo = {}

    def has_geometry(e, depth=0):
        if e.id() not in memo:
            memo[e.id()] = False  # a cycle or a chain past 64 levels adds nothing
            if depth <= 64:
                memo[e.id()] = e.id() in by_product or any(has_geometry(c, depth + 1) for c in children(e))
        return memo[e.id()]

    def walk(e, parent, depth):
        if e.id() in visited or depth > 64:
            return
        if e.is_a() not in SPATIAL and not has_geometry(e):
            return
        visited.add(e.id())
        shapes = by_product.get(e.id(), [])
        me = len(nodes)
        if len(shapes) == 1 and not e.is_a("IfcBuildingStorey"):
            nodes.append((label(e), parent, shapes[0][0], shapes[0][1]))
        else:
            # A storey's node is placed at its height (its elevation: the loader lists the storeys with it).
            world = storey_world(e, iterator_unit) if e.is_a("IfcBuildingStorey") else identity
            nodes.append((label(e), parent, None, world))
            for k, (part, world) in enumerate(shapes):
                nodes.append((f"{label(e)} #{k + 1}", me, part, world))
        for c in children(e):
            walk(c, me, depth + 1)

    for project in f.by_type("IfcProject"):
        walk(project, None, 0)
    for pid, shapes in by_product.items():
        if pid not in visited:
            walk(f.by_id(pid), None, 0)

    progress("model", 1.0)
    out = [struct.pack("<Idd", MODEL_FRAME_VERSION, model_unit, file_unit or 0.0), struct.pack("<Q", len(parts))]
    for _, payload in sorted(parts.values(), key=lambda v: v[0]):
        out.append(payload)
    out.append(struct.pack("<Q", len(nodes)))
    for name, parent, part, world in nodes:
        out.append(text(name))
        out.append(struct.pack("<Q", 0xFFFFFFFFFFFFFFFF if parent is None else parent))
        out.append(struct.pack("<Q", 0xFFFFFFFFFFFFFFFF if part is None else part))
        out.append(world)
        out.append(colour(None) + b"\x01")
    frame(b"M", b"".join(out))
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except MemoryError:
        error("IfcOpenShell ran out of memory (the scene memory limit, HRTAO_MAX_SCENE_MB)")
        sys.exit(1)
    except Exception as e:  # noqa: BLE001 - every failure is an error frame, not a traceback
        error(f"IfcOpenShell failed: {type(e).__name__}: {e}")
        sys.exit(1)
