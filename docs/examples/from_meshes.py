"""A scene of your own meshes (trimesh here), ghosted around one part.

`rtta.from_meshes` batches (name, vertices, faces, normals or None) parts into a Scene,
with a colour per part; no file is involved. The scene: a closed housing on a base plate,
a shaft through it and, inside, a ring and two balls, which the ghosted view shows through
the faded housing and base.

    python examples/from_meshes.py [OUT_DIR]     # writes OUT_DIR/from_meshes.png
"""

import sys
from pathlib import Path

import trimesh
from PIL import Image

import rtta


def parts() -> list[list[tuple[str, trimesh.Trimesh, tuple]]]:
    """(name, mesh, RGBA) per part; trimesh's primitives, placed by 4x4 transforms."""
    c, move = trimesh.creation, trimesh.transformations.translation_matrix
    return [
        ("base", c.box((3.0, 0.2, 2.0), move((0, -1.1, 0))), (0.4, 0.42, 0.45, 1.0)),
        ("housing", c.box((2.4, 2.0, 1.6)), (0.75, 0.25, 0.2, 1.0)),
        ("shaft", c.cylinder(0.12, 3.2), (0.7, 0.7, 0.75, 1.0)),  # along z, through the housing
        ("ring", c.torus(0.55, 0.15, transform=move((0, 0, -0.45))), (0.9, 0.7, 0.2, 1.0)),
        ("ball", c.icosphere(3, 0.35).apply_translation((0, 0, 0.3)), (0.2, 0.55, 0.9, 1.0)),
        ("ball_2", c.icosphere(3, 0.2).apply_translation((0.75, 0.5, 0.3)), (0.3, 0.75, 0.4, 1.0)),
    ]


def main(out: Path) -> Path:
    made = parts()
    scene = rtta.from_meshes([(name, m.vertices, m.faces, None) for name, m, _ in made], colors=[c for *_, c in made])
    rgba = rtta.snapshot(
        scene, mode="ghosted-ao", focus=["ring", "ball", "ball_2"], camera=(30, 25, 2.0), size=(480, 360)
    )
    path = out / "from_meshes.png"
    Image.fromarray(rgba).save(path)
    return path


if __name__ == "__main__":
    out = Path(sys.argv[1] if sys.argv[1:] else "out/examples")
    out.mkdir(parents=True, exist_ok=True)
    print("wrote", main(out))
