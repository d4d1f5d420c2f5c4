"""A glTF file's container: the JSON document of a .gltf, or a GLB's JSON and binary chunks,
their header and lengths checked; one RttaError for a file that is not what it says.

`read_document(path)` returns the JSON object and the GLB's binary chunk (None if none).
"""

from __future__ import annotations

import json
import struct
from pathlib import Path

from ...errors import RttaError

GLB_JSON, GLB_BIN = 0x4E4F534A, 0x004E4942


def read_document(path: Path) -> tuple[dict, bytes | None]:
    """(JSON object, binary chunk or None) of a .gltf or .glb file."""
    if path.suffix.lower() == ".gltf":
        return decode(path.read_bytes(), path, "glTF JSON"), None
    data = path.read_bytes()
    if data[:4] != b"glTF":
        raise RttaError("not a GLB file (no 'glTF' header)", path)
    if len(data) < 20:
        raise RttaError(f"GLB file is truncated ({len(data)} bytes; the header alone is 20)", path)
    _, version, total, length, kind = struct.unpack_from("<4sIIII", data)
    if version != 2:
        raise RttaError(f"GLB version {version} is not supported (only 2)", path)
    if total > len(data) or 20 + length > len(data):
        raise RttaError(f"GLB file is truncated (header says {total:,} bytes, file has {len(data):,})", path)
    if kind != GLB_JSON:
        raise RttaError("GLB file's first chunk is not JSON", path)
    doc = decode(data[20 : 20 + length], path, "GLB JSON chunk")
    start = 20 + length
    if start + 8 > min(total, len(data)):
        return doc, None
    blen, bkind = struct.unpack_from("<II", data, start)
    if bkind != GLB_BIN:
        return doc, None
    if start + 8 + blen > len(data):
        raise RttaError(f"GLB binary chunk is truncated (says {blen:,} bytes, {len(data) - start - 8:,} remain)", path)
    return doc, data[start + 8 : start + 8 + blen]


def decode(raw: bytes, path: Path, what: str) -> dict:
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise RttaError(f"{what} is not valid UTF-8 (byte {exc.start})", path) from None
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as exc:
        raise RttaError(
            f"{what} is not valid JSON ({exc.msg} at line {exc.lineno}, column {exc.colno})", path
        ) from None
    except RecursionError:
        raise RttaError(f"{what} is nested too deeply", path) from None
    except ValueError as exc:  # e.g. an integer of more than 4,300 digits
        raise RttaError(f"{what} is not valid JSON ({str(exc)[:100]})", path) from None
    if not isinstance(doc, dict):
        raise RttaError(f"{what} is not a JSON object", path)
    return doc
