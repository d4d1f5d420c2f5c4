"""`rtta info`: what a scene holds, flat (one line per object) or as its part tree."""

from __future__ import annotations

import argparse

from ..errors import printable
from ..scene.model import Scene

AXES = {"y": "Y-up", "z": "Z-up"}


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--tree",
        action="store_true",
        help="print the part tree: every group with its object and triangle counts, objects below",
    )


def summary(scene: Scene) -> list[str]:
    """The header lines: counts and bounds, then the unit and the up axis."""
    lo, hi = scene.bounds
    unit = scene.unit or "unstated"
    return [
        f"{printable(scene.source)}: {scene.count} objects, {scene.vertex_count} vertices, "
        f"{len(scene.indices) // 3} triangles, bounds {lo.round(4).tolist()} .. {hi.round(4).tolist()}",
        f"unit: {unit}, up axis: {AXES.get(scene.up_axis, scene.up_axis)}",
    ]


def run(scene: Scene, tree: bool) -> int:
    print("\n".join(summary(scene)))
    triangles = scene.index_ranges[:, 1] // 3
    if not tree:
        for oid, name in enumerate(scene.names):
            print(f"{oid:5d}  {printable(name)}  ({triangles[oid]} triangles)")
        return 0
    for line in tree_lines(scene):
        print(line)
    return 0


def tree_lines(scene: Scene) -> list[str]:
    """The tree, indented two spaces a level: groups as 'name/  (objects, triangles)',
    objects as 'id  name  (triangles)', in the file's order."""
    triangles = scene.index_ranges[:, 1] // 3
    groups = scene.groups
    out: list[str] = []
    shown: tuple[str, ...] = ()
    for oid, name in enumerate(scene.names):
        path = scene.path_of(oid)
        common = 0
        while common < min(len(path), len(shown)) and path[common] == shown[common]:
            common += 1
        for depth in range(common, len(path)):
            ids = groups["/".join(path[: depth + 1])]
            out.append(
                f"{'  ' * depth}{printable(path[depth])}/  ({len(ids)} objects, {int(triangles[ids].sum())} triangles)"
            )
        shown = path
        out.append(f"{'  ' * len(path)}{oid:d}  {printable(name)}  ({triangles[oid]} triangles)")
    return out
