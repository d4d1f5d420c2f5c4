"""The built-in demo: a disc-brake assembly made from trimesh primitives (24 named parts).

Rotor (with cooling holes), hub, wheel studs and nuts, spindle, dust shield, caliper,
two pads and two pistons (hidden inside the caliper from the default camera), guide
pins, bracket, bleed screw and brake-line fitting. `python scripts/make_demo.py`
regenerates assets/brake_assembly.glb (needs the `demo` extra: shapely, mapbox-earcut).
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

import numpy as np
import trimesh
from trimesh.visual import TextureVisuals
from trimesh.visual.material import PBRMaterial

DEMO_NAME = "brake_assembly.glb"

COLORS = {
    "rotor": (150, 150, 155),
    "hub": (110, 112, 120),
    "stud": (200, 190, 120),
    "nut": (215, 215, 220),
    "spindle": (80, 80, 88),
    "shield": (60, 64, 70),
    "caliper": (200, 40, 35),
    "pad": (70, 140, 200),
    "piston": (240, 170, 40),
    "pin": (180, 180, 190),
    "bracket": (90, 100, 90),
    "bleed": (230, 230, 90),
    "fitting": (160, 110, 70),
}


def demo_path() -> Path:
    """Path of the shipped demo scene (inside the installed package)."""
    return Path(str(resources.files("rtta.assets").joinpath(DEMO_NAME)))


def _box(lo, hi) -> trimesh.Trimesh:
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    return trimesh.creation.box(extents=hi - lo, transform=trimesh.transformations.translation_matrix((lo + hi) / 2))


def _cyl_z(radius, z0, z1, x=0.0, y=0.0, sections=32) -> trimesh.Trimesh:
    m = trimesh.creation.cylinder(radius=radius, height=z1 - z0, sections=sections)
    m.apply_translation((x, y, (z0 + z1) / 2))
    return m


def _rotor() -> trimesh.Trimesh:
    from shapely.geometry import Point

    ring = Point(0, 0).buffer(1.6, 96).difference(Point(0, 0).buffer(0.9, 96))
    for k in range(30):
        a = 2 * np.pi * k / 30
        r = 1.2 if k % 2 == 0 else 1.38
        ring = ring.difference(Point(r * np.cos(a), r * np.sin(a)).buffer(0.055, 12))
    m = trimesh.creation.extrude_polygon(ring, height=0.28)
    m.apply_translation((0, 0, -0.14))
    return m


def _caliper() -> trimesh.Trimesh:
    """Boxes that touch but never overlap, so no two exterior faces are coplanar (no z-fighting)."""
    parts = [
        _box((-0.75, 1.02, 0.2), (0.75, 1.68, 0.52)),  # outer half
        _box((-0.75, 1.02, -0.62), (0.75, 1.68, -0.2)),  # inner half (holds the pistons)
        _box((-0.75, 1.68, -0.62), (0.75, 2.02, 0.52)),  # bridge over the rotor rim
        _box((0.62, 1.02, 0.12), (0.75, 1.68, 0.2)),  # end caps closing the pad pockets
        _box((-0.75, 1.02, 0.12), (-0.62, 1.68, 0.2)),
        _box((0.62, 1.02, -0.2), (0.75, 1.68, -0.12)),
        _box((-0.75, 1.02, -0.2), (-0.62, 1.68, -0.12)),
        _box((-0.62, 1.02, 0.12), (0.62, 1.1, 0.2)),  # lower lips
        _box((-0.62, 1.02, -0.2), (0.62, 1.1, -0.12)),
    ]
    whole = trimesh.util.concatenate(parts)
    assert isinstance(whole, trimesh.Trimesh)  # (trimesh types it as any geometry)
    return whole


def build_brake_assembly() -> trimesh.Scene:
    """The demo scene, rotor axis along +Z, caliper on top (+Y)."""
    parts: list[tuple[str, str, trimesh.Trimesh]] = [
        ("rotor", "rotor", _rotor()),
        (
            "hub",
            "hub",
            trimesh.creation.annulus(
                r_min=0.3, r_max=0.85, height=0.4, transform=trimesh.transformations.translation_matrix((0, 0, 0.34))
            ),
        ),
        ("spindle", "spindle", _cyl_z(0.28, -1.1, 0.5)),
        (
            "dust_shield",
            "shield",
            trimesh.creation.annulus(
                r_min=0.4, r_max=1.75, height=0.03, transform=trimesh.transformations.translation_matrix((0, 0, -0.8))
            ),
        ),
    ]
    for k in range(5):
        a = 2 * np.pi * k / 5 + np.pi / 2
        x, y = 0.6 * np.cos(a), 0.6 * np.sin(a)
        parts.append((f"wheel_stud_{k + 1}", "stud", _cyl_z(0.055, 0.5, 1.05, x, y, 16)))
        parts.append((f"lug_nut_{k + 1}", "nut", _cyl_z(0.11, 0.7, 0.86, x, y, 6)))
    parts += [
        ("caliper", "caliper", _caliper()),
        ("pad_outer", "pad", _box((-0.6, 1.12, 0.145), (0.6, 1.62, 0.2))),
        ("pad_inner", "pad", _box((-0.6, 1.12, -0.2), (0.6, 1.62, -0.145))),
        ("piston_1", "piston", _cyl_z(0.17, -0.46, -0.2, -0.3, 1.37)),
        ("piston_2", "piston", _cyl_z(0.17, -0.46, -0.2, 0.3, 1.37)),
        ("guide_pin_1", "pin", _cyl_z(0.07, -0.95, -0.55, -0.88, 1.35, 16)),
        ("guide_pin_2", "pin", _cyl_z(0.07, -0.95, -0.55, 0.88, 1.35, 16)),
        (
            "bracket",
            "bracket",
            trimesh.util.concatenate(
                [
                    _box((-1.05, 1.15, -0.9), (1.05, 1.55, -0.68)),
                    _box((-1.05, 0.2, -0.9), (-0.75, 1.15, -0.68)),
                    _box((0.75, 0.2, -0.9), (1.05, 1.15, -0.68)),
                ]
            ),
        ),
        (
            "bleed_screw",
            "bleed",
            _cyl_z(0.05, -0.18, 0.0, 0.45, 2.1, 12).apply_transform(
                trimesh.transformations.rotation_matrix(0.0, (1, 0, 0))
            ),
        ),
        ("brake_line_fitting", "fitting", _cyl_z(0.08, -0.9, -0.62, -0.4, 1.85, 12)),
    ]
    scene = trimesh.Scene()
    for name, kind, mesh in parts:
        r, g, b = COLORS[kind]
        mesh = mesh.smooth_shaded  # split vertices at sharp edges so normals stay crisp
        mesh.visual = TextureVisuals(
            material=PBRMaterial(name=kind, baseColorFactor=[r, g, b, 255], metallicFactor=0.0, roughnessFactor=0.8)
        )
        scene.add_geometry(mesh, node_name=name, geom_name=name)
    return scene


def write_demo(path: str | Path) -> Path:
    path = Path(path)
    glb = build_brake_assembly().export(file_type="glb", include_normals=True)
    assert isinstance(glb, bytes)  # (a GLB: trimesh types export's result as any format's)
    path.write_bytes(glb)
    return path
