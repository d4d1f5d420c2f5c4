"""OBJ's objects made distinct for trimesh, which merges objects of one name and ignores groups."""

from __future__ import annotations

import re
from pathlib import Path


def obj_objects(path: Path) -> tuple[bytes, list[str]]:
    """The OBJ's bytes with each `o NAME` line made `o rtta.o.K` (trimesh merges objects of the
    same name, and an unnamed one into its neighbour; in a file without `o` lines, each `g NAME`
    group: CAD exporters write parts as groups), and the names in file order, decoded as
    UTF-8 or else Windows-1252."""
    data = path.read_bytes()
    names: list[str] = []

    def rename(match: re.Match) -> bytes:
        raw = (match.group(2) or b"").strip()
        try:
            names.append(raw.decode("utf-8"))
        except UnicodeDecodeError:
            names.append(raw.decode("cp1252", errors="replace"))
        return match.group(1) + f"o rtta.o.{len(names) - 1}".encode()

    for keyword in (b"o", b"g"):
        out = re.sub(rb"(^|\n)[ \t]*" + keyword + rb"(?:[ \t]+([^\r\n]*)|(?=[\r\n]|$))", rename, data)
        if names:
            break
    return out, names
