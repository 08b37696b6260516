# Writes a small IFC4 model with IfcOpenShell's own API (sys.argv[1]): an IfcProject, an IfcProjectLibrary declared
# to it (IfcRelDeclares), and one wall 4 m long, 0.2 m thick and 3 m high placed at (1 m, 2 m, 0). The mode
# (sys.argv[2]):
#   library-after  the project's IfcUnitAssignment declares millimetres; the library is created after the project
#   library-first  the same, the library created (and so numbered) before the project
#   no-unit        no IfcUnitAssignment at all (and no library): coordinates in no declared unit
# IfcOpenShell 0.8.4's geometry iterator finds no unit when the library is beside the project, so with the
# library it reads the millimetre coordinates as metres. Prints the wall's true length in metres.
import sys

import ifcopenshell
import ifcopenshell.api.context
import ifcopenshell.api.geometry
import ifcopenshell.api.project
import ifcopenshell.api.root
import ifcopenshell.api.unit
import numpy as np

out, mode = sys.argv[1], sys.argv[2]
assert mode in ("library-after", "library-first", "no-unit"), mode
f = ifcopenshell.file(schema="IFC4")
library = None
if mode == "library-first":
    library = ifcopenshell.api.root.create_entity(f, ifc_class="IfcProjectLibrary", name="Library")
project = ifcopenshell.api.root.create_entity(f, ifc_class="IfcProject", name="Units")
if mode == "library-after":
    library = ifcopenshell.api.root.create_entity(f, ifc_class="IfcProjectLibrary", name="Library")
if library is not None:
    mm = ifcopenshell.api.unit.add_si_unit(f, unit_type="LENGTHUNIT", prefix="MILLI")
    ifcopenshell.api.unit.assign_unit(f, units=[mm])
    ifcopenshell.api.project.assign_declaration(f, definitions=[library], relating_context=project)
model = ifcopenshell.api.context.add_context(f, context_type="Model")
body = ifcopenshell.api.context.add_context(
    f, context_type="Model", context_identifier="Body", target_view="MODEL_VIEW", parent=model
)
wall = ifcopenshell.api.root.create_entity(f, ifc_class="IfcWall", name="Wall")
m = np.eye(4)
m[:3, 3] = (1.0, 2.0, 0.0)
# Lengths in metres, written in the project's unit (millimetres, or as given without a unit).
ifcopenshell.api.geometry.edit_object_placement(f, product=wall, matrix=m, is_si=True)
rep = ifcopenshell.api.geometry.add_wall_representation(f, context=body, length=4.0, height=3.0, thickness=0.2)
ifcopenshell.api.geometry.assign_representation(f, product=wall, representation=rep)
# The profile's points are in the file's unit: 4000 (millimetres), or 4 without a unit.
length = max(x for x, _ in f.by_type("IfcCartesianPointList2D")[0].CoordList)
if library is not None:
    assert project.UnitsInContext is not None and length == 4000.0, length
    assert len(f.by_type("IfcContext")) == 2
else:
    assert not f.by_type("IfcUnitAssignment") and length == 4.0, length
f.write(out)
print(4.0)
