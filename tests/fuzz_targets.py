"""Fuzz targets for the parsers rtta wrote itself (issue 42): each takes one input (bytes) and
either gives a result or raises RttaError; anything else, more than LIMIT_S seconds or more
than MEMORY_MB of memory is a finding. scripts/fuzz.py runs a target under atheris
(coverage-guided, in a subprocess); tests/test_fuzz.py runs each briefly and
deterministically (every seed of tests/fuzz_corpus/<target>/, then mutants of a fixed seed).

Targets: obj (OBJ through the loader: obj_objects, obj_read's direct reading, its material
skeleton), gltf (a .glb or .gltf through the loader: the container, the JSON checks, the node
graph walk, the direct read and the rewrite for trimesh), step (the STEP text scans: header,
external references, length unit, product names), ifc (the spatial tree walk and its memo,
on element graphs built from the input), specs (the camera, size, colour, opacity, lens and
name specs of rtta.renderer and the CLI, section planes), views (a saved view file and a
dataset's cameras file), cache (a scene cache entry and its side file, read back by the
loader: tests/fuzz_cache.py).
"""

from __future__ import annotations

import json
import random
import tempfile
from collections.abc import Callable, Iterator
from pathlib import Path

from rtta.errors import RttaError

LIMIT_S = 2.0  # seconds one input may take
MEMORY_MB = 2048  # the fuzzing process's resident memory (libFuzzer's -rss_limit_mb)
INPUT_MB = 256  # what one input may allocate (traced) in the test's smoke run
MAX_LEN = 1 << 16  # bytes of one fuzzed input
LOADER_LIMIT_MB = "512"  # RTTA_MEMORY_LIMIT_MB while fuzzing: the loader's limits bite early (set by the
# fuzzing process and by test_fuzz for its tests, never at import: it would leak into the whole test session)
CORPUS = Path(__file__).resolve().parent / "fuzz_corpus"
_WORK = Path(tempfile.mkdtemp(prefix="rtta-fuzz-"))


def _file(data: bytes, name: str) -> Path:
    path = _WORK / name
    path.write_bytes(data)
    return path


def fuzz_obj(data: bytes) -> None:
    from rtta.scene.loader import load_scene

    load_scene(_file(data, "input.obj"))


def fuzz_gltf(data: bytes) -> None:
    from rtta.scene.loader import load_scene

    load_scene(_file(data, "input.glb" if data[:4] == b"glTF" else "input.gltf"))


def fuzz_step(data: bytes) -> None:
    from rtta.scene.readers import step

    text = data.decode("latin-1")
    try:
        step._check_text(text, Path("input.step"))
    except RttaError:
        pass  # the scans below run on what passed and what did not alike
    step.length_unit(text)
    children = step._children(text)
    step._product_names(text, children)
    try:
        step._check_occurrences(children, Path("input.step"))
    except RttaError:
        pass


IFC_TYPES = (
    "IfcProject",
    "IfcSite",
    "IfcBuilding",
    "IfcBuildingStorey",
    "IfcWall",
    "IfcWindow",
    "IfcOpeningElement",
    "IfcElementAssembly",
    "IfcBeam",
)


def fuzz_ifc(data: bytes) -> None:
    """An IFC element graph from the input (elements, aggregation, containment, openings and
    fillings, cycles and shared parents included); every element's tree_path with the shared
    memo must equal its path walked alone (the memo only saves time)."""
    import ifcopenshell

    from rtta.scene.readers.ifc import tree_path

    model = ifcopenshell.file(schema="IFC4")
    stream = iter(data)
    n = 1 + next(stream, 0) % 12
    names = [None, "", "A", "A/B", "\u2215", "x" * 40]
    elements = [
        model.create_entity(IFC_TYPES[next(stream, 0) % len(IFC_TYPES)], Name=names[next(stream, 0) % len(names)])
        for _ in range(n)
    ]
    for op in stream:
        a, b = elements[next(stream, 0) % n], elements[next(stream, 0) % n]
        kind = op % 4
        if kind == 0:
            model.create_entity("IfcRelAggregates", RelatingObject=a, RelatedObjects=[b])
        elif kind == 1:
            model.create_entity("IfcRelContainedInSpatialStructure", RelatingStructure=a, RelatedElements=[b])
        elif kind == 2 and a.is_a("IfcOpeningElement"):
            model.create_entity("IfcRelFillsElement", RelatingOpeningElement=a, RelatedBuildingElement=b)
        elif kind == 2:
            model.create_entity("IfcRelVoidsElement", RelatingBuildingElement=a, RelatedOpeningElement=b)
        else:
            model.create_entity("IfcRelNests", RelatingObject=a, RelatedObjects=[b])
    memo: dict = {}
    order = list(elements)
    random.Random(len(data)).shuffle(order)
    for element in order:
        shared, alone = tree_path(element, memo), tree_path(element, {})
        if shared != alone:
            raise AssertionError(f"tree_path of #{element.id()}: {shared} with the memo, {alone} alone")


_SCENE = None


def _scene():
    """A small scene of named parts in groups, for the specs that name objects."""
    global _SCENE
    if _SCENE is None:
        import sys

        sys.path.insert(0, str(Path(__file__).resolve().parent))
        from bad_gltf import box_doc, glb

        from rtta.scene.loader import load_scene

        nodes = [
            {"name": "frame", "children": [1, 2, 3]},
            {"name": "bolt", "mesh": 0},
            {"name": "bolt", "mesh": 0, "translation": [2, 0, 0]},
            {"name": "cover plate*", "mesh": 0, "translation": [0, 2, 0]},
        ]
        doc, binary = box_doc(nodes)
        _SCENE = load_scene(_file(glb(doc, binary), "scene.glb"))
    return _SCENE


def fuzz_specs(data: bytes) -> None:
    """The input's text (split at NUL into up to four fields) as every spec a user types."""
    from rtta.renderer.options import check_size, make_settings, orbit_camera, style_keywords
    from rtta.renderer.snapshot import make_lens, parse_opacities
    from rtta.scene.camera import parse_orbit
    from rtta.scene.cutaway import parse_section
    from rtta.scene.framing import parse_camera
    from rtta.scene.select import resolve_names

    text = data.decode("utf-8", "surrogateescape")
    fields = (text.split("\0") + ["", "", ""])[:4]
    scene = _scene()
    calls: list[Callable[[], object]] = [
        lambda: parse_camera(fields[0]),
        lambda: parse_orbit(fields[0]),
        lambda: orbit_camera(scene, fields[0], fov=45.0),
        lambda: check_size(fields[0]),
        lambda: make_settings(atlas_max=fields[0]),
        lambda: parse_opacities(scene, fields[:2]),
        lambda: resolve_names(scene, [fields[0]], "--focus"),
        lambda: make_lens(scene, fields[0], fields[1] or None, []),
        lambda: style_keywords({"outline_color": fields[0].split(","), "edge_color": fields[1]}),
        lambda: parse_section(fields[0]),
    ]
    for call in calls:
        try:
            call()
        except RttaError:
            pass


def fuzz_views(data: bytes) -> None:
    """The input as a saved view file (--view-file) and as a dataset's --cameras file."""
    from rtta.dataset.options import parse_cameras
    from rtta.renderer.view_file import read_view

    path = _file(data, "input.json")
    for read in (read_view, parse_cameras):
        try:
            read(path)
        except RttaError:
            pass


def fuzz_cache(data: bytes) -> None:
    """The input as a scene cache entry of a small source file (tests/fuzz_cache.py)."""
    import fuzz_cache

    fuzz_cache.fuzz_cache(data, CORPUS / "cache")


TARGETS: dict[str, Callable[[bytes], None]] = {
    "obj": fuzz_obj,
    "gltf": fuzz_gltf,
    "step": fuzz_step,
    "ifc": fuzz_ifc,
    "specs": fuzz_specs,
    "views": fuzz_views,
    "cache": fuzz_cache,
}


def run_one(target: str, data: bytes) -> None:
    """One input through one target: returns or raises RttaError (the contract); any other
    exception is the finding."""
    try:
        TARGETS[target](data)
    except RttaError:
        pass


def warm(target: str) -> None:
    """What a target imports and caches on first use (trimesh, the scene of the specs), done
    before inputs are timed."""
    if target in ("obj", "gltf", "cache"):
        import trimesh  # noqa: F401  (the loader's fallback reader)
    run_one(target, seeds(target)[0])


def seeds(target: str) -> list[bytes]:
    """The target's seed corpus, in name order."""
    return [p.read_bytes() for p in sorted((CORPUS / target).iterdir()) if p.is_file()]


_TOKENS = [b"0", b"-1", b"1e308", b"-1e400", b"nan", b"inf", b"4294967295", b"2147483648", b"1e-320", b"3.0"]
_TOKENS += [b"null", b"[]", b"{}", b'""', b"true", b",", b"\n", b"/", b"#1", b"*", b"'", b"\\", b"\x00", b"\xff"]
_TOKENS += [b"9" * 400, b"[" * 3000, b"1e999", b"-0"]


def mutants(corpus: list[bytes], n: int, seed: int = 42) -> Iterator[bytes]:
    """`n` deterministic mutants of the corpus (seeded): bit flips, special bytes, a run
    deleted, duplicated or truncated, a splice from another seed, a number or token
    replaced by an extreme one, the JSON of a .gltf reparsed and one value swapped."""
    rng = random.Random(seed)
    for _ in range(n):
        data = bytearray(rng.choice(corpus) or b"0")
        for _ in range(rng.randint(1, 4)):
            i = rng.randrange(len(data) or 1)
            op = rng.randrange(8)
            if op == 0 and data:
                data[i] ^= 1 << rng.randrange(8)
            elif op == 1 and data:
                data[i] = rng.choice([0, 0xFF, 0x7F, 0x80, 0x2D, 0x39, 0x22, 0x2C, 0x0A, 0x23])
            elif op == 2:
                del data[i : i + rng.randint(1, 64)]
            elif op == 3:
                data[i:i] = data[i : i + rng.randint(1, 256)] * rng.randint(1, 8)
            elif op == 4:
                del data[i:]
            elif op == 5:
                other = rng.choice(corpus)
                j = rng.randrange(len(other) or 1)
                data[i:] = other[j:]
            elif op == 6:
                data[i : i + rng.randint(0, 4)] = rng.choice(_TOKENS)
            else:
                data = bytearray(_json_swap(bytes(data), rng))
        yield bytes(data[:MAX_LEN])


def _json_swap(data: bytes, rng: random.Random) -> bytes:
    """A JSON document with one value (of any depth) replaced: structure-aware for .gltf."""
    try:
        doc = json.loads(data)
    except (ValueError, RecursionError):
        return data
    holders = []
    todo = [doc]
    while todo:
        item = todo.pop()
        keys = list(item) if isinstance(item, dict) else range(len(item)) if isinstance(item, list) else ()
        for k in keys:
            holders.append((item, k))
            todo.append(item[k])
    if not holders:
        return data
    holder, key = rng.choice(holders)
    holder[key] = rng.choice(
        [-1, 0, 1, 3, 2**31, 2**32 + 5, 10**400, 1e308, -0.0, None, "x", [], {}, [0] * 16, True, "data:,"]
    )
    return json.dumps(doc).encode()
