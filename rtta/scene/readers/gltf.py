"""glTF/GLB scenes: the node graph is walked by rtta, not by trimesh, so objects are named in
file order (never with trimesh's random suffixes), cycles and absurd depths are errors
rather than hangs, and nothing is dropped without a word.

`prepare(path)` reads the file (rtta.scene.readers.gltf_document), checks the document
(gltf_check), its buffers and base-colour images, walks the graph of the chosen scene
(gltf_graph: iteratively, no recursion however deep; a node of singular transform hidden
with a warning), and keeps the drawn (mesh, primitive) pairs. A plain file's primitives are then read
directly (rtta.scene.readers.gltf_read); any other is rewritten for trimesh as one single-primitive
mesh per pair, one node each and no hierarchy, so trimesh only decodes geometry and
textures. The world transform and the name of every object come from the walk.
"""

from __future__ import annotations

import base64
import binascii
import io
import json
import struct
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ...errors import RttaError
from ..files import PARTS_HINT, TextureBudget, image_problem, local_file, max_objects, memory_limit, read_limited
from ..precheck import check_size
from . import draco, gltf_graph
from .gltf_check import COMPONENT_BYTES, FLOAT, TYPE_WIDTH, check
from .gltf_document import read_document
from .gltf_read import (
    Decoded,
    accessor_array,
    append_view,
    decode,
    densify_sparse,
    extension,
    transform_texcoords,
    view_bytes,
)
from .gltf_rewrite import fan_indices, geometry_name, rewrite

BUFFER_COPIES = 4  # the file, the rewritten blob, trimesh's slices of it, the GLB it reads


@dataclass
class Instance:
    """One object: a primitive of a mesh at the end of one path through the node graph."""

    name: str
    geometry: str  # the mesh name trimesh gives the rewritten single-primitive mesh
    matrix: np.ndarray  # float64 [4, 4] world transform
    path: tuple[str, ...] = ()  # the groups above it in the node tree, root first


@dataclass
class Prepared:
    instances: list[Instance]
    warnings: list[str] = field(default_factory=list)
    inputs: list[Path] = field(default_factory=list)  # files it refers to
    doc: dict = field(default_factory=dict)  # the checked document
    pairs: list[tuple[int, int]] = field(default_factory=list)  # drawn (mesh, primitive), file order
    buffers: list[bytes] = field(default_factory=list)
    images: dict[int, bytes] = field(default_factory=dict)  # usable base-colour images

    def decoded(self) -> dict[str, Decoded] | None:
        """Every drawn primitive read directly (rtta.scene.readers.gltf_read), keyed like
        Instance.geometry; None when the file needs trimesh."""
        found = decode(self.doc, self.pairs, self.buffers)
        return None if found is None else {geometry_name(m, p): d for (m, p), d in found.items()}

    def for_trimesh(self) -> bytes:
        """The rewritten, self-contained GLB trimesh reads (rtta.scene.readers.gltf_rewrite)."""
        new, blob = rewrite(self.doc, self.pairs, self.buffers, self.images)
        text = json.dumps(new, allow_nan=False).encode()
        text += b" " * (-len(text) % 4)
        return (
            struct.pack("<4sIII", b"glTF", 2, 28 + len(text) + len(blob), len(text))
            + b"JSON"
            + text
            + struct.pack("<I", len(blob))
            + b"BIN\0"
            + blob
        )


def prepare(path: Path) -> Prepared:
    doc, binary = read_document(path)
    _specular_glossiness(doc)
    _webp_sources(doc)
    check(doc, path, None if binary is None else len(binary))
    out = Prepared([], doc=doc)
    _check_extensions(doc, path)
    out.buffers = _buffers(doc, binary, path, out)
    _check_memory(doc, out.buffers, path)
    try:
        densify_sparse(doc, out.buffers)
    except ValueError as exc:
        raise RttaError(f"glTF {exc}", path) from None
    limit = max_objects(path, sum(target.stat().st_size for target in out.inputs))  # buffer files so far
    walk = gltf_graph.walk(doc, path, out.warnings, limit)
    out.pairs = _primitives(doc, walk, out.buffers, path, out.warnings)
    if draco.available():
        draco.decompress(doc, out.pairs, out.buffers, path)
    transform_texcoords(doc, out.pairs, out.buffers, out.warnings)
    out.images = _images(doc, out.buffers, path, out)
    _colors(doc, out.warnings)
    _vertex_colors(doc, out.pairs, out.buffers, out.warnings)
    per_mesh: dict[int, list[int]] = {}
    for m, p in out.pairs:
        per_mesh.setdefault(m, []).append(p)
    out.instances = [
        Instance(
            name,
            geometry_name(mesh, p),
            matrix,  # a node's primitives: a group of its own
            (*tree, name.replace("/", "\u2215")) if len(per_mesh[mesh]) > 1 else tree,
        )
        for name, mesh, matrix, tree in walk
        for p in per_mesh.get(mesh, [])
    ]
    if len(out.instances) > limit:
        raise RttaError(
            f"the node graph makes {len(out.instances):,} objects (at most {limit:,} for a file of its size; "
            f"{PARTS_HINT})",
            path,
        )
    _check_size(doc, walk, out.pairs, path)
    return out


def _check_extensions(doc: dict, path: Path) -> None:
    required = set(doc.get("extensionsRequired", []))
    for name in sorted(required & {"KHR_draco_mesh_compression", "EXT_meshopt_compression"}):
        if name == draco.EXTENSION and draco.available():
            continue
        how = "; `pip install rtta[draco]` adds it" if name == draco.EXTENSION else ""
        raise RttaError(f"needs the glTF extension {name}, which rtta cannot decode here{how}", path)


def _buffers(doc: dict, binary: bytes | None, path: Path, out: Prepared) -> list[bytes]:
    """The bytes of every buffer; an error for a buffer that is a URL, outside the folder,
    missing, not a regular file or shorter than it says."""
    data: list[bytes] = []
    for i, buf in enumerate(doc.get("buffers", [])):
        uri = buf.get("uri")
        if uri is None:
            raw = binary or b""
        elif uri.startswith("data:"):
            raw = _data_uri(uri, path, f"buffers[{i}]")
        else:
            target = local_file(uri, path, "buffer")
            raw = read_limited(target, path, f"buffer file '{uri}'")
            out.inputs.append(target)
        if len(raw) < buf["byteLength"]:
            raise RttaError(f"buffer {i} has {len(raw):,} bytes, but its byteLength says {buf['byteLength']:,}", path)
        data.append(raw)
    return data


def _data_uri(uri: str, path: Path, where: str) -> bytes:
    head, _, body = uri.partition(",")
    if not head.endswith(";base64"):
        raise RttaError(f"glTF {where} is a data: URI that is not base64", path)
    if len(body) * 3 // 4 > memory_limit():
        raise RttaError(f"glTF {where} is a data: URI larger than the memory limit", path)
    try:
        return base64.b64decode(body, validate=False)
    except (binascii.Error, ValueError):
        raise RttaError(f"glTF {where} is a data: URI that is not valid base64", path) from None


def _check_memory(doc: dict, buffers: list[bytes], path: Path) -> None:
    """Accessors without a bufferView become arrays of zeros, sparse ones dense copies: their
    sizes count too; and the buffers are held about BUFFER_COPIES times while trimesh reads them."""
    zeros = sum(
        a["count"] * COMPONENT_BYTES[a["componentType"]] * TYPE_WIDTH[a["type"]]
        for a in doc.get("accessors", [])
        if "bufferView" not in a or "sparse" in a
    )
    need = zeros + BUFFER_COPIES * sum(len(b) for b in buffers)
    if need > memory_limit():
        raise RttaError(
            f"reading the file's buffers and accessors needs about {need / 2**20:,.0f} MiB, over "
            f"the memory limit of {memory_limit() / 2**20:,.0f} MiB (RTTA_MEMORY_LIMIT_MB)",
            path,
        )


def _check_size(doc: dict, walk: list, pairs: list, path: Path) -> None:
    """The vertices and triangles the drawn primitives declare, every instance counted."""
    uses: dict[int, int] = {}
    for _, mesh, _, _ in walk:
        uses[mesh] = uses.get(mesh, 0) + 1
    accessors, vertices, triangles = doc.get("accessors", []), 0, 0
    for m, p in pairs:
        prim = doc["meshes"][m]["primitives"][p]
        v = accessors[prim["attributes"]["POSITION"]]["count"]
        n = accessors[prim["indices"]]["count"] if "indices" in prim else v
        vertices += v * uses[m]
        triangles += (n // 3 if prim.get("mode", 4) == 4 else max(n - 2, 0)) * uses[m]
    check_size(vertices, triangles, path, "the file declares")


def _primitives(doc: dict, walk: list, buffers: list, path: Path, warnings: list[str]) -> list[tuple[int, int]]:
    """(mesh, primitive) pairs that are drawn, in file order; a triangle fan gets its
    triangle-list indices (prim["_fan"]); points and lines are left out with a warning."""
    used = sorted({mesh for _, mesh, _, _ in walk})
    meshes = doc.get("meshes", [])
    pairs, skipped = [], {}
    for m in used:
        for p, prim in enumerate(meshes[m]["primitives"]):
            mode = prim.get("mode", 4)
            if mode == 6:
                prim["_fan"] = fan_indices(doc, prim, buffers)
            if mode in (4, 5, 6):
                pairs.append((m, p))
            else:
                kind = "points" if mode == 0 else "lines"
                skipped[kind] = skipped.get(kind, 0) + 1
    for kind, n in skipped.items():
        warnings.append(f"{n} primitive(s) of {kind} left out (only surfaces are drawn)")
    return pairs


def _images(doc: dict, buffers: list, path: Path, out: Prepared) -> dict[int, bytes]:
    """The bytes of every base-colour image that can be used. A missing, unreadable, corrupt
    or oversized one (file, data: URI or embedded) is a warning and is left out, so its
    objects keep their material colour; trimesh never opens a file itself."""
    images, textures = doc.get("images", []), doc.get("textures", [])
    used = sorted({textures[t]["source"] for t in _base_textures(doc) if "source" in textures[t]})
    for t in sorted({t for t in _base_textures(doc) if "source" not in textures[t]}):
        found = textures[t].get("extensions")
        found = found if isinstance(found, dict) else {}
        kinds = sorted(k for k, v in found.items() if isinstance(v, dict) and "source" in v)
        if kinds:  # KHR_texture_basisu (KTX2), MSFT_texture_dds: images that Pillow cannot decode
            out.warnings.append(
                f"texture {t} has only {', '.join(kinds)} images, which rtta cannot decode; objects using it "
                "keep their material colour"
            )
    good, budget = {}, TextureBudget()
    for i in used:
        image = images[i]
        uri = image.get("uri")
        label = uri if uri is not None and not uri.startswith("data:") else f"images[{i}] (embedded)"
        try:
            if uri is None and "bufferView" in image:
                blob = view_bytes(doc, buffers, image["bufferView"])
            elif uri is not None and uri.startswith("data:"):
                blob = _data_uri(uri, path, f"images[{i}]")
            elif uri is not None:
                try:
                    target = local_file(uri, path, "texture")
                except RttaError as exc:
                    out.warnings.append(f"{exc.message}; objects using it keep their material colour")
                    continue
                out.inputs.append(target)
                blob = read_limited(target, path, "")
            else:
                raise RttaError("has neither a uri nor a bufferView")
            problem = image_problem(io.BytesIO(blob), budget)
            if problem:
                raise RttaError(problem)
            good[i] = blob
        except RttaError as exc:
            out.warnings.append(f"texture '{label}' {exc.message.strip()}; objects using it keep their material colour")
    return good


def _specular_glossiness(doc: dict) -> None:
    """KHR_materials_pbrSpecularGlossiness (older exporters' materials): its diffuse factor
    and texture stand for the base colour, as the extension says they replace the
    metallic-roughness ones; checked afterwards like any base colour."""
    materials = doc.get("materials")
    for mat in materials if isinstance(materials, list) else ():
        ext = extension(mat, "KHR_materials_pbrSpecularGlossiness")
        if not isinstance(ext, dict) or not isinstance(mat.setdefault("pbrMetallicRoughness", {}), dict):
            continue
        pbr = mat["pbrMetallicRoughness"]
        pbr["baseColorFactor"] = ext.get("diffuseFactor", [1.0, 1.0, 1.0, 1.0])
        pbr.pop("baseColorTexture", None)
        if "diffuseTexture" in ext:
            pbr["baseColorTexture"] = ext["diffuseTexture"]


def _webp_sources(doc: dict) -> None:
    """A texture whose only image is EXT_texture_webp's takes it as its source (Pillow reads
    WebP); checked afterwards like any source."""
    textures = doc.get("textures")
    for tex in textures if isinstance(textures, list) else ():
        webp = extension(tex, "EXT_texture_webp")
        if isinstance(webp, dict) and "source" in webp and "source" not in tex:
            tex["source"] = webp["source"]


def _base_textures(doc: dict) -> list[int]:
    out = []
    for mat in doc.get("materials", []):
        tex = mat.get("pbrMetallicRoughness", {}).get("baseColorTexture")
        if tex is not None:
            out.append(tex["index"])
    return out


DRAWN_AS = "(NaN and infinite components drawn as 1, the rest clamped)"


def _drawable(values) -> np.ndarray:
    """Colour components as drawn: NaN or infinite ones 1 (glTF's default factor), the rest
    clamped to [0, 1]."""
    v = np.asarray(values, np.float64)
    return np.where(np.isfinite(v), np.clip(v, 0.0, 1.0), 1.0)


def _colors(doc: dict, warnings: list[str]) -> None:
    """Base colour factors made drawable (`_drawable`); each change is said once."""
    fixed = []
    for i, mat in enumerate(doc.get("materials", [])):
        pbr = mat.get("pbrMetallicRoughness", {})
        factor = pbr.get("baseColorFactor")
        if factor is None:
            continue
        clean = _drawable(factor).tolist()
        if clean != factor:
            fixed.append(mat.get("name") or f"materials[{i}]")
            pbr["baseColorFactor"] = clean
    if fixed:
        warnings.append(
            f"{len(fixed)} material(s) with a baseColorFactor that is NaN, infinite or outside [0, 1] "
            f"{DRAWN_AS}: " + ", ".join(fixed[:5])
        )


def _vertex_colors(doc: dict, pairs: list, buffers: list[bytes], warnings: list[str]) -> None:
    """Float COLOR_0 made drawable as base colour factors are (`_drawable`), into an accessor
    of its own; trimesh would cast NaN to 0, a black, transparent object. Said once."""
    fixed = set()
    for m, p in pairs:
        i = doc["meshes"][m]["primitives"][p]["attributes"].get("COLOR_0")
        if i is None or i in fixed:
            continue
        acc = doc["accessors"][i]
        if acc["componentType"] != FLOAT or "bufferView" not in acc:
            continue
        colors = accessor_array(doc, i, buffers)
        clean = _drawable(colors)
        if np.array_equal(clean, colors):
            continue
        acc["bufferView"], acc["byteOffset"] = append_view(doc, buffers, clean.astype(np.float32).tobytes()), 0
        fixed.add(i)
    if fixed:
        warnings.append(
            f"{len(fixed)} vertex colour accessor(s) with values that are NaN, infinite or outside [0, 1] "
            f"{DRAWN_AS}: accessors " + ", ".join(map(str, sorted(fixed)[:5]))
        )
