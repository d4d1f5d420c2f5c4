"""OBJ's objects made distinct for trimesh, which merges objects of one name and ignores groups;
the colours of a file rtta reads itself (obj_read) as trimesh gives them."""

from __future__ import annotations

import io
import re
from dataclasses import replace
from pathlib import Path

from . import obj_read
from .trimesh_io import base_color, trimesh_load


def obj_objects(path: Path) -> tuple[bytes, list[str]]:
    """The OBJ's bytes with each `o NAME` line made `o rtta.o.K` (trimesh merges objects of the
    same name, and an unnamed one into its neighbour), and the names in file order, decoded
    as UTF-8 or else Windows-1252. A file with fewer than two `o` lines but several `g NAME`
    groups has its groups made the objects so (its one `o` line left out): CAD exporters
    write the parts of a model as groups."""
    data = b"\n" + path.read_bytes()  # every line after a newline: _line's patterns start there
    names: list[str] = []

    def rename(match: re.Match) -> bytes:
        raw = (match.group(1) or b"").strip()
        try:
            names.append(raw.decode("utf-8"))
        except UnicodeDecodeError:
            names.append(raw.decode("cp1252", errors="replace"))
        return f"\no rtta.o.{len(names) - 1}".encode()

    objects = re.sub(_line(b"o"), rename, data)
    if len(names) >= 2:
        return objects[1:], names
    found = names[:]
    names.clear()
    groups = re.sub(_line(b"g"), rename, re.sub(_line(b"o"), lambda m: b"\n#", data))
    if len(names) >= 2:
        return groups[1:], names
    return objects[1:], found


def _line(keyword: bytes) -> bytes:
    """A line `KEYWORD NAME` (or a bare `KEYWORD`) with the newline before it; group 1 the name.
    A literal first character lets the engine skip to the newlines (a pattern starting with
    `(^|\n)` tried every position: 8 s of a 100,000-part file)."""
    return rb"\n[ \t]*" + keyword + rb"(?:[ \t]+([^\r\n]*)|(?=[\r\n]|$))"


def object_number(name: str) -> int | None:
    """K of an object obj_objects named `rtta.o.K` (trimesh's node name for it), else None."""
    match = re.fullmatch(r"rtta\.o\.(\d+)", name)
    return int(match.group(1)) if match else None


def material_colors(decoded: list, data: bytes, path: Path, resolver) -> list | None:
    """obj_read's objects coloured as trimesh colours them, from its reading of the file's
    material skeleton (obj_read.material_skeleton) through `resolver`; None where a material
    has a texture: the whole file then goes through trimesh, which reads its texture
    coordinates."""
    skeleton, stands_for = obj_read.material_skeleton(data)
    loaded = trimesh_load(io.BytesIO(skeleton), "obj", path, resolver)
    color_of: dict[int, list[float] | None] = {}
    for node in loaded.graph.nodes_geometry:
        mesh = loaded.geometry.get(loaded.graph[node][1])
        if getattr(getattr(getattr(mesh, "visual", None), "material", None), "image", None) is not None:
            return None
        k = object_number(str(node))
        if k is not None and mesh is not None:
            color_of[k] = base_color(mesh)
    return [
        (k, replace(geometry, color=color_of.get(stands_for.get(k, -1), geometry.color))) for k, geometry in decoded
    ]
