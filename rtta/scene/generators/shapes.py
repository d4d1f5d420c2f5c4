"""Closed test shapes for the layered-depth-image tests and benchmarks (seed 003's table has a
sphere, a torus knot and non-convex shapes), and the lens shapes. All watertight."""

from __future__ import annotations

import numpy as np
import trimesh


def sphere(radius: float = 1.0, subdivisions: int = 3) -> trimesh.Trimesh:
    return trimesh.creation.icosphere(subdivisions=subdivisions, radius=radius)


def box(size: float = 2.0) -> trimesh.Trimesh:
    return trimesh.creation.box(extents=(size, size, size))


def torus(major: float = 1.0, minor: float = 0.35) -> trimesh.Trimesh:
    """Torus about the z axis (depth complexity 2 along z, 4 from the side)."""
    return trimesh.creation.torus(major_radius=major, minor_radius=minor, major_sections=64, minor_sections=24)


def torus_knot(p: int = 2, q: int = 3, tube: float = 0.18, segments: int = 256, sides: int = 16) -> trimesh.Trimesh:
    """A (p, q) torus knot swept with a circular tube: rings along the curve, each joined to
    the next and the last to the first, so the surface is closed."""
    t = np.linspace(0, 2 * np.pi, segments, endpoint=False)
    r = 1.0 + 0.4 * np.cos(q * t)

    def curve(tt, rr):
        return np.stack([rr * np.cos(p * tt), rr * np.sin(p * tt), 0.4 * np.sin(q * tt)], -1)

    c = curve(t, r)
    tangent = np.roll(c, -1, axis=0) - np.roll(c, 1, axis=0)
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    normal = np.cross(tangent, np.array([0.0, 0.0, 1.0]))
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    binormal = np.cross(tangent, normal)
    a = np.linspace(0, 2 * np.pi, sides, endpoint=False)
    ring = np.cos(a)[None, :, None] * normal[:, None] + np.sin(a)[None, :, None] * binormal[:, None]
    vertices = (c[:, None] + tube * ring).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(segments), np.arange(sides), indexing="ij")
    v00 = i * sides + j
    v10 = ((i + 1) % segments) * sides + j
    v01 = i * sides + (j + 1) % sides
    v11 = ((i + 1) % segments) * sides + (j + 1) % sides
    faces = np.concatenate([np.stack([v00, v10, v11], -1).reshape(-1, 3), np.stack([v00, v11, v01], -1).reshape(-1, 3)])
    mesh = trimesh.Trimesh(vertices, faces, process=True)
    mesh.fix_normals()
    return mesh


def vase(sections: int = 64) -> trimesh.Trimesh:
    """A non-convex solid of revolution: a wavy profile with two bulges and a waist, closed at
    both ends on the axis (depth complexity 4 through the bulges from above)."""
    z = np.linspace(0.0, 2.0, 41)
    radius = 0.55 + 0.3 * np.sin(z * 2.5 * np.pi) ** 2 * (0.6 + 0.4 * z)
    profile = np.concatenate([[[0.0, 0.0]], np.stack([radius, z], -1), [[0.0, 2.0]]])
    return trimesh.creation.revolve(profile, sections=sections)


SHAPES = {"sphere": sphere, "torus": torus, "torus-knot": torus_knot, "vase": vase, "box": box}
