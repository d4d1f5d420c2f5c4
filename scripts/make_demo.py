"""Regenerate assets/brake_assembly.glb from trimesh primitives (pip install '.[demo]')."""

from pathlib import Path

from rtta.scene.generators.demo import DEMO_NAME, write_demo

if __name__ == "__main__":
    out = write_demo(Path(__file__).resolve().parent.parent / "assets" / DEMO_NAME)
    print(f"wrote {out}")
