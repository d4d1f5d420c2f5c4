"""Ghosting a building by IFC class: doors and windows in focus, walls and floor faded.

A small IFC4 house written with ifcopenshell.api (the `bim` extra): a slab, four walls, a door
and two windows in openings cut in the walls. rtta names each product `IfcWall 'name'` (under
its spatial tree), so "IfcWindow" selects every window, as `rtta snapshot --focus` does.

    python examples/ifc_by_class.py [OUT_DIR]    # writes OUT_DIR/ifc_by_class.png and house.ifc
"""

import sys
from pathlib import Path

import ifcopenshell.api
import numpy as np
from PIL import Image

import rtta

WALLS = [(0, 0, 6, 0.2), (5.8, 0, 6, 4), (0, 3.8, 6, 4), (0, 0, 0.2, 4)]
PARTS = [  # class, name, footprint (x0, y0, x1, y1), bottom, top (metres), the wall it fills (index)
    ("IfcSlab", "Floor", (0, 0, 6, 4), -0.2, 0, None),
    *[("IfcWall", f"Wall {k + 1}", b, 0, 2.8, None) for k, b in enumerate(WALLS)],
    ("IfcDoor", "Front door", (2.5, 0, 3.5, 0.2), 0, 2.1, 1),
    ("IfcWindow", "East", (5.8, 1.2, 6, 2.8), 0.9, 2.1, 2),
    ("IfcWindow", "Back", (2, 3.8, 3.6, 4), 0.9, 2.1, 3),
]
TREE = ("Project", "Site", "Building", "BuildingStorey")
BODY = {"context_type": "Model", "context_identifier": "Body", "target_view": "MODEL_VIEW"}


def write_house(path: Path) -> None:
    run = ifcopenshell.api.run
    f = run("project.create_file", version="IFC4")
    tree = [run("root.create_entity", f, ifc_class=f"Ifc{c}", name=c) for c in TREE]  # the spatial tree
    run("unit.assign_unit", f)  # millimetres in the file; the API takes metres
    body = run("context.add_context", f, parent=run("context.add_context", f, context_type="Model"), **BODY)
    for parent, child in zip(tree, tree[1:], strict=False):  # project > site > building > storey
        run("aggregate.assign_object", f, relating_object=parent, products=[child])

    def add(kind, name, box, z0, z1):  # a box: its footprint extruded from z0 up to z1
        item = run("root.create_entity", f, ifc_class=kind, name=name)
        up = np.r_[np.eye(4)[:2], [[0, 0, 1, z0], [0, 0, 0, 1]]]  # placed z0 up
        run("geometry.edit_object_placement", f, product=item, matrix=up)
        outline = [(box[0], box[1]), (box[2], box[1]), (box[2], box[3]), (box[0], box[3])]
        rep = run("geometry.add_slab_representation", f, context=body, depth=z1 - z0, polyline=outline)
        run("geometry.assign_representation", f, product=item, representation=rep)
        return item

    items = []
    for kind, name, box, z0, z1, wall in PARTS:
        items.append(add(kind, name, box, z0, z1))
        if wall is not None:  # an opening through the wall's thickness (y for walls along x), filled
            grow = [0, -0.1, 0, 0.1] if box[2] - box[0] > box[3] - box[1] else [-0.1, 0, 0.1, 0]
            hole = add("IfcOpeningElement", "opening", np.add(box, grow), z0, z1)
            run("feature.add_feature", f, feature=hole, element=items[wall])
            run("feature.add_filling", f, opening=hole, element=items[-1])
    run("spatial.assign_container", f, relating_structure=tree[-1], products=items)  # not the openings
    f.write(str(path))


def main(out: Path) -> Path:
    out.mkdir(parents=True, exist_ok=True)
    write_house(out / "house.ifc")
    scene = rtta.load_scene(out / "house.ifc")
    print("\n".join("/".join((*scene.path_of(i), name)) for i, name in enumerate(scene.names)))
    rgba = rtta.snapshot(scene, "ghosted-ao", focus=["IfcDoor", "IfcWindow"], camera=(150, 30, 2.2), size=(480, 360))
    Image.fromarray(rgba).save(out / "ifc_by_class.png")
    return out / "ifc_by_class.png"


if __name__ == "__main__":
    print("wrote", main(Path(sys.argv[1] if sys.argv[1:] else "out/examples")))
