# Writes a small two-storey IFC4 building for a walk-through test with IfcOpenShell's own API (sys.argv[1]).
# Z up, project length unit millimetres; every number below is in metres (world coordinates).
#   IfcProject "Walk test" -> IfcSite -> IfcBuilding -> IfcBuildingStorey "Ground floor" (Elevation 0.0)
#                                                     and IfcBuildingStorey "First floor" (Elevation 3.0, placed at z=3)
#   Ground floor:
#     IfcSlab "Ground slab"        x[0,14]      y[0,8]      z[-0.2,0]
#     IfcWall "South wall"         x[0,14]      y[0,0.2]    z[0,2.8]
#     IfcWall "North wall"         x[0,14]      y[7.8,8]    z[0,2.8]
#     IfcWall "West wall"          x[0,0.2]     y[0,8]      z[0,2.8]
#     IfcWall "East wall"          x[13.8,14]   y[0,8]      z[0,2.8]
#     IfcWall "Interior wall"      x[4.0,4.2]   y[0,8]      z[0,2.8], voided by an IfcOpeningElement "Door hole"
#                                  cutting y[3,4] z[0,2.1] through the whole thickness (its solid overshoots the
#                                  wall by 0.1 in x on both sides and below z=0 so the boolean has no coplanar faces),
#                                  filled by IfcDoor "Door" (no representation)
#     IfcStair "Stair" aggregating 17 IfcStairFlight "Step 1".."Step 17": step k is the solid block
#                                  x[6.5+0.28(k-1), 6.5+0.28k]  y[6.8,7.8]  z[0, 3k/17]
#   First floor:
#     IfcSlab "First floor slab"   x[0,14]      y[0,8]      z[2.8,3.0], outline with a stairwell notch
#                                  x[6.2,11.26] y[6.6,8]
# Nothing else has geometry (no IfcSpace). On success prints one JSON line: {"storeys": [[name, elevation_m], ...]}.
import json
import os
import sys

import ifcopenshell
import ifcopenshell.api
import ifcopenshell.api.aggregate
import ifcopenshell.api.context
import ifcopenshell.api.feature
import ifcopenshell.api.geometry
import ifcopenshell.api.project
import ifcopenshell.api.root
import ifcopenshell.api.spatial
import ifcopenshell.api.unit
import ifcopenshell.util.unit
import numpy as np

STOREY_HEIGHT = 3.0
STEPS = 17


def build(out):
    f = ifcopenshell.api.project.create_file(version="IFC4")
    project = ifcopenshell.api.root.create_entity(f, ifc_class="IfcProject", name="Walk test")
    ifcopenshell.api.unit.assign_unit(f)  # millimetres
    scale = ifcopenshell.util.unit.calculate_unit_scale(f)  # metres per file unit
    if abs(scale - 0.001) > 1e-12:
        raise RuntimeError(f"expected a millimetre project, got unit scale {scale}")
    model = ifcopenshell.api.context.add_context(f, context_type="Model")
    body = ifcopenshell.api.context.add_context(
        f, context_type="Model", context_identifier="Body", target_view="MODEL_VIEW", parent=model
    )

    def place(product, x, y, z=0.0):
        # World-space placement in metres; relationships must exist first so the placement is made relative
        # to the right parent.
        m = np.eye(4)
        m[:3, 3] = (x, y, z)
        ifcopenshell.api.geometry.edit_object_placement(f, product=product, matrix=m, is_si=True)

    def prism(product, x0, y0, z0, outline, height):
        # Places the product at (x0, y0, z0) and gives it an extrusion of `outline` (metres, relative to that
        # corner) straight up by `height`.
        place(product, x0, y0, z0)
        pts = [(float(px), float(py)) for px, py in outline]
        pts.append(pts[0])  # IfcArbitraryClosedProfileDef wants a closed curve
        rep = ifcopenshell.api.geometry.add_slab_representation(f, context=body, depth=height, polyline=pts)
        ifcopenshell.api.geometry.assign_representation(f, product=product, representation=rep)

    def box(product, x0, x1, y0, y1, z0, z1):
        dx, dy = x1 - x0, y1 - y0
        prism(product, x0, y0, z0, [(0.0, 0.0), (dx, 0.0), (dx, dy), (0.0, dy)], z1 - z0)

    site = ifcopenshell.api.root.create_entity(f, ifc_class="IfcSite", name="Site")
    building = ifcopenshell.api.root.create_entity(f, ifc_class="IfcBuilding", name="Building")
    ground = ifcopenshell.api.root.create_entity(f, ifc_class="IfcBuildingStorey", name="Ground floor")
    first = ifcopenshell.api.root.create_entity(f, ifc_class="IfcBuildingStorey", name="First floor")
    ifcopenshell.api.aggregate.assign_object(f, relating_object=project, products=[site])
    ifcopenshell.api.aggregate.assign_object(f, relating_object=site, products=[building])
    ifcopenshell.api.aggregate.assign_object(f, relating_object=building, products=[ground, first])
    place(site, 0.0, 0.0)
    place(building, 0.0, 0.0)
    for storey, elevation in ((ground, 0.0), (first, STOREY_HEIGHT)):
        storey.Elevation = elevation / scale
        place(storey, 0.0, 0.0, elevation)

    def element(ifc_class, name, storey):
        e = ifcopenshell.api.root.create_entity(f, ifc_class=ifc_class, name=name)
        ifcopenshell.api.spatial.assign_container(f, relating_structure=storey, products=[e])
        return e

    box(element("IfcSlab", "Ground slab", ground), 0.0, 14.0, 0.0, 8.0, -0.2, 0.0)

    first_slab = element("IfcSlab", "First floor slab", first)
    notch = [(0.0, 0.0), (14.0, 0.0), (14.0, 8.0), (11.26, 8.0), (11.26, 6.6), (6.2, 6.6), (6.2, 8.0), (0.0, 8.0)]
    prism(first_slab, 0.0, 0.0, 2.8, notch, 0.2)

    box(element("IfcWall", "South wall", ground), 0.0, 14.0, 0.0, 0.2, 0.0, 2.8)
    box(element("IfcWall", "North wall", ground), 0.0, 14.0, 7.8, 8.0, 0.0, 2.8)
    box(element("IfcWall", "West wall", ground), 0.0, 0.2, 0.0, 8.0, 0.0, 2.8)
    box(element("IfcWall", "East wall", ground), 13.8, 14.0, 0.0, 8.0, 0.0, 2.8)

    interior = element("IfcWall", "Interior wall", ground)
    box(interior, 4.0, 4.2, 0.0, 8.0, 0.0, 2.8)
    opening = ifcopenshell.api.root.create_entity(f, ifc_class="IfcOpeningElement", name="Door hole")
    ifcopenshell.api.feature.add_feature(f, feature=opening, element=interior)
    # The hole in the wall is y[3,4] z[0,2.1]; the opening solid overshoots the wall in x and below the floor.
    box(opening, 3.9, 4.3, 3.0, 4.0, -0.1, 2.1)
    door = element("IfcDoor", "Door", ground)
    door.OverallWidth = 1.0 / scale
    door.OverallHeight = 2.1 / scale
    ifcopenshell.api.feature.add_filling(f, opening=opening, element=door)
    place(door, 4.0, 3.0, 0.0)

    stair = element("IfcStair", "Stair", ground)
    place(stair, 0.0, 0.0, 0.0)
    flights = [
        ifcopenshell.api.root.create_entity(f, ifc_class="IfcStairFlight", name=f"Step {k}")
        for k in range(1, STEPS + 1)
    ]
    ifcopenshell.api.aggregate.assign_object(f, relating_object=stair, products=flights)
    for k, flight in enumerate(flights, start=1):
        box(flight, 6.5 + 0.28 * (k - 1), 6.5 + 0.28 * k, 6.8, 7.8, 0.0, k * STOREY_HEIGHT / STEPS)

    if os.path.exists(out):
        os.remove(out)
    f.write(out)  # IfcOpenShell does not always raise when it cannot write
    if not os.path.isfile(out) or os.path.getsize(out) == 0:
        raise RuntimeError(f"could not write {out}")
    return [[s.Name, s.Elevation * scale] for s in (ground, first)]


def main():
    if len(sys.argv) != 2:
        sys.exit(f"usage: {sys.argv[0]} OUT.ifc")
    try:
        storeys = build(sys.argv[1])
    except Exception as e:  # report and fail
        sys.exit(f"make_two_storey.py: failed: {type(e).__name__}: {e}")
    print(json.dumps({"storeys": storeys}))


if __name__ == "__main__":
    main()
