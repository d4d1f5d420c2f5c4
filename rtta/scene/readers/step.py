"""STEP assemblies through cascadio (OpenCASCADE's STEP reader and mesher, as trimesh uses).

cascadio gives a GLB in memory (no temporary file) whose nodes keep the assembly tree;
parts carry their product names, but sub-assembly nodes only label ids, so their names
come from the file's own product structure (NEXT_ASSEMBLY_USAGE_OCCURRENCE), matched by the
parts below them. cascadio converts lengths to metres and colours to linear RGB: both are
turned back into what the file meant (its length unit, the sRGB colours the CAD program shows).
"""

from __future__ import annotations

import json
import re
import struct
from collections import Counter
from pathlib import Path

import numpy as np

from ...errors import RttaError
from ...outputs import signals_held
from ..files import PARTS_HINT, max_objects
from . import Assembly, native_output, srgb_from_linear

UNITS_M = {"mm": 1e-3, "cm": 1e-2, "m": 1.0, "km": 1e3, "in": 0.0254, "ft": 0.3048, "um": 1e-6}
SI_PREFIX = {".MILLI.": "mm", ".CENTI.": "cm", "$": "m", ".KILO.": "km", ".MICRO.": "um"}
CONVERTED = {"INCH": "in", "FOOT": "ft", "MILLIMETRE": "mm", "METRE": "m", "CENTIMETRE": "cm"}
GENERIC = re.compile(r"^(=>\[[\d:]*\]|NAUO\d*|)$")
COMPONENTS = {5126: np.float32, 5125: np.uint32, 5123: np.uint16, 5121: np.uint8}
WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}
TOLERANCE = 0.002  # mesher's linear deflection, relative to the edge length


def read(path: Path) -> Assembly:
    data = path.read_bytes()
    text = data.decode("latin-1")
    _check_text(text, path)
    children = _children(text)
    _check_occurrences(children, path)  # before OpenCASCADE expands them
    with signals_held():  # a signal during a native module's initialisation crashes it
        import cascadio

    with native_output() as said:
        glb = cascadio.to_glb_bytes(data, tol_linear=TOLERANCE, tol_relative=True)
    if not glb:
        errors = [line.strip("* ") for line in said if "ERR" in line or "Fail" in line]
        why = errors[0][:120] if errors else "OpenCASCADE found no shapes in it"
        raise RttaError(f"cannot read STEP file ({why})", path)
    unit = length_unit(text)
    out = Assembly(unit=unit, up_axis="z")
    _walk(glb, out, 1.0 / UNITS_M.get(unit, 1.0), _product_names(text, children), path)
    return out


def _check_text(text: str, path: Path) -> None:
    head = text[:4096].lstrip("\ufeff \r\n\t")
    if not head.startswith("ISO-10303-21"):
        raise RttaError("not a STEP file (no 'ISO-10303-21;' header)", path)
    if "END-ISO-10303-21" not in text[-4096:]:
        raise RttaError("STEP file is truncated (no 'END-ISO-10303-21;' at its end)", path)
    for ref in re.findall(r"(?:EXTERNAL_SOURCE|DOCUMENT_FILE)\s*\(\s*'([^']*)'", text):
        name = ref.replace("\\", "/")
        if re.match(r"^[a-zA-Z][a-zA-Z0-9+.-]*:", name) or name.startswith("/") or ".." in name.split("/"):
            raise RttaError(
                f"external reference '{ref}' is outside the file's folder; only the file itself is read", path
            )


def length_unit(text: str) -> str:
    """The length unit of the file's unit contexts (GLOBAL_UNIT_ASSIGNED_CONTEXT), the one
    most of them name ('' when none is found). Units that only define others (the
    millimetre an inch is converted from) do not count."""
    contexts = [
        re.findall(r"#(\d+)", refs) for refs in re.findall(r"GLOBAL_UNIT_ASSIGNED_CONTEXT\s*\(\s*\(([^)]*)\)", text)
    ]
    wanted = {ref for refs in contexts for ref in refs}
    # every unit entity found in one pass over the file: a search per reference scanned the
    # whole text each time (a 2,000-part assembly has a context per part: 31 s of a 40 s read)
    bodies: dict[str, str] = {}
    for m in re.finditer(r"#(\d+)\s*=([^;]*);", text) if wanted else ():
        if m.group(1) in wanted:
            bodies.setdefault(m.group(1), m.group(2))
    found: Counter = Counter()
    for refs in contexts:
        for ref in refs:
            unit = _unit_of(bodies.get(ref, ""))
            if unit:
                found[unit] += 1
    return found.most_common(1)[0][0] if found else ""


def _unit_of(entity: str) -> str:
    """'mm', 'in'... for a length unit entity's text, '' for any other unit."""
    if "LENGTH_UNIT" not in entity:
        return ""
    m = re.search(r"CONVERSION_BASED_UNIT\s*\(\s*'([^']*)'", entity)
    if m:
        return CONVERTED.get(m.group(1).strip().upper(), "")
    m = re.search(r"SI_UNIT\s*\(\s*(\.\w+\.|\$)\s*,\s*\.METRE\.\s*\)", entity)
    return SI_PREFIX.get(m.group(1), "") if m else ""


def _entities(text: str, kind: str) -> dict[int, list[str]]:
    """#id -> its top-level arguments, for every simple entity of one kind."""
    out = {}
    for m in re.finditer(rf"#(\d+)\s*=\s*{kind}\s*\(([^;]*)\)\s*;", text):
        out[int(m.group(1))] = [a.strip() for a in re.split(r",(?![^(]*\))(?=(?:[^']*'[^']*')*[^']*$)", m.group(2))]
    return out


def _ref(a: str) -> int:
    return int(a[1:]) if re.fullmatch(r"#\d{1,18}", a) else -1  # '#', '#x': no reference (fuzzing, issue 42)


def _children(text: str) -> dict[int, list[int]]:
    """The product structure: each product definition's children, one per occurrence
    (NEXT_ASSEMBLY_USAGE_OCCURRENCE: relating, then related)."""
    children: dict[int, list[int]] = {}
    for a in _entities(text, "NEXT_ASSEMBLY_USAGE_OCCURRENCE").values():
        if len(a) > 4:
            children.setdefault(_ref(a[3]), []).append(_ref(a[4]))
    return children


def _check_occurrences(children: dict[int, list[int]], path: Path) -> None:
    """RttaError when the product structure places more parts than a file of its size may make
    (max_objects): a part used ten times in an assembly used ten times in one ... ten levels deep
    is 10^10 parts in a few KB, which OpenCASCADE would expand into memory before anything else."""
    limit = max_objects(path)
    memo: dict[int, int] = {}

    def placed(pd: int, depth: int) -> int:  # leaf occurrences below pd, at most limit + 1
        if pd not in memo:
            kids = children.get(pd, []) if depth <= 64 else []  # a cycle stops here (OpenCASCADE's own check)
            memo[pd] = min(sum(placed(k, depth + 1) for k in kids), limit + 1) if kids else 1
        return memo[pd]

    used = {k for kids in children.values() for k in kids}
    total = sum(placed(root, 0) for root in children if root not in used)
    if total > limit:
        raise RttaError(
            f"STEP product structure places over {limit:,} parts (assemblies used many times over; "
            f"at most {limit:,} for a file of its size; {PARTS_HINT})",
            path,
        )


def _product_names(text: str, children: dict[int, list[int]]) -> dict[tuple, str]:
    """Sub-assembly names by the sorted names of the parts below them (with repeats);
    `children`: the product structure (_children)."""

    def unquote(a: str) -> str:
        return a[1:-1].replace("''", "'") if len(a) >= 2 and a[0] == "'" else ""

    products = {k: unquote(a[1]) or unquote(a[0]) for k, a in _entities(text, "PRODUCT").items() if len(a) > 1}
    formations = {
        **_entities(text, "PRODUCT_DEFINITION_FORMATION"),
        **_entities(text, "PRODUCT_DEFINITION_FORMATION_WITH_SPECIFIED_SOURCE"),
    }
    name_of = {}
    for k, a in _entities(text, "PRODUCT_DEFINITION").items():
        f = formations.get(_ref(a[2])) if len(a) > 2 else None
        name_of[k] = products.get(_ref(f[2]), "") if f and len(f) > 2 else ""
    memo: dict[int, Counter] = {}

    def leaves(pd: int, depth: int = 0) -> Counter:
        if pd not in memo:
            kids = children.get(pd, [])
            found: Counter = Counter()
            if not kids or depth > 64:
                found[name_of.get(pd, "")] = 1
            else:
                for k in kids:
                    found.update(leaves(k, depth + 1))
            memo[pd] = found
        return memo[pd]

    return {_bag(leaves(pd)): name_of[pd] for pd in children if name_of.get(pd)}


def _bag(names: Counter) -> tuple:
    """A multiset of part names as a key: (name, count) pairs, sorted. Counted, not listed:
    a product structure shared level after level names 2^levels parts (a 4 kB file of 24
    levels took 5 s and gigabytes as a sorted list; found while fuzzing, issue 42)."""
    return tuple(sorted(names.items()))


def _walk(glb: bytes, out: Assembly, scale: float, assemblies: dict, path: Path) -> None:
    doc, binary = _split_glb(glb, path)
    nodes, meshes = doc.get("nodes", []), doc.get("meshes", [])
    materials = doc.get("materials", [])
    memo: dict[int, tuple] = {}

    def leaves(i: int) -> tuple:
        if i not in memo:
            n = nodes[i]
            found = Counter([meshes[n["mesh"]].get("name") or n.get("name", "")] if "mesh" in n else [])
            for c in n.get("children", []):
                found.update(dict(leaves(c)))
            memo[i] = _bag(found)
        return memo[i]

    def visit(i: int, parent: np.ndarray, groups: tuple[str, ...]) -> None:
        n = nodes[i]
        m = parent @ _matrix(n)
        name = n.get("name", "")
        if "mesh" in n:
            mesh = meshes[n["mesh"]]
            v, f, mat = _mesh(doc, binary, mesh)
            if len(f):
                world = (v @ m[:3, :3].T + m[:3, 3]) * scale
                color = _color(materials, mat)
                label = mesh.get("name") or ("" if GENERIC.match(name) else name) or "part"
                out.add(label, world, f, color, groups)
        if n.get("children"):
            if GENERIC.match(name):
                name = assemblies.get(leaves(i), "") or f"assembly {len(groups) + 1}"
            for c in n["children"]:
                visit(c, m, (*groups, name))

    for scene in doc.get("scenes", [{}])[:1]:
        for root in scene.get("nodes", []):
            visit(root, np.identity(4), ())


def _split_glb(glb: bytes, path: Path) -> tuple[dict, bytes]:
    try:
        n = struct.unpack_from("<I", glb, 12)[0]
        doc = json.loads(glb[20 : 20 + n])
        binary = glb[28 + n :] if len(glb) > 28 + n else b""
    except (struct.error, ValueError):
        raise RttaError("cannot read STEP file (OpenCASCADE's mesh is unreadable)", path) from None
    return doc, binary


def _matrix(node: dict) -> np.ndarray:
    if "matrix" in node:
        return np.asarray(node["matrix"], np.float64).reshape(4, 4).T
    m = np.identity(4)
    x, y, z, w = node.get("rotation", (0.0, 0.0, 0.0, 1.0))
    m[:3, :3] = [
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ]
    m[:3, :3] *= np.asarray(node.get("scale", (1.0, 1.0, 1.0)))[None, :]
    m[:3, 3] = node.get("translation", (0.0, 0.0, 0.0))
    return m


def _accessor(doc: dict, binary: bytes, i: int) -> np.ndarray:
    a = doc["accessors"][i]
    view = doc["bufferViews"][a["bufferView"]]
    dtype = np.dtype(COMPONENTS[a["componentType"]])
    width, count = WIDTH[a["type"]], a["count"]
    start = view.get("byteOffset", 0) + a.get("byteOffset", 0)
    stride = view.get("byteStride") or dtype.itemsize * width
    raw = np.frombuffer(
        binary, np.uint8, count=(count - 1) * stride + dtype.itemsize * width if count else 0, offset=start
    )
    rows = np.lib.stride_tricks.as_strided(raw, (count, dtype.itemsize * width), (stride, 1))
    return np.ascontiguousarray(rows).view(dtype).reshape(count, width)


def _mesh(doc: dict, binary: bytes, mesh: dict) -> tuple[np.ndarray, np.ndarray, int | None]:
    vs, fs, base, material = [], [], 0, None
    for prim in mesh.get("primitives", []):
        if prim.get("mode", 4) != 4 or "POSITION" not in prim.get("attributes", {}):
            continue
        v = _accessor(doc, binary, prim["attributes"]["POSITION"]).astype(np.float64)
        idx = _accessor(doc, binary, prim["indices"]).reshape(-1) if "indices" in prim else np.arange(len(v))
        vs.append(v)
        fs.append(idx.astype(np.int64)[: len(idx) // 3 * 3].reshape(-1, 3) + base)
        base += len(v)
        material = prim.get("material", material) if material is None else material
    if not vs:
        return np.zeros((0, 3)), np.zeros((0, 3), np.int64), None
    return np.concatenate(vs), np.concatenate(fs), material


def _color(materials: list, i: int | None) -> list[float] | None:
    if i is None or i >= len(materials):
        return None
    factor = materials[i].get("pbrMetallicRoughness", {}).get("baseColorFactor")
    return srgb_from_linear(factor) if factor else None
