"""A glTF file written on the fly with trimesh, opened with `rtta.load_scene`, parts picked by group.

trimesh builds a small robot arm as a scene graph (base > arm > wrist > fingers) and writes
it as a .glb; rtta reads the node tree into each object's path, so a GROUP name selects all
the parts below it: `opacity={"arm": 0.8}` sets every part of the arm, `focus=["wrist"]` puts
the wrist and its fingers in focus. Left: transparent with per-group opacities; right: ghosted.

    python examples/gltf_tree.py [OUT_DIR]       # writes OUT_DIR/gltf_tree.png and OUT_DIR/arm.glb
"""

import sys
from pathlib import Path

import numpy as np
import trimesh
from PIL import Image

import rtta

# node, parent, mesh, offset from the parent, RGBA
NODES = [
    ("base", None, trimesh.creation.cylinder(0.5, 0.3), (0, 0, 0.15), (90, 90, 100, 255)),
    ("arm", None, None, (0, 0, 0.3), None),  # a group: a node without a mesh
    ("upper", "arm", trimesh.creation.box((0.25, 0.25, 1.2)), (0, 0, 0.6), (220, 120, 40, 255)),
    ("elbow", "arm", trimesh.creation.icosphere(2, 0.2), (0, 0, 1.25), (60, 60, 70, 255)),
    ("wrist", "arm", None, (0.45, 0, 1.25), None),
    ("forearm", "wrist", trimesh.creation.box((0.9, 0.2, 0.2)), (0, 0, 0), (220, 120, 40, 255)),
    ("finger", "wrist", trimesh.creation.box((0.3, 0.05, 0.08)), (0.55, 0.07, 0), (40, 160, 220, 255)),
    ("finger_2", "wrist", trimesh.creation.box((0.3, 0.05, 0.08)), (0.55, -0.07, 0), (40, 160, 220, 255)),
]


def write_arm(path: Path) -> Path:
    scene = trimesh.Scene()
    for name, parent, mesh, offset, colour in NODES:
        move, parent = trimesh.transformations.translation_matrix(offset), parent or scene.graph.base_frame
        if mesh is None:  # a group node
            scene.graph.update(frame_from=parent, frame_to=name, matrix=move)
            continue
        mesh.visual.face_colors = colour
        scene.add_geometry(mesh, node_name=name, geom_name=name, parent_node_name=parent, transform=move)
    scene.apply_transform(trimesh.transformations.rotation_matrix(-np.pi / 2, (1, 0, 0)))  # z up -> glTF's y up
    scene.export(path)
    return path


def main(out: Path) -> Path:
    scene = rtta.load_scene(write_arm(out / "arm.glb"))
    print("\n".join("/".join((*scene.path_of(i), name)) for i, name in enumerate(scene.names)))
    view = {"camera": (30, 25, 2.1), "size": (360, 360)}
    left = rtta.snapshot(scene, "transparent", opacity={"arm": 0.8, "base": 0.25}, **view)
    right = rtta.snapshot(scene, "ghosted", focus=["wrist"], **view)
    Image.fromarray(np.concatenate([left, right], axis=1)).save(out / "gltf_tree.png")
    return out / "gltf_tree.png"


if __name__ == "__main__":
    out = Path(sys.argv[1] if sys.argv[1:] else "out/examples")
    out.mkdir(parents=True, exist_ok=True)
    print("wrote", main(out))
