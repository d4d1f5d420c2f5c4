"""Assembly files with a known tree, names, units and colours, written by the tests with the
format's own library: STEP with OpenCASCADE (OCP, in the test extra), IFC with
ifcopenshell.api. What each writes is returned alongside, for the tests to compare."""

from __future__ import annotations

from pathlib import Path

import numpy as np

# STEP: engine > (block), crank > (shaft), head > (valve, valve); millimetres; sRGB colours
STEP_PARTS = {   # name: (group path, box min, box max in mm, colour or None)
    "block": (("engine",), (0, 0, 0), (100, 20, 10), (0.8, 0.2, 0.1)),
    "shaft": (("engine", "crank"), (5, -5, 20), (15, 5, 60), (0.2, 0.5, 0.9)),
    "valve": (("engine", "head"), (18, 3, 30), (22, 7, 45), None),
    "valve_2": (("engine", "head"), (58, 3, 30), (62, 7, 45), None),
}


def write_step(path: Path, unit: float = 1e-3) -> dict:
    """The STEP_PARTS assembly; its numbers are lengths in `unit` (metres per unit: 1e-3 for
    millimetres, 0.0254 for inches), the unit the file declares."""
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox, BRepPrimAPI_MakeCylinder
    from OCP.gp import gp_Trsf, gp_Vec
    from OCP.Interface import Interface_Static
    from OCP.Quantity import Quantity_Color, Quantity_TOC_sRGB
    from OCP.STEPCAFControl import STEPCAFControl_Controller, STEPCAFControl_Writer
    from OCP.STEPControl import STEPControl_AsIs
    from OCP.TCollection import TCollection_ExtendedString
    from OCP.TDataStd import TDataStd_Name
    from OCP.TDocStd import TDocStd_Document
    from OCP.TopLoc import TopLoc_Location
    from OCP.XCAFDoc import XCAFDoc_ColorGen, XCAFDoc_DocumentTool

    doc = TDocStd_Document(TCollection_ExtendedString("XmlOcaf"))
    XCAFDoc_DocumentTool.SetLengthUnit_s(doc, unit)
    shapes = XCAFDoc_DocumentTool.ShapeTool_s(doc.Main())
    colors = XCAFDoc_DocumentTool.ColorTool_s(doc.Main())

    def named(label, text):
        TDataStd_Name.Set_s(label, TCollection_ExtendedString(text))
        return label

    def at(x, y, z):
        t = gp_Trsf()
        t.SetTranslation(gp_Vec(float(x), float(y), float(z)))
        return TopLoc_Location(t)

    def color(label, rgb):
        colors.SetColor(label, Quantity_Color(*rgb, Quantity_TOC_sRGB), XCAFDoc_ColorGen)

    root, crank, head = (named(shapes.NewShape(), n) for n in ("engine", "crank", "head"))
    block = named(shapes.AddShape(BRepPrimAPI_MakeBox(100.0, 20.0, 10.0).Shape(), False), "block")
    shaft = named(shapes.AddShape(BRepPrimAPI_MakeCylinder(5.0, 40.0).Shape(), False), "shaft")
    valve = named(shapes.AddShape(BRepPrimAPI_MakeCylinder(2.0, 15.0).Shape(), False), "valve")
    color(block, STEP_PARTS["block"][3])
    color(shaft, STEP_PARTS["shaft"][3])
    shapes.AddComponent(root, block, at(0, 0, 0))
    shapes.AddComponent(crank, shaft, at(10, 0, 20))
    shapes.AddComponent(head, valve, at(20, 5, 30))
    shapes.AddComponent(head, valve, at(60, 5, 30))
    shapes.AddComponent(root, crank, at(0, 0, 0))
    shapes.AddComponent(root, head, at(0, 0, 0))
    shapes.UpdateAssemblies()
    STEPCAFControl_Controller.Init_s()
    Interface_Static.SetCVal_s("write.step.unit", "INCH" if abs(unit - 0.0254) < 1e-9 else "MM")
    writer = STEPCAFControl_Writer()
    writer.SetNameMode(True)
    writer.SetColorMode(True)
    writer.Transfer(doc, STEPControl_AsIs)
    writer.Write(str(path))
    return STEP_PARTS


IFC_TREE = ("Demo project", "Site", "House")


def write_ifc(path: Path, storeys: int = 2) -> dict:
    """A house in millimetres: per storey a wall with an opening filled by a window, a slab
    and a space; a door on the first storey. Returns {object name: (path, min, max) in mm}."""
    import ifcopenshell.api.aggregate
    import ifcopenshell.api.context
    import ifcopenshell.api.feature
    import ifcopenshell.api.geometry
    import ifcopenshell.api.project
    import ifcopenshell.api.root
    import ifcopenshell.api.spatial
    import ifcopenshell.api.unit

    api = ifcopenshell.api
    f = api.project.create_file(version="IFC4")
    project = api.root.create_entity(f, ifc_class="IfcProject", name=IFC_TREE[0])
    api.unit.assign_unit(f)                                   # millimetres
    body = api.context.add_context(f, context_type="Model", context_identifier="Body", target_view="MODEL_VIEW",
                                   parent=api.context.add_context(f, context_type="Model"))
    site = api.root.create_entity(f, ifc_class="IfcSite", name=IFC_TREE[1])
    building = api.root.create_entity(f, ifc_class="IfcBuilding", name=IFC_TREE[2])
    api.aggregate.assign_object(f, relating_object=project, products=[site])
    api.aggregate.assign_object(f, relating_object=site, products=[building])
    expected = {}

    def element(kind, name, xyz, container, size=None, slab=None):
        e = api.root.create_entity(f, ifc_class=kind, name=name)
        m = np.eye(4)
        m[:3, 3] = xyz
        api.geometry.edit_object_placement(f, product=e, matrix=m)
        if slab is not None:
            rep = api.geometry.add_slab_representation(f, context=body, depth=0.2, polyline=slab)
        else:
            rep = api.geometry.add_wall_representation(f, context=body, length=size[0], thickness=size[1],
                                                       height=size[2])
        api.geometry.assign_representation(f, product=e, representation=rep)
        if kind == "IfcSpace":
            api.aggregate.assign_object(f, relating_object=container, products=[e])
        elif kind != "IfcOpeningElement":
            api.spatial.assign_container(f, relating_structure=container, products=[e])
        return e

    for k in range(storeys):
        z = 3.0 * k
        storey = api.root.create_entity(f, ifc_class="IfcBuildingStorey", name=f"Storey {k + 1}")
        api.aggregate.assign_object(f, relating_object=building, products=[storey])
        where = (*IFC_TREE, f"Storey {k + 1}")
        wall = element("IfcWall", f"Wall {k + 1}", (0, 0, z), storey, (5, 0.2, 3))
        opening = element("IfcOpeningElement", "hole", (1, -0.1, z + 1), storey, (1, 0.4, 1))
        api.feature.add_feature(f, feature=opening, element=wall)
        window = element("IfcWindow", f"Window {k + 1}", (1, 0.05, z + 1), storey, (1, 0.1, 1))
        api.feature.add_filling(f, opening=opening, element=window)
        element("IfcSlab", f"Floor {k + 1}", (0, 0, z), storey, slab=[(0, 0), (5, 0), (5, 4), (0, 4)])
        element("IfcSpace", f"Room {k + 1}", (0.2, 0.2, z), storey, (4, 3, 2.5))
        expected[f"IfcWall 'Wall {k + 1}'"] = (where, (0, 0, z * 1e3), (5000, 200, z * 1e3 + 3000))
        expected[f"IfcWindow 'Window {k + 1}'"] = (where, (1000, 50, z * 1e3 + 1000), (2000, 150, z * 1e3 + 2000))
        expected[f"IfcSlab 'Floor {k + 1}'"] = (where, (0, 0, z * 1e3), (5000, 4000, z * 1e3 + 200))
        if k == 0:
            element("IfcDoor", "Front door", (3, 0, 0), storey, (0.9, 0.05, 2.1))
            expected["IfcDoor 'Front door'"] = (where, (3000, 0, 0), (3900, 50, 2100))
    f.write(str(path))
    return expected
