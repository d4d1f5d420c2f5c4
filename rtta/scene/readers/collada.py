"""COLLADA (.dae, and .zae archives) through pycollada, walking the node tree itself so that
every geometry instance keeps its node path and names (pycollada's flat `objects()` loses
them). The file's unit (`<unit meter=...>`) and up axis (`<up_axis>`) are kept."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...errors import RttaError, reason
from ..files import PARTS_HINT, WALK_PER_OBJECT, max_objects
from . import Assembly, check_archive, hidden, unit_name

MAX_DEPTH = 256


def read(path: Path) -> Assembly:
    import collada
    from collada.common import DaeBrokenRefError, DaeUnsupportedError

    if path.suffix.lower() == ".zae":
        check_archive(path)
    try:
        dae = collada.Collada(str(path), ignore=[DaeUnsupportedError, DaeBrokenRefError])
    except Exception as exc:  # pycollada raises many types for bad files
        raise RttaError(f"cannot read COLLADA file ({reason(exc)})", path) from None
    info = dae.assetInfo
    meters = float(getattr(info, "unitmeter", None) or 1.0)
    axis = str(getattr(info, "upaxis", "Y_UP") or "Y_UP").upper()
    out = Assembly(unit=unit_name(meters), up_axis="z" if axis.startswith("Z") else "y")
    if dae.scene is None:
        raise RttaError("the COLLADA file has no scene", path)
    hiders: dict[str, None] = {}  # nodes whose singular transform hid a geometry, in file order
    walk = _Walk(path)
    for node in dae.scene.nodes:
        _visit(node, np.identity(4), (), out, 0, (hiders, None), walk)
    hidden.note_hidden(list(hiders), len(out.names), path, out.warnings)
    return out


class _Walk:
    """What the node walk may still do: <instance_node> makes the tree a graph, and node k
    holding node k+1 twice 40 times over is 2^40 paths in a few KiB; the walk stops with an
    error once it visited more nodes, or made more parts, than a file of its size may."""

    def __init__(self, path: Path) -> None:
        self.path, self.objects = path, max_objects(path)
        self.visits = self.objects * WALK_PER_OBJECT

    def step(self, out: Assembly) -> None:
        self.visits -= 1
        if self.visits < 0 or len(out.names) > self.objects:
            raise RttaError(
                f"the COLLADA node graph makes over {self.objects:,} parts or {self.objects * WALK_PER_OBJECT:,} "
                f"node visits (nodes instanced many times over, or in a cycle; {PARTS_HINT})",
                self.path,
            )


def _label(node) -> str:
    return str(getattr(node, "name", None) or getattr(node, "id", None) or "node")


def _visit(
    node, parent: np.ndarray, groups: tuple[str, ...], out: Assembly, depth: int, hiding: tuple, walk: _Walk
) -> None:
    """The node's geometries and its children's. Below a singular transform (a zero scale)
    nothing is drawn; `hiding` is (the names of the nodes that hid a geometry, the node whose
    transform flattens this subtree or None)."""
    from collada import scene

    if depth > MAX_DEPTH:
        return
    walk.step(out)
    if isinstance(node, scene.NodeNode):  # <instance_node>: the referenced node, here
        node = node.node
    if not isinstance(node, scene.Node):
        return
    m = parent @ np.asarray(node.matrix, np.float64)
    name = _label(node)
    hiders, hider = hiding
    hider = hider or (name if hidden.singular(m) else None)
    geometries = [c for c in node.children if isinstance(c, scene.GeometryNode)]
    for k, g in enumerate(geometries):
        v, f, color = _geometry(g, walk.path)
        if len(f) and hider is not None:
            hiders[hider] = None
        elif len(f):
            world = v @ m[:3, :3].T + m[:3, 3]
            label = name if len(geometries) == 1 else f"{name} {g.geometry.name or g.geometry.id or k + 1}"
            out.add(label, world, f, color, groups)
    for child in node.children:
        if isinstance(child, scene.Node | scene.NodeNode):
            _visit(child, m, (*groups, name), out, depth + 1, (hiders, hider), walk)


def _geometry(gnode, path: Path) -> tuple[np.ndarray, np.ndarray, list[float] | None]:
    """Triangles of one geometry instance, in its node's frame, and its first material colour."""
    from collada.polylist import Polylist

    vs, fs, base, color = [], [], 0, None
    materials = {m.symbol: m.target for m in (gnode.materials or [])}
    for prim in gnode.geometry.primitives:
        if isinstance(prim, Polylist):  # pycollada allocates for sum(vcount), before any check
            counts = np.asarray(prim.vcounts, np.int64)
            if len(prim.index) and (counts.min(initial=0) < 0 or int(counts.sum()) != len(prim.index)):
                raise RttaError(
                    f"COLLADA geometry '{gnode.geometry.id}' has polygon sizes (<vcount>) that add up to "
                    f"{int(counts.sum()):,} corners, but its <p> has {len(prim.index):,}",
                    path,
                )
        tri = prim.triangleset() if hasattr(prim, "triangleset") else prim
        if not hasattr(tri, "vertex_index") or tri.vertex is None or tri.vertex_index is None:
            continue
        v = np.asarray(tri.vertex, np.float64).reshape(-1, 3)
        f = np.asarray(tri.vertex_index, np.int64).reshape(-1, 3)
        vs.append(v)
        fs.append(f + base)
        base += len(v)
        if color is None:
            color = _diffuse(materials.get(getattr(prim, "material", None)))
    if not vs:
        return np.zeros((0, 3)), np.zeros((0, 3), np.int64), None
    return np.concatenate(vs), np.concatenate(fs), color


def _diffuse(material) -> list[float] | None:
    effect = getattr(material, "effect", None)
    d = getattr(effect, "diffuse", None)
    if isinstance(d, tuple | list) and len(d) >= 3:
        c = [float(x) for x in d[:4]] + [1.0] * (4 - min(4, len(d)))
        return c if np.isfinite(c).all() else None
    return None
