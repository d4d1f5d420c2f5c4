"""Malformed glTF JSON made by hypothesis from the fields of a valid file (and the optional
fields glTF defines): every field given a value of the wrong type, a missing one, an index
out of range, a huge or non-finite number. Each file either loads or is one RttaError
line, through the loader and through `rtta info`; never another exception, never slow."""

from __future__ import annotations

import copy
import json
import time

import pytest
from bad_gltf import box_doc, glb
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rtta.cli.main import main
from rtta.errors import RttaError
from rtta.scene.loader import load_scene

BASE, BINARY = box_doc(
    [{"mesh": 0, "name": "box", "children": [1]}, {"mesh": 0, "name": "child", "translation": [1.5, 0, 0]}]
)
BASE["materials"] = [{"name": "red", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.1, 0.1, 1.0]}}]
BASE["meshes"][0]["primitives"][0].update(material=0, mode=4)
BASE["bufferViews"][0]["byteStride"] = 12
DELETE = object()


def _paths(value, prefix=()) -> list[tuple]:
    """Every path into the document (keys and indices), the containers included."""
    out = [prefix] if prefix else []
    if isinstance(value, dict):
        for key, item in value.items():
            out += _paths(item, (*prefix, key))
    elif isinstance(value, list):
        for i, item in enumerate(value):
            out += _paths(item, (*prefix, i))
    return out


OPTIONAL = [
    ("scene",),
    ("nodes", 0, "matrix"),
    ("nodes", 0, "rotation"),
    ("nodes", 0, "scale"),
    ("nodes", 1, "children"),
    ("accessors", 0, "byteOffset"),
    ("accessors", 1, "sparse"),
    ("meshes", 0, "primitives", 0, "attributes", "TEXCOORD_0"),
    ("meshes", 0, "primitives", 0, "attributes", "COLOR_0"),
    ("buffers", 0, "uri"),
    ("images",),
    ("textures",),
    ("materials", 0, "pbrMetallicRoughness", "baseColorTexture"),
    ("extensionsRequired",),
    ("extensionsUsed",),
    ("samplers",),
    ("cameras",),
    ("nodes", 0, "camera"),
    # extensions rtta reads: Draco, texture transforms and sets, spec-gloss, WebP
    ("meshes", 0, "primitives", 0, "extensions"),
    ("meshes", 0, "primitives", 0, "attributes", "TEXCOORD_1"),
    ("materials", 0, "extensions"),
    ("materials", 0, "extensions", "KHR_materials_pbrSpecularGlossiness"),
    ("materials", 0, "pbrMetallicRoughness", "baseColorTexture", "extensions"),
    ("materials", 0, "pbrMetallicRoughness", "baseColorTexture", "texCoord"),
    ("textures", 0, "extensions"),
    ("textures", 0, "extensions", "EXT_texture_webp"),
]
PATHS = _paths(BASE) + OPTIONAL

NUMBERS = st.one_of(
    st.integers(-(2**70), 2**70),
    st.sampled_from([-1, 0, 1, 2, 3, 7, 24, 36, 255, 2**31, 2**32 + 1, 10**15, 1e400, -1e400, 10**400, -(10**400)]),
    st.floats(allow_nan=True, allow_infinity=True),
)
LEAVES = st.one_of(
    st.none(),
    st.booleans(),
    NUMBERS,
    st.text(max_size=6),
    st.sampled_from(["VEC3", "SCALAR", "MAT4", "data:,", "../x.bin"]),
)
VALUES = st.one_of(
    LEAVES,
    st.lists(LEAVES, max_size=17),
    st.lists(NUMBERS, min_size=3, max_size=4),
    st.dictionaries(
        st.sampled_from(["index", "count", "uri", "POSITION", "buffer", "nodes", "mesh"]), LEAVES, max_size=3
    ),
    st.just(DELETE),
)


def _apply(doc: dict, path: tuple, value) -> None:
    target = doc
    for key in path[:-1]:
        try:
            target = target[key]
        except (KeyError, IndexError, TypeError):
            return
    last = path[-1]
    if isinstance(target, dict):
        if value is DELETE:
            target.pop(last, None)
        else:
            target[last] = copy.deepcopy(value)
    elif isinstance(target, list) and isinstance(last, int) and last < len(target):
        if value is DELETE:
            del target[last]
        else:
            target[last] = copy.deepcopy(value)


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    return tmp_path_factory.mktemp("fuzz")


@settings(
    max_examples=300,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)
@given(st.lists(st.tuples(st.sampled_from(PATHS), VALUES), min_size=1, max_size=3))
def test_malformed_gltf_loads_or_is_one_line(folder, mutations):
    doc = copy.deepcopy(BASE)
    for path, value in mutations:
        _apply(doc, path, value)
    path = folder / "fuzz.glb"
    path.write_bytes(glb(doc, BINARY))
    t0 = time.perf_counter()
    try:
        scene = load_scene(path)
    except RttaError as exc:
        text = str(exc)
        assert text.startswith(f"{path}: ") and "\n" not in text.replace("\\n", ""), text
    else:
        assert scene.count >= 1 and all(isinstance(n, str) for n in scene.names)
    assert time.perf_counter() - t0 < 10


def test_fuzzed_files_through_the_cli(folder, capsys):
    """A sample of the same kind of files through `rtta info`: exit 0 or 2 and one error line."""
    import random

    rng = random.Random(26)
    leaves = [None, True, -1, 2**40, 1e308, float("nan"), "x", [], {}, [0] * 16]
    for _ in range(40):
        doc = copy.deepcopy(BASE)
        for _ in range(rng.randint(1, 3)):
            _apply(doc, rng.choice(PATHS), rng.choice(leaves + [DELETE]))
        path = folder / "cli.glb"
        path.write_bytes(glb(doc, BINARY))
        code = main(["info", str(path)])
        err = capsys.readouterr().err
        errors = [line for line in err.splitlines() if line.startswith("rtta: error: ")]
        assert code in (0, 2) and len(errors) == (code == 2), (json.dumps(doc)[:300], err)
        assert all(line.startswith("rtta: ") for line in err.splitlines()) and "Traceback" not in err
