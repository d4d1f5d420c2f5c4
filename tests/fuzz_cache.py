"""The fuzz target `cache` (issue 42): the scene cache's entry reader (rtta.scene.cache).

An input is a cache entry for one of the small source files of tests/fuzz_corpus/cache/sources/:

    byte 0          the source (index into SOURCES)
    byte 1          flags: FIX_CHECKSUM (the head's CRC-32 made to match what follows, so that
                    a mutation reaches the checks behind it), SIDECAR (the rest is the entry's
                    Scene.closed file)
    bytes 2..5      the entry's length n (uint32, little-endian)
    n bytes         the entry; then the side file's bytes

The sources are copied to a fixed folder (SOURCE_HOME) with a fixed mtime, and the key's
version, code fingerprint and memory limit are fixed while the target runs (portable_keys),
so that an entry written on one machine or checkout is found on another. The load must give
a whole Scene (the entry's, or the source's rebuilt after a miss) or an RttaError: any other
exception, or a scene whose arrays do not fit together (check_scene), is a finding.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
import zlib
from collections.abc import Iterator
from pathlib import Path

import numpy as np

SOURCES = ("triangle.obj", "parts.obj", "tree.glb", "textured.glb", "box.gltf")
COMPANIONS = {"parts.obj": ("parts.mtl",), "box.gltf": ("box.bin",)}  # files a source reads too
SOURCE_HOME = Path(tempfile.gettempdir()) / "rtta-fuzz-cache-sources"
SOURCE_MTIME_NS = 1_600_000_000 * 10**9
OPTIONS = {"smooth_angle": 30.0, "smooth": False}  # load_scene's defaults, as the loader keys them
FIX_CHECKSUM, SIDECAR = 1, 2
_CACHE = Path(tempfile.mkdtemp(prefix="rtta-fuzz-cache-"))
_DIRECT: dict[str, object] = {}


def encode(source: int, flags: int, entry: bytes, side: bytes = b"") -> bytes:
    """One input of the target (the inverse of decode)."""
    return bytes([source, flags]) + len(entry).to_bytes(4, "little") + entry + side


def decode(data: bytes) -> tuple[str, int, bytes, bytes]:
    """(source name, flags, entry bytes, side file bytes) of an input."""
    data = data if len(data) >= 6 else data + bytes(6 - len(data))
    n = int.from_bytes(data[2:6], "little")
    return SOURCES[data[0] % len(SOURCES)], data[1], data[6 : 6 + n], data[6 + n :]


def source(name: str, corpus: Path) -> Path:
    """The source `name` (and its companions) in SOURCE_HOME with SOURCE_MTIME_NS: copied from
    corpus/sources/ when missing or different (by a rename: processes may fuzz at once)."""
    SOURCE_HOME.mkdir(parents=True, exist_ok=True)
    for part in (name, *COMPANIONS.get(name, ())):
        data = (corpus / "sources" / part).read_bytes()
        target = SOURCE_HOME / part
        with contextlib.suppress(OSError):
            st = target.stat()
            if st.st_size == len(data) and st.st_mtime_ns == SOURCE_MTIME_NS and target.read_bytes() == data:
                continue
        fd, temp = tempfile.mkstemp(dir=SOURCE_HOME, prefix=".tmp-")
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        os.utime(temp, ns=(SOURCE_MTIME_NS, SOURCE_MTIME_NS))
        os.replace(temp, target)
    return SOURCE_HOME / name


@contextlib.contextmanager
def portable_keys(folder: Path) -> Iterator[None]:
    """RTTA_CACHE_DIR = `folder`, and cache keys without the version, code fingerprint and
    memory limit of this process (restored after)."""
    from rtta.scene import cache

    real, before = cache._key, os.environ.get("RTTA_CACHE_DIR")

    def key(path: Path, options: dict) -> dict | None:
        found = real(path, options)
        if found is not None:
            found.update(version="fuzz", code="fuzz", memory_limit=0)
        return found

    cache._key, os.environ["RTTA_CACHE_DIR"] = key, str(folder)
    try:
        yield
    finally:
        cache._key = real
        if before is None:
            os.environ.pop("RTTA_CACHE_DIR", None)
        else:
            os.environ["RTTA_CACHE_DIR"] = before


def fixed_checksum(entry: bytes) -> bytes:
    """The entry with its head's checksum made that of what follows the head (where the head
    still reads as JSON and the new one fits before the body); else the entry as it is."""
    import json

    from rtta.scene.cache import ALIGN, MAGIC

    start = len(MAGIC) + 8
    if entry[: len(MAGIC)] != MAGIC or len(entry) < start:
        return entry
    n = int.from_bytes(entry[len(MAGIC) : start], "little")
    body = start + n + (-(start + n) % ALIGN)
    try:
        head = json.loads(entry[start : start + n])
        if not isinstance(head, dict) or n > len(entry):
            return entry
        head["checksum"] = zlib.crc32(entry[body:])
        text = json.dumps(head).encode()
    except (ValueError, RecursionError, TypeError):
        return entry
    if start + len(text) > body:
        return entry
    return MAGIC + len(text).to_bytes(8, "little") + text + bytes(body - start - len(text)) + entry[body:]


def fuzz_cache(data: bytes, corpus: Path) -> None:
    """The input's entry (and side file) in a fresh cache folder, then its source loaded: a hit
    must be a whole scene, a miss the source's own scene (rebuilt)."""
    from rtta.scene import cache
    from rtta.scene.loader import load_scene

    name, flags, entry, side = decode(data)
    path = source(name, corpus)
    if name not in _DIRECT:
        _DIRECT[name] = load_scene(path, cache=False)
    if flags & FIX_CHECKSUM:
        entry = fixed_checksum(entry)
    shutil.rmtree(_CACHE, ignore_errors=True)
    _CACHE.mkdir()
    with portable_keys(_CACHE):
        stem = _CACHE / cache._digest(cache._key(path, OPTIONS))
        stem.with_suffix(cache.SUFFIX).write_bytes(entry)
        if flags & SIDECAR:
            stem.with_suffix(cache.CLOSED).write_bytes(side)
        hit = cache.load(path, OPTIONS)
        scene = load_scene(path) if hit is None else hit
    check_scene(scene)
    if hit is None:
        same_scene(scene, _DIRECT[name])


def check_scene(scene) -> None:
    """AssertionError unless the scene's arrays fit together: shapes and dtypes, indices below
    the vertex count, object ids below the object count, finite numbers, index ranges within
    the indices, texture ids of textures it has; then what the renderer asks of it first."""
    n, v = len(scene.names), len(scene.positions)
    assert n > 0 and all(isinstance(s, str) for s in [*scene.names, *scene.warnings, *scene.inputs]), "names"
    assert isinstance(scene.unit, str) and scene.up_axis in ("y", "z"), f"unit, up axis {scene.up_axis!r}"
    shapes = {
        "positions": ((v, 3), np.float32),
        "normals": ((v, 3), np.float32),
        "object_ids": ((v,), np.uint32),
        "index_ranges": ((n, 2), np.int64),
        "colors": ((n, 4), np.float32),
        "aabb_min": ((n, 3), np.float64),
        "aabb_max": ((n, 3), np.float64),
        "origin": ((3,), np.float64),
        "uvs": ((v, 2), np.float32),
        "texture_ids": ((n,), np.int32),
    }
    for field, (shape, dtype) in shapes.items():
        a = getattr(scene, field)
        if a is None and field in ("uvs", "texture_ids"):
            continue
        assert a.shape == shape and a.dtype == dtype, f"{field}: {a.dtype} {a.shape}, not {shape}"
        assert a.dtype.kind != "f" or np.isfinite(a).all(), f"{field} not finite"
    indices, ranges = scene.indices, scene.index_ranges.astype(object)  # Python ints: no overflow
    assert indices.dtype == np.uint32 and indices.ndim == 1 and len(indices) % 3 == 0, "indices"
    assert not len(indices) or int(indices.max()) < v, "an index past the vertices"
    assert not v or int(scene.object_ids.max()) < n, "an object id past the objects"
    assert all(0 <= a and 0 <= b and a + b <= len(indices) for a, b in ranges), "an index range past the indices"
    assert (scene.aabb_min <= scene.aabb_max).all(), "a box with min > max"
    assert ((scene.colors >= 0) & (scene.colors <= 1)).all(), "a colour outside [0, 1]"
    for t in scene.textures:
        assert t.dtype == np.uint8 and t.ndim == 3 and t.shape[2] == 4 and t.size, f"texture {t.shape}"
    if scene.texture_ids is not None:
        assert ((scene.texture_ids >= -1) & (scene.texture_ids < len(scene.textures))).all(), "texture ids"
    if scene.paths is not None:
        assert len(scene.paths) == n and all(isinstance(s, str) for p in scene.paths for s in p), "paths"
    scene.box_corners()
    scene.index_runs(np.ones(n, bool))
    closed = scene.closed
    assert closed.dtype == bool and closed.shape == (n,), f"closed {closed.dtype} {closed.shape}"


def same_scene(a, b) -> None:
    """AssertionError unless two scenes have the same names and arrays."""
    assert a.names == b.names, "names differ from the source's"
    for field in ("positions", "normals", "object_ids", "indices", "index_ranges", "colors", "uvs", "texture_ids"):
        x, y = getattr(a, field), getattr(b, field)
        assert (x is None) == (y is None) and (x is None or np.array_equal(x, y)), f"{field} differs from the source's"


def seeds(corpus: Path) -> dict[str, bytes]:
    """Entries the cache writes for each source (the first with its Scene.closed file): one
    input each as written, one with its checksum to be fixed and its side file."""
    from rtta.scene import cache
    from rtta.scene.loader import load_scene

    out = {}
    for k, name in enumerate(SOURCES):
        folder = Path(tempfile.mkdtemp(prefix="rtta-cache-seed-"))
        try:
            with portable_keys(folder):
                path = source(name, corpus)
                assert load_scene(path).closed is not None  # the entry, then its side file
                stem = folder / cache._digest(cache._key(path, OPTIONS))
                entry = stem.with_suffix(cache.SUFFIX).read_bytes()
                side = stem.with_suffix(cache.CLOSED).read_bytes()
        finally:
            shutil.rmtree(folder, ignore_errors=True)
        base = name.replace(".", "_")
        out[f"{base}.bin"] = encode(k, 0, entry)
        out[f"{base}_closed.bin"] = encode(k, FIX_CHECKSUM | SIDECAR, entry, side)
    return out
