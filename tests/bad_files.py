"""Builders for the container and reference cases of the bad-input corpus (tests/bad_inputs.py):
3MF archives (zip bombs, component cycles and explosions, entity expansion), OBJ files whose
materials and textures point where they must not, FIFOs and device links."""

from __future__ import annotations

import io
import os
import struct
import zipfile
from pathlib import Path

MODEL = "3D/3dmodel.model"
NS = 'xmlns="http://schemas.microsoft.com/3dmanufacturing/core/2015/02"'
TRIANGLE = (
    '<mesh><vertices><vertex x="0" y="0" z="0"/><vertex x="1" y="0" z="0"/><vertex x="0" y="1" z="0"/>'
    '</vertices><triangles><triangle v1="0" v2="1" v3="2"/></triangles></mesh>'
)


def threemf(model: str | bytes, extra: dict[str, bytes] | None = None, level: int = 6) -> bytes:
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED, compresslevel=level) as z:
        z.writestr(
            "[Content_Types].xml",
            '<?xml version="1.0"?><Types xmlns="http://schemas.openxmlformats.org/package/2006/content-types"/>',
        )
        z.writestr(MODEL, model)
        for name, data in (extra or {}).items():
            z.writestr(name, data)
    return buf.getvalue()


def threemf_bad_deflate() -> bytes:
    """A whole archive whose model member's compressed data is not deflate (a damaged copy)."""
    data = bytearray(threemf_good())
    with zipfile.ZipFile(io.BytesIO(bytes(data))) as z:
        info = z.getinfo(MODEL)
    name_len, extra_len = struct.unpack_from("<HH", data, info.header_offset + 26)
    start = info.header_offset + 30 + name_len + extra_len
    data[start : start + info.compress_size] = b"\xff" * info.compress_size  # reserved block type
    return bytes(data)


def _model(objects: str, items: str) -> str:
    return (
        f'<?xml version="1.0"?><model unit="millimeter" {NS}><resources>{objects}</resources>'
        f"<build>{items}</build></model>"
    )


def threemf_bomb(megabytes: int) -> bytes:
    """A real zip bomb: a model padded with `megabytes` MiB of XML whitespace (a few KiB packed)."""
    pad = b" " * (megabytes * 2**20)
    model = _model(f'<object id="1" type="model">{TRIANGLE}</object>', '<item objectid="1"/>').encode()
    return threemf(model.replace(b"<resources>", b"<resources>" + pad), level=9)


def threemf_declares(gib: float) -> bytes:
    """A small archive whose directory says its model unpacks to `gib` GiB (a forged bomb:
    the sizes a reader would allocate for)."""
    data = bytearray(threemf(_model(f'<object id="1" type="model">{TRIANGLE}</object>', '<item objectid="1"/>')))
    size = int(gib * 2**30) & 0xFFFFFFFF
    name = MODEL.encode()
    for sig, offset in ((b"PK\x01\x02", 24), (b"PK\x03\x04", 22)):  # central and local headers
        at = 0
        while (at := data.find(sig, at)) >= 0:
            name_len = struct.unpack_from("<H", data, at + (28 if sig == b"PK\x01\x02" else 26))[0]
            start = at + (46 if sig == b"PK\x01\x02" else 30)
            if bytes(data[start : start + name_len]) == name:
                struct.pack_into("<I", data, at + offset, size)
            at += 4
    return bytes(data)


def threemf_cycle() -> bytes:
    objects = (
        '<object id="1" type="model"><components><component objectid="2"/></components></object>'
        '<object id="2" type="model"><components><component objectid="1"/></components></object>'
    )
    return threemf(_model(objects, '<item objectid="1"/>'))


def threemf_explosion(levels: int = 30) -> bytes:
    """Object k holds object k+1 twice: 2**levels triangles from a few KiB."""
    objects = "".join(
        f'<object id="{k}" type="model"><components><component objectid="{k + 1}"/>'
        f'<component objectid="{k + 1}"/></components></object>'
        for k in range(1, levels + 1)
    )
    objects += f'<object id="{levels + 1}" type="model">{TRIANGLE}</object>'
    return threemf(_model(objects, '<item objectid="1"/>'))


def threemf_entities() -> bytes:
    """Billion laughs in the model's DTD."""
    dtd = (
        '<!DOCTYPE model [<!ENTITY a "aaaaaaaaaa">'
        + "".join(f'<!ENTITY {chr(98 + i)} "{("&" + chr(97 + i) + ";") * 10}">' for i in range(9))
        + "]>"
    )
    body = _model(f'<object id="1" type="model" name="&j;">{TRIANGLE}</object>', '<item objectid="1"/>')
    return threemf(body.replace("<model", dtd + "<model", 1))


def threemf_good() -> bytes:
    return threemf(_model(f'<object id="1" type="model" name="tri">{TRIANGLE}</object>', '<item objectid="1"/>'))


OBJ_TRI = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n"


def obj_with_material(mtllib: str, texture: str | None = None) -> tuple[str, str]:
    """(OBJ text, MTL text) of a textured triangle using `mtllib` (whose map_Kd is `texture`)."""
    obj = f"mtllib {mtllib}\no tri\n{OBJ_TRI}usemtl red\nf 1/1 2/2 3/3\n"
    mtl = "newmtl red\nKd 0.8 0.1 0.1\n" + (f"map_Kd {texture}\n" if texture else "")
    return obj, mtl


def make_fifo(path: Path) -> bool:
    """A named pipe at `path` (False where the system has none)."""
    if not hasattr(os, "mkfifo"):
        return False
    try:
        os.mkfifo(path)
    except OSError:
        return False
    return True


def make_link(path: Path, target: str) -> bool:
    try:
        os.symlink(target, path)
    except OSError:
        return False
    return True
