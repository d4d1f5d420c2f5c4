"""Generated large assemblies written as GLB, for `rtta bench scale` and the scale tests.

`n` parts, each a box, a cylinder or a sphere (12, 64 and 80 triangles: 52 on average),
each its own mesh with its own node (translation, rotation, non-uniform size) and one of a
few materials, like an exported CAD assembly. The GLB is written directly with numpy (one
buffer, one accessor per part attribute), so a 100,000-part file takes seconds to make.
"""

from __future__ import annotations

import json
import struct
from pathlib import Path

import numpy as np
import trimesh

MATERIALS = (
    (0.80, 0.36, 0.30),
    (0.30, 0.56, 0.80),
    (0.45, 0.72, 0.38),
    (0.86, 0.70, 0.30),
    (0.62, 0.45, 0.78),
    (0.60, 0.60, 0.62),
)


def _bases() -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    shapes = (
        trimesh.creation.box(),
        trimesh.creation.cylinder(radius=0.5, height=1.0, sections=16),
        trimesh.creation.icosphere(subdivisions=1, radius=0.5),
    )
    return [
        (np.asarray(m.vertices, np.float32), np.asarray(m.faces, np.uint32), np.asarray(m.vertex_normals, np.float32))
        for m in shapes
    ]


def _quaternions(rng: np.random.Generator, n: int) -> np.ndarray:
    q = rng.normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def write_assembly(path: str | Path, n: int, seed: int = 0, normals: bool = False) -> Path:
    """Write an `n`-part assembly to `path` (.glb); returns the path. `normals`: with a
    NORMAL attribute per part (as CAD exports usually have; without, the loader smooths)."""
    rng = np.random.default_rng(seed)
    bases = _bases()
    kind = rng.integers(0, len(bases), n)
    side = max(1.0, np.cbrt(n)) * 1.5
    sizes = rng.uniform(0.3, 1.2, (n, 3)).astype(np.float32)
    blobs, accessors, meshes, nodes = [], [], [], []
    offset = 0
    views: list[tuple[int, int]] = []
    per = 3 if normals else 2
    for i in range(n):
        v, f, vn = bases[kind[i]]
        pv = (v * sizes[i]).astype(np.float32)
        arrays = [
            (
                pv,
                {
                    "componentType": 5126,
                    "type": "VEC3",
                    "count": len(pv),
                    "min": pv.min(0).tolist(),
                    "max": pv.max(0).tolist(),
                },
            ),
            (f.reshape(-1), {"componentType": 5125, "type": "SCALAR", "count": f.size}),
        ]
        if normals:
            nn = vn / sizes[i]
            nn = (nn / np.linalg.norm(nn, axis=1, keepdims=True)).astype(np.float32)
            arrays.append((nn, {"componentType": 5126, "type": "VEC3", "count": len(nn)}))
        for data, acc in arrays:
            acc["bufferView"] = len(views)
            views.append((offset, data.nbytes))
            blobs.append(data.tobytes())
            offset += data.nbytes
            accessors.append(acc)
        attributes = {"POSITION": per * i} | ({"NORMAL": per * i + 2} if normals else {})
        meshes.append(
            {
                "primitives": [
                    {"attributes": attributes, "indices": per * i + 1, "material": int(rng.integers(0, len(MATERIALS)))}
                ]
            }
        )
    translation = rng.uniform(-side / 2, side / 2, (n, 3))
    rotation = _quaternions(rng, n)
    buffer_views = [{"buffer": 0, "byteOffset": off, "byteLength": length} for off, length in views]
    for i in range(n):
        nodes.append(
            {
                "name": f"part{i:06d}",
                "mesh": i,
                "translation": translation[i].tolist(),
                "rotation": rotation[i].tolist(),
            }
        )
    doc = {
        "asset": {"version": "2.0", "generator": "rtta assembly"},
        "scene": 0,
        "scenes": [{"nodes": list(range(n))}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [*c, 1.0]}} for c in MATERIALS],
        "accessors": accessors,
        "bufferViews": buffer_views,
        "buffers": [{"byteLength": offset}],
    }
    return _write_glb(Path(path), doc, b"".join(blobs))


def _write_glb(path: Path, doc: dict, binary: bytes) -> Path:
    text = json.dumps(doc, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    binary += b"\0" * (-len(binary) % 4)
    total = 12 + 8 + len(text) + 8 + len(binary)
    with open(path, "wb") as out:
        out.write(struct.pack("<III", 0x46546C67, 2, total))
        out.write(struct.pack("<II", len(text), 0x4E4F534A) + text)
        out.write(struct.pack("<II", len(binary), 0x004E4942) + binary)
    return path
