"""The scene cache on disk (rtta.scene.cache): a scene read back equals the file's, a changed
file or input misses, a damaged or foreign entry is rebuilt, --no-cache writes nothing,
processes loading at once leave one valid entry, and eviction keeps the folder bounded."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
import zlib
from pathlib import Path

import numpy as np
import pytest
from assemblies import write_ifc
from bad_gltf import box_doc, png

import rtta
from rtta.errors import RttaError
from rtta.scene import cache
from rtta.scene.generators.assembly import write_assembly
from rtta.scene.loader import load_scene

FIELDS = ("positions", "normals", "object_ids", "indices", "index_ranges", "colors", "aabb_min", "aabb_max", "origin")
FIELDS += ("uvs", "texture_ids")


@pytest.fixture
def folder(tmp_path, monkeypatch):
    """This test's own cache folder (conftest's session folder is shared by every test)."""
    where = tmp_path / "cache"
    monkeypatch.setenv("RTTA_CACHE_DIR", str(where))
    return where


def _aged(*paths: Path) -> None:
    """Files written a minute ago: a file modified within cache.RACY_NS is not cached."""
    old = time.time_ns() - 60 * 10**9
    for p in paths:
        os.utime(p, ns=(old, old))


def _gltf(folder: Path, color=(200, 30, 30)) -> Path:
    """A textured box as .gltf with its buffer and its texture in files of their own."""
    folder.mkdir(parents=True, exist_ok=True)
    doc, binary = box_doc([{"mesh": 0, "name": "box"}, {"mesh": 0, "name": "copy", "translation": [2, 0, 0]}])
    uv = np.tile(np.array([[0, 0], [1, 0], [1, 1], [0, 1]], np.float32), (6, 1))
    doc["bufferViews"].append({"buffer": 0, "byteOffset": len(binary), "byteLength": uv.nbytes})
    binary += uv.tobytes()
    doc["buffers"] = [{"byteLength": len(binary), "uri": "box.bin"}]
    doc["accessors"].append({"bufferView": 3, "componentType": 5126, "count": 24, "type": "VEC2"})
    doc["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = 3
    doc["meshes"][0]["primitives"][0]["material"] = 0
    doc["materials"] = [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]
    doc["textures"] = [{"source": 0}]
    doc["images"] = [{"uri": "tex.png"}]
    doc["scenes"] = [{"nodes": [0, 1]}]
    (folder / "box.bin").write_bytes(binary)
    (folder / "tex.png").write_bytes(png((8, 8), color))
    (folder / "box.gltf").write_text(json.dumps(doc))
    _aged(folder / "box.bin", folder / "tex.png", folder / "box.gltf")
    return folder / "box.gltf"


def _obj(folder: Path) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "parts.mtl").write_text("newmtl red\nKd 0.8 0.1 0.1\nnewmtl blue\nKd 0.1 0.2 0.9\n")
    quad = "v 0 0 {z}\nv 1 0 {z}\nv 1 1 {z}\nv 0 1 {z}\n"
    text = "mtllib parts.mtl\no first\n" + quad.format(z=0) + "usemtl red\nf 1 2 3\nf 1 3 4\n"
    text += "o second\n" + quad.format(z=1) + "usemtl blue\nf 5 6 7\nf 5 7 8\n"
    (folder / "parts.obj").write_text(text)
    _aged(folder / "parts.mtl", folder / "parts.obj")
    return folder / "parts.obj"


def _ifc(folder: Path) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    write_ifc(folder / "house.ifc")
    _aged(folder / "house.ifc")
    return folder / "house.ifc"


def assert_same(a, b) -> None:
    """Every array (values and dtypes), name, path, colour, texture, unit, warning, input."""
    for name in FIELDS:
        x, y = getattr(a, name), getattr(b, name)
        assert (x is None) == (y is None), name
        if x is not None:
            assert x.dtype == y.dtype and np.array_equal(x, y), name
    assert a.names == b.names and a.paths == b.paths and a.warnings == b.warnings
    assert a.inputs == b.inputs and a.source == b.source and (a.unit, a.up_axis) == (b.unit, b.up_axis)
    assert len(a.textures) == len(b.textures)
    assert all(np.array_equal(s, t) and s.dtype == t.dtype for s, t in zip(a.textures, b.textures, strict=True))


def _entries(folder: Path) -> list[Path]:
    return sorted(folder.glob(f"*{cache.SUFFIX}")) if folder.is_dir() else []


class Reads:
    """Counts the readers' loads (a cache hit reads nothing)."""

    def __init__(self, monkeypatch) -> None:
        self.count = 0
        real = rtta.scene.readers.load

        def counted(*args):
            self.count += 1
            return real(*args)

        monkeypatch.setattr("rtta.scene.readers.load", counted)


@pytest.mark.parametrize("write", [_gltf, _obj, _ifc], ids=["gltf-textured", "obj-materials", "ifc"])
def test_the_cached_scene_is_the_files(write, folder, tmp_path, monkeypatch):
    path = write(tmp_path / "files")
    direct = load_scene(path, cache=False)
    assert not _entries(folder)
    reads = Reads(monkeypatch)
    first = load_scene(path)
    assert reads.count == 1 and len(_entries(folder)) == 1
    again = load_scene(path)
    assert reads.count == 1  # read back from the entry
    assert_same(direct, first)
    assert_same(direct, again)
    again.positions[0] += 1  # the arrays read back are the scene's own, writable
    if write is _gltf:
        assert again.textured and len(again.inputs) == 3 and again.paths is None
    if write is _ifc:
        assert again.unit == "mm" and again.up_axis == "z" and again.paths
        monkeypatch.setitem(sys.modules, "ifcopenshell", None)  # as if rtta[bim] were uninstalled since
        with pytest.raises(RttaError, match=r"needs ifcopenshell: pip install 'rtta\[bim\]'"):
            load_scene(path)


def test_a_changed_file_or_input_misses(folder, tmp_path, monkeypatch):
    path = _gltf(tmp_path / "files")
    red = load_scene(path)
    reads = Reads(monkeypatch)
    (tmp_path / "files" / "tex.png").write_bytes(png((8, 8), (30, 200, 30)))  # an input besides the file
    _aged(tmp_path / "files" / "tex.png")
    green = load_scene(path)
    assert reads.count == 1 and green.textures[0][0, 0, 1] > red.textures[0][0, 0, 1]
    text = path.read_text()
    path.write_text(text.replace('"copy"', '"kopy"'))  # same size, another mtime
    _aged(path)
    os.utime(path, ns=(time.time_ns() - 30 * 10**9,) * 2)
    assert load_scene(path).names == ["box", "kopy"] and reads.count == 2
    path.write_text(text.replace('"copy"', '"copied"'))  # another size
    _aged(path)
    assert load_scene(path).names == ["box", "copied"] and reads.count == 3
    load_scene(path, smooth_angle=10.0)  # other options: their own entry
    assert reads.count == 4 and len(_entries(folder)) == 4


def test_a_lower_memory_limit_is_not_bypassed(folder, tmp_path, monkeypatch):
    path = _obj(tmp_path / "files")
    load_scene(path)
    monkeypatch.setenv("RTTA_MEMORY_LIMIT_MB", "0.0001")
    with pytest.raises(RttaError, match="memory"):
        load_scene(path)


def test_a_file_just_written_is_not_cached(folder, tmp_path):
    path = write_assembly(tmp_path / "new.glb", 3)
    load_scene(path)
    assert not _entries(folder)


def test_the_demo_is_not_cached(folder):
    from rtta.scene.generators.demo import demo_path
    from rtta.scene.loader import load_scene_or_demo

    assert load_scene_or_demo(None).count == load_scene(demo_path()).count == 24
    assert not folder.exists()


def test_a_file_changed_during_its_load_is_not_cached(folder, tmp_path, monkeypatch):
    path = _obj(tmp_path / "files")
    real = rtta.scene.readers.load

    def then_touched(*args):
        scene = real(*args)
        os.utime(path)  # written again while it was read
        return scene

    monkeypatch.setattr("rtta.scene.readers.load", then_touched)
    load_scene(path)
    assert not _entries(folder)


def _rewritten(entry: Path, change, values: tuple[str, list] | None = None) -> None:
    """The entry with its metadata changed by `change` (and the first values of one array
    replaced: (name, values)) and its checksum made to match."""
    data = bytearray(entry.read_bytes())
    n = int.from_bytes(data[len(cache.MAGIC) : len(cache.MAGIC) + 8], "little")
    start = len(cache.MAGIC) + 8
    head = json.loads(bytes(data[start : start + n]))
    body = start + n + (-(start + n) % cache.ALIGN)
    meta = json.loads(bytes(data[body : body + head["meta"]]))
    payload = bytearray(data[body + head["meta"] + (-head["meta"] % cache.ALIGN) :])
    if values is not None:
        _, dtype, _, offset = next(r for r in meta["arrays"] if r[0] == values[0])
        raw = np.asarray(values[1], dtype).tobytes()
        payload[offset : offset + len(raw)] = raw
    change(meta)
    text = json.dumps(meta).encode()
    rest = bytes(text) + bytes(-len(text) % cache.ALIGN) + bytes(payload)
    head.update(meta=len(text), checksum=zlib.crc32(rest))
    top = json.dumps(head).encode()
    top = cache.MAGIC + len(top).to_bytes(8, "little") + top
    entry.write_bytes(top + bytes(-len(top) % cache.ALIGN) + rest)


def _values(name: str, values: list):
    return lambda e: _rewritten(e, lambda m: None, (name, values))


FORMAT = b'"format": %d' % cache.FORMAT


def _shape(meta, name, shape):
    next(r for r in meta["arrays"] if r[0] == name)[2] = shape


def _dtype(meta, name, dtype):
    next(r for r in meta["arrays"] if r[0] == name)[1] = dtype


DAMAGE = {
    "truncated": lambda e: e.write_bytes(e.read_bytes()[: e.stat().st_size // 2]),
    "empty": lambda e: e.write_bytes(b""),
    "flipped byte": lambda e: e.write_bytes((lambda b: b[:-100] + bytes([b[-100] ^ 1]) + b[-99:])(e.read_bytes())),
    "flipped meta byte": lambda e: e.write_bytes((lambda b: b[:300] + bytes([b[300] ^ 4]) + b[301:])(e.read_bytes())),
    "foreign format": lambda e: e.write_bytes(e.read_bytes().replace(FORMAT, b'"format": 9', 1)),
    "not json": lambda e: e.write_bytes(cache.MAGIC + (40).to_bytes(8, "little") + b"{" * 40 + e.read_bytes()[64:]),
    "wrong shape": lambda e: _rewritten(e, lambda m: _shape(m, "positions", [3, 3])),
    "fewer normals": lambda e: _rewritten(e, lambda m: _shape(m, "normals", [3, 3])),
    "wrong dtype": lambda e: _rewritten(e, lambda m: _dtype(m, "indices", "float64")),
    "fewer names": lambda e: _rewritten(e, lambda m: m["names"].pop()),
    "other version": lambda e: _rewritten(e, lambda m: m["key"].__setitem__("version", "0.0.1")),
    "foreign array": lambda e: _rewritten(e, lambda m: m["arrays"].append(["evil", "uint8", [1], 0])),
    # found by the cache fuzz target (tests/fuzz_cache.py): entries of whole CRC-32 that were trusted
    "NaN position": _values("positions", [np.nan] * 3),
    "infinite normal": _values("normals", [np.inf] * 3),
    "NaN origin": _values("origin", [np.nan] * 3),
    "NaN texture coordinate": _values("uvs", [np.nan] * 2),
    "NaN colour": _values("colors", [np.nan] * 4),
    "colour above 1": _values("colors", [2.0] * 4),
    "box inside out": _values("aabb_min", [10.0] * 3),
    "range past the indices": _values("index_ranges", [2**62, 2**62]),  # first + count overflowed int64
    "texture id below -1": _values("texture_ids", [-5]),
    "empty texture": lambda e: _rewritten(e, lambda m: _shape(m, "texture_0", [0, 0, 4])),
    "names a string": lambda e: _rewritten(e, lambda m: m.__setitem__("names", "ab")),  # read as ['a', 'b']
    "up axis x": lambda e: _rewritten(e, lambda m: m.__setitem__("up_axis", "x")),
}


@pytest.mark.parametrize("damage", list(DAMAGE))
def test_a_damaged_entry_is_rebuilt(damage, folder, tmp_path, monkeypatch):
    path = _gltf(tmp_path / "files")
    direct = load_scene(path, cache=False)
    load_scene(path)
    (entry,) = _entries(folder)
    DAMAGE[damage](entry)
    reads = Reads(monkeypatch)
    assert_same(direct, load_scene(path))
    assert reads.count == 1  # read from the file, not the entry
    assert_same(direct, load_scene(path))
    assert reads.count == 1  # and the entry written again is whole


def test_another_rtta_version_misses(folder, tmp_path, monkeypatch):
    path = _obj(tmp_path / "files")
    load_scene(path)
    reads = Reads(monkeypatch)
    monkeypatch.setattr(rtta, "__version__", "99.0")
    assert_same(load_scene(path, cache=False), load_scene(path))
    assert reads.count == 2 and len(_entries(folder)) == 2


def test_no_cache_writes_nothing(folder, tmp_path, capsys):
    from rtta.cli.main import main

    path = _obj(tmp_path / "files")
    assert main(["info", "--no-cache", str(path)]) == 0
    assert "2 objects" in capsys.readouterr().out
    assert not folder.exists()
    assert main(["info", str(path)]) == 0
    assert len(_entries(folder)) == 1


def test_a_folder_that_cannot_be_written_is_no_cache(tmp_path, monkeypatch):
    blocker = tmp_path / "a file"
    blocker.write_text("not a folder")
    monkeypatch.setenv("RTTA_CACHE_DIR", str(blocker / "cache"))
    path = _obj(tmp_path / "files")
    assert load_scene(path).names == load_scene(path).names == ["first", "second"]


def test_processes_loading_at_once_leave_one_valid_entry(folder, tmp_path, monkeypatch):
    path = write_assembly(tmp_path / "many.glb", 400)
    _aged(path)
    code = "import sys\nfrom rtta.scene.loader import load_scene\nprint(load_scene(sys.argv[1]).count)"
    env = {**os.environ, "RTTA_CACHE_DIR": str(folder)}
    runs = [
        # in tmp_path: `python -c` puts its cwd first on sys.path (from a checkout, its rtta/)
        subprocess.Popen(
            [sys.executable, "-c", code, str(path)], env=env, stdout=subprocess.PIPE, text=True, cwd=tmp_path
        )
        for _ in range(8)
    ]
    outs = [run.communicate(timeout=300)[0] for run in runs]
    assert [run.returncode for run in runs] == [0] * 8 and outs == ["400\n"] * 8
    assert len(_entries(folder)) == 1 and os.listdir(folder) == [_entries(folder)[0].name]  # no temporaries
    monkeypatch.setattr(cache, "_CODE", [])  # this process's code fingerprint made now, as the children's were
    reads = Reads(monkeypatch)
    assert_same(load_scene(path, cache=False), load_scene(path))
    assert reads.count == 1  # only the direct load: the entry was whole


def test_eviction_keeps_the_folder_under_the_bound(folder, tmp_path, monkeypatch):
    paths = [write_assembly(tmp_path / f"a{i}.glb", 30, seed=i) for i in range(5)]
    _aged(*paths)
    load_scene(paths[0])
    size = _entries(folder)[0].stat().st_size
    bound = int(2.5 * size)
    monkeypatch.setenv("RTTA_CACHE_MAX_BYTES", str(bound))
    for i, p in enumerate(paths[1:], 1):
        time.sleep(0.02)  # mtimes apart: the order of use
        load_scene(p)
        total = sum(e.stat().st_size for e in _entries(folder))
        assert total <= bound and len(_entries(folder)) == min(i + 1, 2)
    reads = Reads(monkeypatch)
    load_scene(paths[-1])  # the last ones used are kept
    assert reads.count == 0
    load_scene(paths[0])
    assert reads.count == 1
    monkeypatch.setenv("RTTA_CACHE_MAX_BYTES", str(size // 2))  # an entry over the bound is not kept
    load_scene(paths[1])
    assert not _entries(folder)


COMMANDS = [["info"], ["snapshot", "--out", "o"], ["export", "--out", "o"], ["dataset", "x.glb", "--out", "o"]]


@pytest.mark.parametrize("command", [*COMMANDS, ["ldi", "x.glb"], None])
def test_every_command_that_loads_a_scene_has_no_cache(command):
    """rtta's commands and rtta-view (command None) take --no-cache; the loader gets cache=False."""
    from rtta.cli.common import load_options
    from rtta.cli.main import build_parser

    if command is None:
        import viewer

        args = viewer.build_parser().parse_args(["--no-cache"])
    else:
        args = build_parser().parse_args([*command, "--no-cache"])
    assert args.no_cache
    if command is None or command[0] != "ldi":
        assert load_options(args)["cache"] is False
        assert load_options(type(args)(**{**vars(args), "no_cache": False}))["cache"] is True


def test_closed_is_kept_beside_the_entry(folder, tmp_path, monkeypatch):
    """Scene.closed (the closure test, seconds for 10^5 parts) is worked out once per entry."""
    from rtta.scene import model

    path = write_assembly(tmp_path / "parts.glb", 40)
    _aged(path)
    expected = load_scene(path, cache=False).closed
    first = load_scene(path)
    assert np.array_equal(first.closed, expected) and expected.any()
    (side,) = folder.glob(f"*{cache.CLOSED}")
    with monkeypatch.context() as m:
        m.setattr(model, "closed_objects", lambda *a: pytest.fail("worked out again"))
        assert np.array_equal(load_scene(path).closed, expected)
    side.write_bytes(side.read_bytes()[:-1])  # damaged: worked out again, and written again
    assert np.array_equal(load_scene(path).closed, expected) and side.stat().st_size == 4 + len(expected)
    (entry,) = _entries(folder)
    cache.evict(folder, entry.stat().st_size)  # the entry and its side file: over the bound, both go
    assert not list(folder.iterdir())
