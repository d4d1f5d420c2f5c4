"""Generated scenes for tests and benchmarks (deterministic for a seed)."""

from __future__ import annotations

import numpy as np
import trimesh

from ..model import Scene, from_meshes


def _sphere(subdiv_target: int) -> trimesh.Trimesh:
    """A UV sphere with about `subdiv_target` vertices (at least a tetrahedron's worth)."""
    count = max(3, int(np.sqrt(max(subdiv_target, 12) / 2)))
    return trimesh.creation.uv_sphere(radius=1.0, count=[count, 2 * count])


def random_scene(
    n: int,
    seed: int = 0,
    vertices_per_object: int = 24,
    spread: float = 10.0,
    size_range: tuple[float, float] = (0.3, 1.5),
    offset=(0.0, 0.0, 0.0),
) -> Scene:
    """n boxes and spheres scattered in a cube of side `spread`, moved by `offset`."""
    rng = np.random.default_rng(seed)
    base_box = trimesh.creation.box()
    base_sphere = _sphere(vertices_per_object)
    parts = []
    off = np.asarray(offset, np.float64)
    for i in range(n):
        mesh = base_box if (i % 2 == 0 or vertices_per_object <= 24) else base_sphere
        size = rng.uniform(*size_range, 3)
        rot = trimesh.transformations.random_rotation_matrix(rng.random(3))[:3, :3]
        center = rng.uniform(-spread / 2, spread / 2, 3) + off
        v = (np.asarray(mesh.vertices) * size) @ rot.T + center
        parts.append((f"part{i:04d}", v, np.asarray(mesh.faces), None))
    return from_meshes(parts, source=f"<random {n} seed {seed}>")


def torus(k: int) -> tuple[np.ndarray, np.ndarray]:
    """A closed torus grid with rows x cols ~= k vertices (at least 3 x 3)."""
    rows = max(3, int(round(np.sqrt(k / 3.0))))
    cols = max(3, int(round(k / rows)))
    u = np.linspace(0, 2 * np.pi, cols, endpoint=False)
    v = np.linspace(0, 2 * np.pi, rows, endpoint=False)
    uu, vv = np.meshgrid(u, v)
    r = 1.0 + 0.35 * np.cos(vv)
    verts = np.stack([r * np.cos(uu), r * np.sin(uu), 0.35 * np.sin(vv)], -1).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(rows), np.arange(cols), indexing="ij")
    a = i * cols + j
    b = i * cols + (j + 1) % cols
    c = ((i + 1) % rows) * cols + j
    d = ((i + 1) % rows) * cols + (j + 1) % cols
    faces = np.concatenate([np.stack([a, b, d], -1).reshape(-1, 3), np.stack([a, d, c], -1).reshape(-1, 3)])
    return verts, faces


def table1_scene(objects: int, vertices: int, seed: int = 1) -> Scene:
    """Tori with (about) the object and vertex counts of a row of the paper's Table 1."""
    rng = np.random.default_rng(seed)
    spread = 3.0 * np.cbrt(objects)
    per = np.full(objects, vertices // objects)
    per[: vertices % objects] += 1
    parts = []
    for i in range(objects):
        v, f = torus(int(per[i]))
        rot = trimesh.transformations.random_rotation_matrix(rng.random(3))[:3, :3]
        v = (v * rng.uniform(0.4, 1.2)) @ rot.T + rng.uniform(-spread / 2, spread / 2, 3)
        parts.append((f"part{i:04d}", v, f, None))
    return from_meshes(parts, source=f"<table1 {objects} objects>")


TABLE1 = [(5, 2191), (21, 32081), (580, 56654), (269, 1040503)]
