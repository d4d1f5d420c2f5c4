"""glTF's KHR_draco_mesh_compression through DracoPy (the `draco` extra): every drawn
compressed primitive is decoded once into plain accessors, so that both glTF readers take it
as an uncompressed one.

The decoder is native code, and a damaged or hostile buffer could crash it or exhaust
memory: it runs in a child process (formats.isolated), which turns a crash or a timeout
into one error. A decoded primitive may not hold more vertices or indices than the file
declares for it (the memory checks were made on those counts)."""

from __future__ import annotations

import importlib.util
import pickle
import tempfile
from pathlib import Path

import numpy as np

from ...errors import RttaError, reason
from ..files import memory_limit
from .gltf_check import TYPE_WIDTH
from .gltf_read import append_accessor, view_bytes

EXTENSION = "KHR_draco_mesh_compression"
ATTRIBUTES = ("POSITION", "NORMAL", "TEXCOORD_0", "COLOR_0")


def available() -> bool:
    return importlib.util.find_spec("DracoPy") is not None


def decompress(doc: dict, pairs: list[tuple[int, int]], buffers: list[bytes], path: Path) -> None:
    """Decode the compressed ones of the drawn (mesh, primitive) `pairs` in place: new
    buffers, views and accessors for their attributes and indices, the extension removed."""
    found = [(m, p, _extension(doc, m, p, path)) for m, p in pairs]
    found = [(m, p, ext) for m, p, ext in found if ext is not None]
    if not found:
        return
    views = sorted({ext["bufferView"] for _, _, ext in found})
    decoded = dict(zip(views, _decode([view_bytes(doc, buffers, v) for v in views], path), strict=True))
    for m, p, ext in found:
        prim = doc["meshes"][m]["primitives"][p]
        _replace(doc, buffers, prim, ext, decoded[ext["bufferView"]], f"meshes[{m}].primitives[{p}]", path)
        del prim["extensions"][EXTENSION]
        if not prim["extensions"]:
            del prim["extensions"]


def _extension(doc: dict, m: int, p: int, path: Path) -> dict | None:
    prim = doc["meshes"][m]["primitives"][p]
    extensions = prim.get("extensions")
    if not isinstance(extensions, dict) or EXTENSION not in extensions:
        return None
    where = f"glTF meshes[{m}].primitives[{p}].extensions.{EXTENSION}"
    ext = extensions[EXTENSION]
    views = len(doc.get("bufferViews", []))
    if not isinstance(ext, dict) or type(ext.get("bufferView")) is not int or not 0 <= ext["bufferView"] < views:
        raise RttaError(f"{where} needs a 'bufferView' index below {views}", path)
    names = ext.get("attributes")
    if not isinstance(names, dict) or not all(type(v) is int and 0 <= v < 2**31 for v in names.values()):
        raise RttaError(f"{where}.attributes must map attribute names to Draco ids", path)
    if "POSITION" not in names:
        raise RttaError(f"{where}.attributes has no POSITION", path)
    if prim.get("mode", 4) != 4:
        raise RttaError(f"{where}: a compressed primitive must be a triangle list", path)
    return ext


def _decode(blobs: list[bytes], path: Path) -> list[dict]:
    """The blobs decoded by read() in a child process."""
    from . import isolated

    with tempfile.TemporaryDirectory(prefix="rtta-draco-") as tmp:
        job = Path(tmp) / "draco.pickle"
        job.write_bytes(pickle.dumps(blobs, protocol=5))
        try:
            return isolated.read("rtta.scene.readers.draco", job, "Draco")
        except RttaError as exc:  # named the job: name the user's file
            raise RttaError(exc.message, path) from None


def read(path: Path) -> list[dict]:
    """Child side: each pickled blob decoded to {'faces': uint32 [F, 3], 'attributes':
    {Draco id: array [V, k]}}. The child's address space is capped at the memory limit plus
    1 GiB, so a blob that claims a huge mesh fails here instead of exhausting the machine."""
    import resource

    import DracoPy

    hard = resource.getrlimit(resource.RLIMIT_AS)[1]
    cap = memory_limit() + (1 << 30)
    resource.setrlimit(resource.RLIMIT_AS, (cap if hard == resource.RLIM_INFINITY else min(cap, hard), hard))

    out = []
    for i, blob in enumerate(pickle.loads(path.read_bytes())):
        try:
            mesh = DracoPy.decode(blob)
            faces = np.asarray(mesh.faces, np.uint32).reshape(-1, 3)
            attributes = {int(a["unique_id"]): np.asarray(a["data"]) for a in mesh.attributes}
        except MemoryError:
            raise
        except Exception as exc:
            raise RttaError(f"its Draco-compressed geometry {i} cannot be decoded ({reason(exc, 120)})", path) from None
        out.append({"faces": faces, "attributes": attributes})
    return out


def _replace(doc: dict, buffers: list[bytes], prim: dict, ext: dict, decoded: dict, where: str, path: Path) -> None:
    """Point the primitive's attributes and indices at new accessors holding the decoded data."""
    accessors = doc["accessors"]
    attrs = prim["attributes"]
    for name, uid in ext["attributes"].items():
        if name not in ATTRIBUTES or name not in attrs:
            continue
        data = decoded["attributes"].get(uid)
        declared = accessors[attrs[name]]
        if data is None:
            raise RttaError(f"glTF {where}: its Draco data has no attribute {uid} ({name})", path)
        data = np.asarray(data).reshape(len(data), -1)
        if name == "COLOR_0" and data.dtype.kind in "ui":
            data = data / float(np.iinfo(data.dtype).max)
        width = TYPE_WIDTH[declared["type"]]
        if data.shape[1] != width or len(data) > declared["count"]:
            raise RttaError(
                f"glTF {where}: its Draco data decodes {name} to {len(data):,} values of "
                f"{data.shape[1]}, where the file declares {declared['count']:,} of {width}",
                path,
            )
        attrs[name] = append_accessor(doc, buffers, data.astype(np.float32), declared["type"])
    vertices = accessors[attrs["POSITION"]]["count"]
    if vertices < 1:
        raise RttaError(f"glTF {where}: its Draco data decodes to no vertices", path)
    faces = decoded["faces"].reshape(-1)
    if not len(faces):  # a point cloud: one flat triangle, which the loader leaves out
        faces = np.zeros(3, np.uint32)
    if "indices" in prim and len(faces) > accessors[prim["indices"]]["count"]:
        raise RttaError(
            f"glTF {where}: its Draco data decodes to {len(faces):,} indices, where the file "
            f"declares {accessors[prim['indices']]['count']:,}",
            path,
        )
    if int(faces.max()) >= vertices:
        raise RttaError(f"glTF {where}: its Draco data has indices beyond its {vertices:,} vertices", path)
    prim["indices"] = append_accessor(doc, buffers, faces.astype(np.uint32), "SCALAR")
