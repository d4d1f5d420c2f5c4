"""Plain OBJ assemblies read straight into arrays, without trimesh's per-object split.

trimesh splits an OBJ's objects by masking the file's whole vertex array once per object,
so its time grows with objects × vertices: 10,000 cylinders took 12.6 s split against 1.6 s
unsplit, and 100,000 parts would take about 20 minutes. `decode` reads a plain file
(`v` positions, `vn` normals, `vt` checked but not used, triangle and polygon faces, `o` objects as
rtta.scene.readers.obj names them, `s`, `usemtl` and `mtllib`, comments) in whole-file passes; any
other file (vertex colours, lines or points, relative indices, anything it cannot parse)
returns None and goes through trimesh as before, with its messages for damaged files. The
colours of a file with materials come from trimesh reading its material_skeleton.
Each object gets the vertices its faces use, in file order (paired with their normals where
the faces give them), as trimesh gives them; polygons are fans around their first corner.
"""

from __future__ import annotations

import re
import warnings

import numpy as np

from ..batch import fans
from .gltf_read import NO_FACTOR, Decoded

# Every pattern starts at the newline before its line (the text is searched with one newline
# put before it): a literal first character lets the engine skip to candidates, where `^` with
# MULTILINE tries every position (4 s of a 30,000-part file's 9 s went to that).
# any line that is not v, vn, vt, f, o, s, g, usemtl or mtllib with its arguments, a comment or blank
_OTHER = re.compile(rb"\n(?![ \t]*(?:(?:vn?|vt|f|s|g|o|usemtl|mtllib)[ \t]|#|\r?(?:\n|$)))")
_MATERIAL = re.compile(rb"\n[ \t]*(?:usemtl|mtllib)[ \t]")
_KEPT = re.compile(rb"\n[ \t]*(?:(?:usemtl|mtllib|o|g)[ \t][^\r\n]*|f[ \t][^\r\n]*(?:\r?\n[ \t]*f[ \t][^\r\n]*)*)")
# a v or vn line of other than 3 numbers (w, vertex colours, a damaged row); a continued line
_ODD = re.compile(rb"\n[ \t]*vn?[ \t](?![ \t]*[^ \t\r\n]+[ \t]+[^ \t\r\n]+[ \t]+[^ \t\r\n]+[ \t]*\r?(?:\n|$))")
_CONTINUED = re.compile(rb"\\[ \t]*\r?(?:\n|$)")
_OBJECT = re.compile(rb"\no rtta\.o\.(\d+)(?=\r?(?:\n|$))")  # as rtta.scene.readers.obj writes them
_POLYGON = re.compile(rb"\n[ \t]*f[ \t](?![ \t]*[^ \t\r\n]+[ \t]+[^ \t\r\n]+[ \t]+[^ \t\r\n]+[ \t]*\r?(?:\n|$))")
_FACE = re.compile(rb"\n[ \t]*f[ \t]+([^\r\n]*)")
_V = re.compile(rb"\n[ \t]*v[ \t]+([^\r\n]*)")
_VN = re.compile(rb"\n[ \t]*vn[ \t]+([^\r\n]*)")
_VT = re.compile(rb"\n[ \t]*vt[ \t]+([^\r\n]*)")


def decode(data: bytes, names: list[str]) -> list[tuple[int, Decoded]] | None:
    """(object number K, geometry) per object with faces, in file order, for a plain OBJ whose
    objects are `o rtta.o.K` lines (rtta.scene.readers.obj.obj_objects, K indexes `names`); None for
    any other file."""
    data = b"\n" + data  # each line after a newline (the patterns above)
    if _OTHER.search(data) or _ODD.search(data) or _CONTINUED.search(data):
        return None
    parts = _OBJECT.split(data)  # [before any object, K, its lines, K, its lines ...]
    if _FACE.search(parts[0]):  # faces before any object: trimesh names them itself
        return None
    polygons = _POLYGON.search(data) is not None
    face_rows, face_sizes, face_object = [], [], []  # per object: its face rows joined, their sizes
    for k, chunk in zip(parts[1::2], parts[2::2], strict=True):
        rows = _FACE.findall(chunk)
        if rows:
            face_rows.append(b" ".join(rows))
            face_sizes.append([len(row.split()) for row in rows] if polygons else [3] * len(rows))
            face_object.append(int(k))
    del parts
    # objects numbered in file order (rtta.scene.readers.obj): the triangles come grouped by object
    ascending = all(b > a for a, b in zip(face_object, face_object[1:], strict=False))
    if not face_rows or not ascending or face_object[-1] >= len(names):
        return None
    try:
        v, vn = (_numbers(pattern.findall(data), np.float64).reshape(-1, 3) for pattern in (_V, _VN))
        n_vt = _texture_rows(data)
        corners = None if n_vt is None else _corners(face_rows, face_sizes, face_object, len(v), len(vn), n_vt)
    except (ValueError, OverflowError):  # a number or an index that does not parse
        return None
    if corners is None:
        return None
    tri, tri_n, objects, uv = corners
    # faces with texture coordinates get trimesh's grey for a material it made up, others the palette
    return _objects(names, v, vn, tri, tri_n, objects, NO_FACTOR if uv else None)


def has_materials(data: bytes) -> bool:
    """Whether the file names materials (their colours come from trimesh: material_skeleton)."""
    # the first line has no newline before it: matched on its own, the file not copied
    return _MATERIAL.search(data) is not None or _MATERIAL.match(b"\n" + data[:64]) is not None


def material_skeleton(data: bytes) -> tuple[bytes, dict[int, int]]:
    """What decides each object's material, for trimesh to read with the file's resolver:
    (an OBJ text, the object K whose skeleton object stands for each object). The text has the
    file's `mtllib` lines, then one object per distinct content: its `usemtl` and `g` lines in
    order, led by the material it inherits from the objects before it, each run of faces one
    face over three dummy vertices in the run's corner form (so trimesh makes the same
    visuals: a made-up material where faces have texture coordinates). Objects of the same
    content get the same colour from trimesh, so 100,000 parts of 6 materials cost it 6."""
    libraries: list[bytes] = []
    contents: dict[int, list[bytes]] = {}  # by object number
    material: bytes | None = None
    content: list[bytes] | None = None
    for m in _KEPT.finditer(b"\n" + data):
        line = m.group(0).strip()
        if line.startswith(b"mtllib"):
            libraries.append(line)  # trimesh reads the first one in the file
        elif line.startswith(b"o "):
            content = contents.setdefault(int(line[len(b"o rtta.o.") :]), [])
            if material is not None:
                content.append(material)
        elif line.startswith(b"f"):
            corner = line.split(b"\n", 1)[0].split()[1].split(b"/")
            form = b"/".join([b"%d"] + [b"1" if part else b"" for part in corner[1:]])
            if content is not None:
                content.append(b"f " + b" ".join(form % i for i in (1, 2, 3)))
        else:  # usemtl, g
            usemtl = line.startswith(b"usemtl")
            material = line if usemtl else material
            if content is not None and usemtl and content and content[-1].startswith(b"usemtl"):
                content[-1] = line  # a material no face used: as if not there
            elif content is not None:
                content.append(line)
    lines = [*libraries, b"v 0 0 0", b"v 1 0 0", b"v 0 1 0", b"vt 0 0", b"vn 0 0 1"]
    standing: dict[tuple, int] = {}
    stands_for: dict[int, int] = {}
    for k, kept in contents.items():
        key = tuple(kept)
        if key not in standing:
            standing[key] = k
            lines += [b"o rtta.o.%d" % k, *kept]
        stands_for[k] = standing[key]
    return b"\n".join(lines) + b"\n", stands_for


def _numbers(rows: list[bytes], dtype) -> np.ndarray:
    """The numbers of `rows` in order; ValueError where one does not parse."""
    if not rows:
        return np.zeros(0, dtype)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # numpy warns, and stops, at what it cannot parse
        return np.fromstring(b" ".join(rows), dtype=dtype, sep=" ")


def _texture_rows(data: bytes) -> int | None:
    """How many `vt` rows the file has; None where they are not all of 2 or all of 3 numbers
    (trimesh's reading refuses or drops them: its outcome is kept). ValueError where one
    does not parse. They are read though no material here uses them."""
    rows = _VT.findall(data)
    widths = {len(row.split()) for row in rows}
    if len(widths) > 1 or widths - {2, 3}:
        return None
    _numbers(rows, np.float64)
    return len(rows)


def _corners(
    face_rows: list[bytes], face_sizes: list[list[int]], face_object: list[int], n_v: int, n_vn: int, n_vt: int
) -> tuple[np.ndarray, np.ndarray | None, np.ndarray, bool] | None:
    """(triangle corners' vertex indices [T, 3], their normal indices [T, 3] or None, the
    object of each triangle [T], whether the corners name texture coordinates) with 0-based
    indices checked, or None. Per object with faces: its face rows joined, their sizes, its number."""
    per_object = np.array([len(sizes) for sizes in face_sizes], np.int64)
    sizes = np.fromiter((n for group in face_sizes for n in group), np.int64, int(per_object.sum()))
    if sizes.min() < 3:
        return None
    flat = b" ".join(face_rows)
    slashes = flat.count(b"/")
    total = int(sizes.sum())
    if slashes == 0:
        index, normal, uv = _numbers([flat], np.int64), None, False
    elif flat.count(b"//") == total and slashes == 2 * total:  # every corner a//n
        parts = _numbers([flat.replace(b"//", b" ")], np.int64).reshape(-1, 2)
        index, normal, uv = parts[:, 0], parts[:, 1], False
    else:
        pieces = [c.split(b"/") for c in flat.split()]
        widths = {len(p) for p in pieces}
        if widths == {2}:  # a/t: texture coordinates only
            index, normal, uv = np.array([int(p[0]) for p in pieces], np.int64), None, True
        elif widths == {3} and all(p[2] for p in pieces):  # a/t/n (a//n mixed in: trimesh's)
            if not all(p[1] for p in pieces):
                return None
            index = np.array([int(p[0]) for p in pieces], np.int64)
            normal = np.array([int(p[2]) for p in pieces], np.int64)
            uv = True
        else:
            return None
        texture = np.array([int(p[1]) for p in pieces], np.int64)
        if texture.min() < 1 or texture.max() > n_vt:  # trimesh drops such an object's uvs: its colour
            return None
    if len(index) != total or index.min() < 1 or index.max() > n_v:  # relative indices go to trimesh
        return None
    if normal is not None and (normal.min() < 1 or normal.max() > n_vn):
        return None
    index = index.astype(np.int32) - 1  # int32 from here: half the memory of the corner arrays
    normal = None if normal is None else normal.astype(np.int32) - 1
    poly, at = fans(np.cumsum(sizes) - sizes, sizes)
    objects = np.repeat(np.asarray(face_object, np.int32), per_object)[poly]
    return index[at], None if normal is None else normal[at], objects, uv


def _objects(
    names: list[str],
    v: np.ndarray,
    vn: np.ndarray,
    tri: np.ndarray,
    tri_n: np.ndarray | None,
    objects: np.ndarray,
    color: list[float] | None,
) -> list[tuple[int, Decoded]]:
    """Per object its own vertices (each (vertex, normal) pair once, in file order) and faces;
    `objects` [T] is ascending (decode checks it)."""
    corner_object = np.repeat(objects, 3)
    keys = [tri.reshape(-1)] if tri_n is None else [tri_n.reshape(-1), tri.reshape(-1)]
    rank = np.lexsort((*keys, corner_object))  # by object, then vertex (then normal)
    sorted_keys = np.stack([corner_object[rank], *(k[rank] for k in reversed(keys))], axis=1)
    new = np.ones(len(rank), bool)
    new[1:] = (sorted_keys[1:] != sorted_keys[:-1]).any(axis=1)
    unique_id = np.cumsum(new, dtype=np.int32) - 1  # per sorted corner: its distinct (object, vertex[, normal])
    firsts = np.flatnonzero(new)
    distinct_object = sorted_keys[firsts, 0]
    object_start = np.searchsorted(distinct_object, np.arange(len(names) + 1))
    local = np.empty(len(rank), np.int32)
    local[rank] = unique_id - object_start.astype(np.int32)[sorted_keys[:, 0]]
    local = local.reshape(-1, 3)
    positions = v[sorted_keys[firsts, 1]]
    normals = None if tri_n is None else vn[sorted_keys[firsts, 2]].astype(np.float32)
    face_start = np.searchsorted(objects, np.arange(len(names) + 1))
    out = []
    for o in range(len(names)):
        a, b = face_start[o], face_start[o + 1]
        if a == b:
            continue
        lo, hi = object_start[o], object_start[o + 1]
        n = None if normals is None else normals[lo:hi]
        out.append(
            (o, Decoded(positions[lo:hi], local[a:b], n if n is not None and np.isfinite(n).all() else None, color))
        )
    return out
