"""Assembly files with a known tree, names, units and colours, written by the tests with the
format's own library: STEP with OpenCASCADE (OCP, in the test extra), IFC with
ifcopenshell.api. What each writes is returned alongside, for the tests to compare."""

from __future__ import annotations

from pathlib import Path

import numpy as np

# STEP: engine > (block), crank > (shaft), head > (valve, valve); millimetres; sRGB colours
STEP_PARTS = {  # name: (group path, box min, box max in mm, colour or None)
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
    api.unit.assign_unit(f)  # millimetres
    body = api.context.add_context(
        f,
        context_type="Model",
        context_identifier="Body",
        target_view="MODEL_VIEW",
        parent=api.context.add_context(f, context_type="Model"),
    )
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
            rep = api.geometry.add_wall_representation(
                f, context=body, length=size[0], thickness=size[1], height=size[2]
            )
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


def _box_mesh(size):
    sx, sy, sz = size
    v = np.array([[x, y, z] for z in (0, sz) for y in (0, sy) for x in (0, sx)], float)
    f = np.array(
        [
            [0, 2, 1],
            [1, 2, 3],
            [4, 5, 6],
            [5, 7, 6],
            [0, 1, 4],
            [1, 5, 4],
            [2, 6, 3],
            [3, 6, 7],
            [0, 4, 2],
            [2, 4, 6],
            [1, 3, 5],
            [3, 7, 5],
        ]
    )
    return v, f


# COLLADA / USD / 3DXML: plant > (base), arm > (link), arm > hand > (finger, finger); centimetres, Z up
TREE_PARTS = {  # object name: (group path, translation, box size)
    "base": (("plant",), (0, 0, 0), (40, 40, 10)),
    "link": (("plant", "arm"), (15, 15, 10), (10, 10, 50)),
    "finger": (("plant", "arm", "hand"), (12, 15, 60), (2, 2, 10)),
    "finger_2": (("plant", "arm", "hand"), (26, 15, 60), (2, 2, 10)),
}


def write_collada(path: Path) -> dict:
    """TREE_PARTS as nested COLLADA nodes (the fingers instance one geometry), in cm, Z up."""
    from collada import Collada, asset, geometry, material, scene, source

    dae = Collada()
    dae.assetInfo.unitmeter, dae.assetInfo.unitname, dae.assetInfo.upaxis = 0.01, "centimeter", asset.UP_AXIS.Z_UP
    effect = material.Effect("effect0", [], "phong", diffuse=(0.8, 0.3, 0.1, 1.0))
    mat = material.Material("material0", "orange", effect)
    dae.effects.append(effect)
    dae.materials.append(mat)
    geoms = {}
    for name, (_, _, size) in TREE_PARTS.items():
        if size in geoms:
            continue
        v, f = _box_mesh(size)
        src = source.FloatSource(f"v{len(geoms)}", v.reshape(-1), ("X", "Y", "Z"))
        g = geometry.Geometry(dae, f"g{len(geoms)}", name, [src])
        inputs = source.InputList()
        inputs.addInput(0, "VERTEX", f"#v{len(geoms)}")
        g.primitives.append(g.createTriangleSet(f.reshape(-1), inputs, "mat"))
        dae.geometries.append(g)
        geoms[size] = g

    def leaf(name):
        _, t, size = TREE_PARTS[name]
        gnode = scene.GeometryNode(geoms[size], [scene.MaterialNode("mat", mat, inputs=[])])
        return scene.Node(name, children=[gnode], transforms=[scene.TranslateTransform(*t)], name=name)

    hand = scene.Node("hand", children=[leaf("finger"), leaf("finger_2")], name="hand")
    arm = scene.Node("arm", children=[leaf("link"), hand], name="arm")
    root = scene.Node("plant", children=[leaf("base"), arm], name="plant")
    dae.scenes.append(scene.Scene("scene", [root]))
    dae.scene = dae.scenes[0]
    dae.write(str(path))
    return TREE_PARTS


def write_usd(path: Path) -> dict:
    """TREE_PARTS as prims in cm, Z up; the fingers are two instances of one prototype."""
    from pxr import Gf, Usd, UsdGeom

    stage = Usd.Stage.CreateNew(str(path))
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
    UsdGeom.SetStageMetersPerUnit(stage, 0.01)

    def mesh(at, size):
        v, f = _box_mesh(size)
        m = UsdGeom.Mesh.Define(stage, at)
        m.GetPointsAttr().Set([Gf.Vec3f(*p) for p in v])
        m.GetFaceVertexCountsAttr().Set([3] * len(f))
        m.GetFaceVertexIndicesAttr().Set([int(i) for i in f.reshape(-1)])
        m.GetDisplayColorAttr().Set([Gf.Vec3f(0.2, 0.6, 0.3)])
        return m

    root = UsdGeom.Xform.Define(stage, "/plant")
    stage.SetDefaultPrim(root.GetPrim())
    UsdGeom.Xform.Define(stage, "/plant/arm")
    UsdGeom.Xform.Define(stage, "/plant/arm/hand")
    stage.CreateClassPrim("/_finger")
    mesh("/_finger/geom", TREE_PARTS["finger"][2])
    for name in TREE_PARTS:
        group, t, size = TREE_PARTS[name]
        where = "/" + "/".join((*group, name))
        if name.startswith("finger"):
            x = UsdGeom.Xform.Define(stage, where)
            x.GetPrim().GetReferences().AddInternalReference("/_finger")
            x.GetPrim().SetInstanceable(True)
        else:
            x = mesh(where, size)
        x.AddTranslateOp().Set(Gf.Vec3d(*t))
    stage.GetRootLayer().Save()
    return TREE_PARTS


def write_3dxml(path: Path) -> dict:
    """TREE_PARTS as a 3DXML product structure (products plant > arm > hand; the fingers are
    two instances of one part), in millimetres as 3DXML stores them."""
    import zipfile

    refs = {"plant": 1, "arm": 2, "hand": 3, "base": 4, "link": 5, "finger": 6}
    parent = {"arm": "plant", "hand": "arm", "base": "plant", "link": "arm", "finger": "hand"}
    items, next_id = [], 100
    for name, rid in refs.items():
        items.append(f'<Reference3D id="{rid}" name="{name}"/>')
    for name, (_, t, _) in TREE_PARTS.items():
        part = name.split("_")[0]
        items.append(
            f'<Instance3D id="{next_id}" name="{name}.1"><IsAggregatedBy>{refs[parent[part]]}'
            f"</IsAggregatedBy><IsInstanceOf>{refs[part]}</IsInstanceOf><RelativeMatrix>"
            f"1 0 0 0 1 0 0 0 1 {t[0]} {t[1]} {t[2]}</RelativeMatrix></Instance3D>"
        )
        next_id += 1
    for group in ("arm", "hand"):
        items.append(
            f'<Instance3D id="{next_id}" name="{group}.1"><IsAggregatedBy>{refs[parent[group]]}'
            f"</IsAggregatedBy><IsInstanceOf>{refs[group]}</IsInstanceOf><RelativeMatrix>"
            "1 0 0 0 1 0 0 0 1 0 0 0</RelativeMatrix></Instance3D>"
        )
        next_id += 1
    reps = {}
    for part in ("base", "link", "finger"):
        v, f = _box_mesh(TREE_PARTS[part][2])
        n = np.tile([0.0, 0.0, 1.0], (len(v), 1))
        reps[f"{part}.3DRep"] = (
            '<?xml version="1.0"?><XMLRepresentation xmlns="http://www.3ds.com/xsd/3DXML"><Root>'
            f'<Rep><Faces><Face triangles="{" ".join(map(str, f.reshape(-1)))}"><SurfaceAttributes>'
            '<Color xsi:type="RGBAColorType" xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance" '
            'red="0.8" green="0.3" blue="0.1" alpha="1"/></SurfaceAttributes></Face></Faces><VertexBuffer>'
            f"<Positions>{', '.join(' '.join(map(str, p)) for p in v)}</Positions>"
            f"<Normals>{', '.join(' '.join(map(str, p)) for p in n)}</Normals></VertexBuffer></Rep>"
            "</Root></XMLRepresentation>"
        )
        items.append(
            f'<ReferenceRep id="{next_id}" name="{part}_rep" format="TESSELLATED" '
            f'associatedFile="urn:3DXML:{part}.3DRep"/>'
        )
        items.append(
            f'<InstanceRep id="{next_id + 1}"><IsAggregatedBy>{refs[part]}</IsAggregatedBy>'
            f"<IsInstanceOf>{next_id}</IsInstanceOf></InstanceRep>"
        )
        next_id += 2
    product = (
        '<?xml version="1.0"?><Model_3dxml xmlns="http://www.3ds.com/xsd/3DXML">'
        f'<ProductStructure root="1">{"".join(items)}</ProductStructure></Model_3dxml>'
    )
    with zipfile.ZipFile(path, "w") as z:
        z.writestr("Manifest.xml", '<?xml version="1.0"?><Manifest><Root>plant.3dxml</Root></Manifest>')
        z.writestr("plant.3dxml", product)
        for name, text in reps.items():
            z.writestr(name, text)
    return TREE_PARTS


def write_zae(path: Path) -> dict:
    """The COLLADA file in a .zae archive (with the manifest naming it)."""
    import zipfile

    dae = path.with_suffix(".dae")
    write_collada(dae)
    with zipfile.ZipFile(path, "w") as z:
        z.write(dae, "plant.dae")
        z.writestr("manifest.xml", '<?xml version="1.0"?><dae_root>./plant.dae</dae_root>')
    dae.unlink()
    return TREE_PARTS
