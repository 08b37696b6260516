# Writes a small IFC4 building with IfcOpenShell's own API (sys.argv[1]): a site, a building, one storey, two walls
# (one with an opening), a slab, and a column type whose representation map is placed by N columns
# (sys.argv[2]), each an IfcMappedItem: N instances of one mesh.
import sys

import ifcopenshell
import ifcopenshell.api
import ifcopenshell.api.aggregate
import ifcopenshell.api.context
import ifcopenshell.api.feature
import ifcopenshell.api.geometry
import ifcopenshell.api.root
import ifcopenshell.api.spatial
import ifcopenshell.api.type
import ifcopenshell.api.unit
import numpy as np

out, columns = sys.argv[1], int(sys.argv[2])
f = ifcopenshell.api.project.create_file(version="IFC4") if hasattr(ifcopenshell.api, "project") else ifcopenshell.file(schema="IFC4")
project = ifcopenshell.api.root.create_entity(f, ifc_class="IfcProject", name="Generated")
ifcopenshell.api.unit.assign_unit(f)
model = ifcopenshell.api.context.add_context(f, context_type="Model")
body = ifcopenshell.api.context.add_context(
    f, context_type="Model", context_identifier="Body", target_view="MODEL_VIEW", parent=model
)
site = ifcopenshell.api.root.create_entity(f, ifc_class="IfcSite", name="Site")
building = ifcopenshell.api.root.create_entity(f, ifc_class="IfcBuilding", name="Building")
storey = ifcopenshell.api.root.create_entity(f, ifc_class="IfcBuildingStorey", name="Ground floor")
ifcopenshell.api.aggregate.assign_object(f, relating_object=project, products=[site])
ifcopenshell.api.aggregate.assign_object(f, relating_object=site, products=[building])
ifcopenshell.api.aggregate.assign_object(f, relating_object=building, products=[storey])


def place(product, x, y, z=0.0):
    m = np.eye(4)
    m[:3, 3] = (x, y, z)
    ifcopenshell.api.geometry.edit_object_placement(f, product=product, matrix=m, is_si=True)


def contain(product):
    ifcopenshell.api.spatial.assign_container(f, relating_structure=storey, products=[product])


for i, (x, y) in enumerate([(0.0, 0.0), (0.0, 6.0)]):
    wall = ifcopenshell.api.root.create_entity(f, ifc_class="IfcWall", name=f"Wall {i + 1}")
    place(wall, x, y)
    rep = ifcopenshell.api.geometry.add_wall_representation(f, context=body, length=10.0, height=3.0, thickness=0.3)
    ifcopenshell.api.geometry.assign_representation(f, product=wall, representation=rep)
    contain(wall)
    if i == 0:
        opening = ifcopenshell.api.root.create_entity(f, ifc_class="IfcOpeningElement", name="Window hole")
        place(opening, 4.0, -0.1, 1.0)
        orep = ifcopenshell.api.geometry.add_wall_representation(
            f, context=body, length=1.5, height=1.2, thickness=0.5
        )
        ifcopenshell.api.geometry.assign_representation(f, product=opening, representation=orep)
        ifcopenshell.api.feature.add_feature(f, feature=opening, element=wall)

slab = ifcopenshell.api.root.create_entity(f, ifc_class="IfcSlab", name="Floor slab")
place(slab, 0.0, 0.0, -0.2)
srep = ifcopenshell.api.geometry.add_slab_representation(
    f, context=body, depth=0.2, polyline=[(0.0, 0.0), (10.0, 0.0), (10.0, 6.3), (0.0, 6.3)]
)
ifcopenshell.api.geometry.assign_representation(f, product=slab, representation=srep)
contain(slab)

ctype = ifcopenshell.api.root.create_entity(f, ifc_class="IfcColumnType", name="Round column")
crep = ifcopenshell.api.geometry.add_profile_representation(
    f,
    context=body,
    profile=f.create_entity("IfcCircleProfileDef", ProfileType="AREA", Radius=0.15),
    depth=3.0,
)
ifcopenshell.api.geometry.assign_representation(f, product=ctype, representation=crep)
for k in range(columns):
    col = ifcopenshell.api.root.create_entity(f, ifc_class="IfcColumn", name=f"Column {k + 1}")
    place(col, 1.0 + (k % 8) * 1.1, 1.5 + (k // 8) * 1.5)
    ifcopenshell.api.type.assign_type(f, related_objects=[col], relating_type=ctype)
    contain(col)
f.write(out)
mapped = sum(
    1
    for p in f.by_type("IfcProduct")
    if p.Representation
    for r in p.Representation.Representations
    for i in r.Items
    if i.is_a("IfcMappedItem")
)
print(mapped)
