"""The glTF document trimesh reads (rtta.scene.readers.gltf writes it): self-contained and flat,
so trimesh decodes geometry and textures and nothing else. Every buffer, the triangle-list
indices of fans and every usable image lie in one binary chunk; one mesh of one primitive
per drawn (mesh, primitive), one node each, no hierarchy, no cameras, skins or animations;
materials reduced to base colour and texture.
"""

from __future__ import annotations

import numpy as np

from .gltf_read import accessor_array


def geometry_name(mesh: int, primitive: int) -> str:
    """The name of a drawn (mesh, primitive) in the rewritten document: trimesh's geometry
    key, and the key of the direct reader's records (rtta.scene.readers.gltf)."""
    return f"rtta.{mesh}.{primitive}"


def fan_indices(doc: dict, prim: dict, buffers: list) -> np.ndarray:
    """A triangle fan's indices as a triangle list (uint32)."""
    if "indices" in prim:
        fan = read_indices(doc, prim["indices"], buffers)
    else:
        fan = np.arange(doc["accessors"][prim["attributes"]["POSITION"]]["count"], dtype=np.uint32)
    if len(fan) < 3:
        return np.zeros(0, np.uint32)
    k = np.arange(1, len(fan) - 1)
    return np.stack([np.full(len(k), fan[0]), fan[k], fan[k + 1]], axis=1).astype(np.uint32).reshape(-1)


def read_indices(doc: dict, index: int, buffers: list) -> np.ndarray:
    return accessor_array(doc, index, buffers).reshape(-1).astype(np.uint32)


def rewrite(doc: dict, pairs: list, buffers: list[bytes], images: dict[int, bytes]) -> tuple[dict, bytes]:
    """The self-contained document trimesh reads, and its binary chunk: every buffer, fan
    index and used image in one blob; one mesh of one primitive per drawn (mesh, primitive),
    one node each, flat; materials reduced to base colour and texture."""
    blob, base = bytearray(), []
    for data in buffers:
        base.append(len(blob))
        blob += data
        blob += b"\0" * (-len(blob) % 4)
    views = [
        {
            "buffer": 0,
            "byteOffset": base[v["buffer"]] + v.get("byteOffset", 0),
            "byteLength": v["byteLength"],
            **({"byteStride": v["byteStride"]} if "byteStride" in v else {}),
        }
        for v in doc.get("bufferViews", [])
    ]
    accessors = [
        {k: a[k] for k in ("bufferView", "byteOffset", "componentType", "count", "type") if k in a}
        | ({"normalized": a["normalized"]} if type(a.get("normalized")) is bool else {})
        for a in doc.get("accessors", [])
    ]

    def append(data: bytes) -> int:
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(data)})
        blob.extend(data)
        blob.extend(b"\0" * (-len(blob) % 4))
        return len(views) - 1

    meshes = []
    for m, p in pairs:
        prim = doc["meshes"][m]["primitives"][p]
        new = {
            "attributes": {
                k: v for k, v in prim["attributes"].items() if k in ("POSITION", "NORMAL", "TEXCOORD_0", "COLOR_0")
            },
            "mode": prim.get("mode", 4),
        }
        new.update({k: prim[k] for k in ("indices", "material") if k in prim})
        if "_fan" in prim:
            fan = prim["_fan"]
            new["mode"] = 4
            new["indices"] = len(accessors)
            accessors.append(
                {"bufferView": append(fan.tobytes()), "componentType": 5125, "count": len(fan), "type": "SCALAR"}
                if len(fan)
                else {"componentType": 5125, "count": 3, "type": "SCALAR"}
            )
        meshes.append({"name": geometry_name(m, p), "primitives": [new]})
    new_images = [
        {"bufferView": append(images[i]), "mimeType": "image/png"} if i in images else {}
        for i in range(len(doc.get("images", [])))
    ]
    materials = [
        {"pbrMetallicRoughness": _base_color(mat.get("pbrMetallicRoughness", {}))} for mat in doc.get("materials", [])
    ]
    textures = [{"source": t["source"]} if "source" in t else {} for t in doc.get("textures", [])]
    new_doc = {
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": len(blob)}],
        "bufferViews": views,
        "accessors": accessors,
        "meshes": meshes,
        "materials": materials,
        "textures": textures,
        "images": new_images,
        "nodes": [{"mesh": j, "name": f"rtta.{j}"} for j in range(len(meshes))],
        "scenes": [{"nodes": list(range(len(meshes)))}],
        "scene": 0,
    }
    return new_doc, bytes(blob)


def _base_color(pbr: dict) -> dict:
    """The checked base colour of a material: the factor and the texture's index alone (fields
    rtta does not read, such as a texture's extensions, may hold NaN, which the rewritten JSON
    cannot)."""
    out = {"baseColorFactor": pbr["baseColorFactor"]} if "baseColorFactor" in pbr else {}
    if "baseColorTexture" in pbr:
        out["baseColorTexture"] = {"index": pbr["baseColorTexture"]["index"]}
    return out
