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
    objects as 'id  name  (triangles)'. Each group is printed once with everything below it,
    however its parts interleave with others' in the file; siblings keep the order in which
    the file first names them."""
    triangles = scene.index_ranges[:, 1] // 3
    groups = scene.groups
    root: dict = {"groups": {}, "entries": []}  # entries: group names and object ids, in order
    for oid in range(scene.count):
        node = root
        for part in scene.path_of(oid):
            if part not in node["groups"]:
                node["groups"][part] = {"groups": {}, "entries": []}
                node["entries"].append(part)
            node = node["groups"][part]
        node["entries"].append(oid)
    out: list[str] = []

    def emit(node: dict, path: tuple[str, ...]) -> None:
        pad = "  " * len(path)
        for entry in node["entries"]:
            if isinstance(entry, int):
                out.append(f"{pad}{entry:d}  {printable(scene.names[entry])}  ({triangles[entry]} triangles)")
                continue
            ids = groups["/".join((*path, entry))]
            out.append(f"{pad}{printable(entry)}/  ({len(ids)} objects, {int(triangles[ids].sum())} triangles)")
            emit(node["groups"][entry], (*path, entry))

    emit(root, ())
    return out
