"""Checks made on a scene file before trimesh reads it: how much memory its declared sizes
need (binary STL, PLY and OFF headers; the uncompressed size of every member of a 3MF,
which is a zip archive) and, for 3MF, that its component graph has no cycle and does not
multiply into more objects than can be drawn. glTF is checked in rtta.scene.readers.gltf.

`precheck(path)` raises RttaError for what cannot be loaded and returns warnings for what can.
"""

from __future__ import annotations

import lzma
import re
import struct
import zipfile
import zlib
from pathlib import Path

from ..errors import RttaError, reason
from .files import MAX_OBJECTS_LARGE, PARTS_HINT, max_objects, memory_limit

# what reading a damaged zip archive raises (3MF, 3DXML, ZAE): the directory, or a member's
# compressed data (deflate, lzma), unreadable
ZIP_ERRORS = (
    zipfile.BadZipFile,
    zipfile.LargeZipFile,
    EOFError,
    NotImplementedError,
    OSError,
    ValueError,
    zlib.error,
    lzma.LZMAError,
)

# Peak memory of loading, measured (docs/reliability.md): with normals smoothed at load (a file
# without normals) about 170 bytes per vertex and 1,300 per triangle (163,842 vertices and
# 327,680 triangles: 435 MiB); a file with normals needs about a tenth of that. Half the
# worst case is charged, so a scene the limit admits peaks below twice the limit.
BYTES_PER_VERTEX = 120
BYTES_PER_TRIANGLE = 720
XML_BYTES_FACTOR = 24  # trimesh's 3MF reader: 559 MiB peak for a 27 MiB model (21 per byte)
MAX_ZIP_MEMBERS = 10_000


def check_size(vertices: int, triangles: int, path: Path, what: str = "") -> None:
    """RttaError when a mesh of this size would need more than the memory limit."""
    need = vertices * BYTES_PER_VERTEX + triangles * BYTES_PER_TRIANGLE
    limit = memory_limit()
    if need > limit:
        raise RttaError(
            f"{what or 'the scene has'} {vertices:,} vertices and {triangles:,} triangles, about "
            f"{need / 2**20:,.0f} MiB, over the memory limit of {limit / 2**20:,.0f} MiB "
            "(RTTA_MEMORY_LIMIT_MB)",
            path,
        )


def precheck(path: Path) -> list[str]:
    suffix = path.suffix.lower()
    if suffix == ".stl":
        _stl(path)
    elif suffix == ".ply":
        _ply(path)
    elif suffix == ".off":
        _off(path)
    elif suffix == ".3mf":
        _threemf(path)
    return []


def _stl(path: Path) -> None:
    size = path.stat().st_size
    with open(path, "rb") as f:
        head = f.read(84)
    if head[:5].lower() == b"solid" and b"\0" not in head:
        return  # ASCII STL: trimesh parses it; its size is checked after loading
    if len(head) < 84:
        raise RttaError(
            f"not an STL file (no 'solid' line, and {size} bytes is shorter than a binary STL header)", path
        )
    count = struct.unpack_from("<I", head, 80)[0]
    check_size(3 * count, count, path, "the binary STL declares")
    if 84 + 50 * count != size:
        raise RttaError(
            f"binary STL declares {count:,} triangles ({84 + 50 * count:,} bytes) but the file has {size:,} bytes", path
        )


def _ply(path: Path) -> None:
    with open(path, "rb") as f:
        head = f.read(65536)
    end = head.find(b"end_header")
    if not head.startswith(b"ply") or end < 0:
        raise RttaError("not a PLY file (no 'ply' ... 'end_header' header)", path)
    counts = dict(re.findall(rb"element\s+(\w+)\s+(\d+)", head[:end]))
    check_size(int(counts.get(b"vertex", 0)), int(counts.get(b"face", 0)), path, "the PLY header declares")


def _off(path: Path) -> None:
    with open(path, "rb") as f:
        head = f.read(4096)
    words = re.sub(rb"#[^\n]*", b"", head).split()
    if not words or not words[0].endswith(b"OFF"):
        raise RttaError("not an OFF file (no 'OFF' header)", path)
    try:
        vertices, faces = int(words[1]), int(words[2])
    except (IndexError, ValueError):
        raise RttaError("OFF header has no vertex and face counts", path) from None
    check_size(vertices, faces, path, "the OFF header declares")


def _threemf(path: Path) -> None:
    """The archive's declared uncompressed sizes against the memory limit (trimesh unpacks
    every member into memory, then parses the XML), and the component graph."""
    try:
        with zipfile.ZipFile(path) as archive:
            infos = archive.infolist()
            if len(infos) > MAX_ZIP_MEMBERS:
                raise RttaError(f"3MF archive has {len(infos):,} members (at most {MAX_ZIP_MEMBERS:,})", path)
            total = sum(i.file_size for i in infos)
            if total * XML_BYTES_FACTOR > memory_limit():
                raise RttaError(
                    f"3MF archive unpacks to {total:,} bytes, which needs about "
                    f"{total * XML_BYTES_FACTOR / 2**20:,.0f} MiB to read, over the memory limit of "
                    f"{memory_limit() / 2**20:,.0f} MiB (RTTA_MEMORY_LIMIT_MB)",
                    path,
                )
            model = next((i for i in infos if "3d/3dmodel.model" in i.filename.lower()), None)
            if model is None:
                raise RttaError("3MF archive has no 3D/3dmodel.model", path)
            with archive.open(model) as stream:
                head = stream.read(4096)
            with archive.open(model) as stream:
                _threemf_graph(stream, head, path)
    except ZIP_ERRORS as exc:
        raise RttaError(f"not a readable 3MF archive ({reason(exc, 100)})", path) from None


def _threemf_graph(stream, head: bytes, path: Path) -> None:
    """No DTD (no entity expansion), no component cycle, not too many drawn paths."""
    from lxml import etree

    if b"<!DOCTYPE" in head or b"<!ENTITY" in head:
        raise RttaError("3MF model declares a DTD; rtta does not expand XML entities", path)
    children: dict[str, list[str]] = {}
    items: list[str] = []
    try:
        for _, el in etree.iterparse(
            stream,
            events=("end",),
            tag=("{*}object", "{*}item"),
            resolve_entities=False,
            no_network=True,
            load_dtd=False,
            huge_tree=False,
        ):
            if str(el.tag).endswith("object"):
                children[el.get("id", "")] = [c.get("objectid", "") for c in el.iter("{*}component")]
                el.clear(keep_tail=False)
            else:
                items.append(el.get("objectid", ""))
    except etree.XMLSyntaxError as exc:
        raise RttaError(f"3MF model is not valid XML ({str(exc)[:100]})", path) from None
    paths: dict[str, int] = {}
    for root in items:
        stack, state = [root], {}
        while stack:  # iterative post-order: paths(o) = 1 or the sum over components
            node = stack[-1]
            if node in paths:
                stack.pop()
                continue
            if state.get(node) == 1:
                kids = children.get(node, [])
                paths[node] = min(sum(paths.get(k, 0) for k in kids) if kids else 1, 10 * MAX_OBJECTS_LARGE)
                state[node] = 2
                stack.pop()
                continue
            state[node] = 1
            for k in children.get(node, []):
                if state.get(k) == 1:
                    raise RttaError(f"3MF component graph has a cycle (object {k} contains itself)", path)
                if k not in paths:
                    stack.append(k)
    total = sum(paths.get(r, 0) for r in items)
    limit = max_objects(path)
    if total > limit:
        raise RttaError(
            f"3MF build makes {total:,} objects through its components (at most {limit:,} for a file of its "
            f"size; {PARTS_HINT})",
            path,
        )
