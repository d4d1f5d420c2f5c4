"""Loaded scenes cached on disk, one entry per file and load options, so that opening a file
a second time skips its reading, checks and batching.

Where: `$RTTA_CACHE_DIR`, else `$XDG_CACHE_HOME/rtta`, else `~/.cache/rtta`; at most
`$RTTA_CACHE_MAX_BYTES` (default 2 GiB), the least recently used entries evicted after a
write. An entry is found by the file's resolved path, size and mtime, rtta's version, a
fingerprint of the scene code (the size and mtime of every module of rtta.scene, so a
reader edited in a checkout never hands back its old scenes), the load options and the
memory limit; it is used only when every file the scene was read from (a glTF's buffers
and textures, an OBJ's materials) still has its size and mtime.

An entry is one file: a magic line, a JSON head (format version, CRC-32 of what follows:
it finds damage at 1.3 GB/s, blake2b 0.3-0.8; a deceiving entry still meets the checks below),
the scene's JSON metadata (names, tree paths, warnings, inputs, unit, up axis, the arrays'
dtypes, shapes and offsets) and the arrays' raw bytes. Nothing in it is
unpickled; an entry that is damaged, truncated, of another format or version, or whose
arrays do not fit together (rtta.scene.cache_fits: indices, object ids, index ranges and
texture ids in range, finite numbers) is ignored (and replaced by the next load), never trusted.
Entries are written to a temporary file in the folder and renamed into place (processes
loading a file at once each write a whole entry; the last stays) and never changed in place,
so a scene's arrays map it (copy-on-write: no copy of a 300 MB entry, 1.7 s of 2.4 here).
A folder that cannot be written means no cache, never an error; the demo is not cached.

A file modified less than RACY_NS before its load is not cached: its next change could
fall in the same timestamp tick (2 s on FAT) and leave its size and mtime as they were."""

from __future__ import annotations

import hashlib
import json
import mmap
import os
import stat
import sys
import tempfile
import time
import zlib
from importlib import resources
from pathlib import Path

import numpy as np

from ..errors import RttaError
from .cache_fits import ARRAYS, DTYPES, fits
from .files import memory_limit
from .model import Scene

FORMAT = 2  # 2: CRC-32 (1 had blake2b)
MAGIC = b"rtta-scene-cache"
SUFFIX = ".scene"
CLOSED = ".closed"  # beside an entry: its Scene.closed, once a process has worked it out
DEFAULT_MAX_BYTES = 2 << 30
RACY_NS = 2_000_000_000
STALE_TEMP_S = 3600  # a temporary file this old was left by a process that died while writing
ALIGN = 64


def folder() -> Path:
    """The cache folder: $RTTA_CACHE_DIR, else $XDG_CACHE_HOME/rtta, else ~/.cache/rtta."""
    if os.environ.get("RTTA_CACHE_DIR"):
        return Path(os.environ["RTTA_CACHE_DIR"])
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "rtta"


def max_bytes() -> int:
    """The folder's bound: $RTTA_CACHE_MAX_BYTES (bytes), else DEFAULT_MAX_BYTES."""
    try:
        return max(0, int(os.environ.get("RTTA_CACHE_MAX_BYTES", DEFAULT_MAX_BYTES)))
    except ValueError:
        return DEFAULT_MAX_BYTES


def load(path: Path, options: dict) -> Scene | None:
    """The cached Scene of `path` loaded with `options`, or None (no entry, or one not to be
    trusted: it is removed)."""
    key = _key(path, options)
    if key is None:
        return None
    entry = folder() / f"{_digest(key)}{SUFFIX}"
    try:
        st = entry.stat()
        if not stat.S_ISREG(st.st_mode) or not len(MAGIC) + 8 < st.st_size <= max_bytes():
            return None
        with open(entry, "rb") as f:  # mapped copy-on-write: the arrays are writable, read as used
            data = mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_COPY)
    except (OSError, ValueError):
        return None
    try:
        scene = _decode(data, key, str(path))
    except Exception:  # anything wrong with an entry makes it a miss, never an error
        scene = None
    if scene is None:
        _remove(entry)
        return None
    try:
        os.utime(entry)  # its last use, for the eviction
    except OSError:
        pass
    _closed(scene, entry)
    return scene


def store(path: Path, options: dict, scene: Scene, started_ns: int) -> None:
    """Write the entry of `scene`, loaded from `path` with `options` by a load that began at
    `started_ns` (time.time_ns()); then evict down to the bound. Failures are ignored."""
    key = _key(path, options)
    if key is None:
        return
    try:
        stats = {p: _stat(Path(p)) for p in scene.inputs}
    except OSError:
        return
    if any(mtime > started_ns - RACY_NS for _, mtime in stats.values()):
        return  # modified just before the load or during it: perhaps not what was read
    head, chunks, size = _encode(scene, key, stats)
    where = folder()
    if size > max_bytes():  # never kept: the others still fit the bound, which may have shrunk
        evict(where, max_bytes())
        return
    try:
        where.mkdir(parents=True, exist_ok=True)
        fd, temp = tempfile.mkstemp(dir=where, prefix=".tmp-", suffix=SUFFIX)
    except OSError:
        return
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(head)
            for chunk in chunks:
                f.write(chunk)
        os.replace(temp, where / f"{_digest(key)}{SUFFIX}")
    except OSError:
        _remove(Path(temp))
        return
    evict(where, max_bytes())
    _closed(scene, where / f"{_digest(key)}{SUFFIX}")


def _closed(scene: Scene, entry: Path) -> None:
    """Scene.closed (seconds for 10^5 parts) from the file beside `entry` when a process has
    worked it out before; else the scene writes it there once it does (a byte per object
    after their CRC-32: a file that does not fit is ignored)."""
    side = entry.with_suffix(CLOSED)
    try:
        data = side.read_bytes()
        bits = np.frombuffer(data, np.uint8, offset=4)
        if len(bits) == scene.count and zlib.crc32(data[4:]) == int.from_bytes(data[:4], "little") and bits.max() <= 1:
            scene._corners["closed"] = bits.astype(bool)
            return
    except (OSError, ValueError):
        pass
    scene._corners["keep_closed"] = lambda closed: _write(side, np.asarray(closed, bool).astype(np.uint8).tobytes())


def _write(path: Path, data: bytes) -> None:
    """`data` into `path` by a temporary file renamed into place; failures ignored."""
    try:
        fd, temp = tempfile.mkstemp(dir=path.parent, prefix=".tmp-", suffix=SUFFIX)
    except OSError:
        return
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(zlib.crc32(data).to_bytes(4, "little") + data)
        os.replace(temp, path)
    except OSError:
        _remove(Path(temp))


def evict(where: Path, bound: int) -> None:
    """Remove the least recently used entries (each with its Scene.closed file) until the
    folder's files fit in `bound` bytes, and temporary files left by processes that died
    while writing."""
    sizes: dict[str, list[int]] = {}  # entry stem -> [last use, bytes with its side file]
    try:
        names = os.listdir(where)
    except OSError:
        return
    for name in names:
        try:
            st = os.stat(where / name)
        except OSError:
            continue
        if name.startswith(".tmp-"):
            if time.time() - st.st_mtime > STALE_TEMP_S:
                _remove(where / name)
        elif name.endswith((SUFFIX, CLOSED)):
            row = sizes.setdefault(name.rsplit(".", 1)[0], [0, 0])
            row[0] = max(row[0], st.st_mtime_ns if name.endswith(SUFFIX) else 0)
            row[1] += st.st_size
    total = sum(size for _, size in sizes.values())
    for stem, (used, size) in sorted(sizes.items(), key=lambda item: item[1][0]):
        if total <= bound and used:  # a side file without its entry (used 0) goes regardless
            continue
        _remove(where / f"{stem}{SUFFIX}")
        _remove(where / f"{stem}{CLOSED}")
        total -= size


def _assets() -> Path | None:
    """rtta's shipped scenes' folder (None: rtta imported from a source tree, no rtta.assets)."""
    try:
        return Path(str(resources.files("rtta.assets"))).resolve()
    except (ImportError, OSError, TypeError):
        return None


def _key(path: Path, options: dict) -> dict | None:
    try:
        resolved = path.resolve()
        size, mtime_ns = _stat(resolved)
        limit = memory_limit()
    except (OSError, RuntimeError, RttaError):  # the load itself says what is wrong
        return None
    if resolved.parent == _assets():
        return None  # the demo: shipped with rtta, small
    return {
        "path": str(resolved),
        "size": size,
        "mtime_ns": mtime_ns,
        "version": _version(),
        "code": _code(),
        "options": {k: options[k] for k in sorted(options)},
        "memory_limit": limit,  # a scene refused under a lower limit is not handed back
    }


def _stat(path: Path) -> tuple[int, int]:
    st = path.stat()
    return st.st_size, st.st_mtime_ns


def _digest(key: dict) -> str:
    return hashlib.blake2b(json.dumps(key, sort_keys=True).encode(), digest_size=20).hexdigest()


def _version() -> str:
    """rtta.__version__, read from the imported package rather than imported here (which
    would make the scene layer import every layer above it)."""
    return str(getattr(sys.modules.get(__name__.split(".")[0]), "__version__", "unknown"))


_CODE: list[str] = []


def _code() -> str:
    """A fingerprint of rtta.scene's modules (names, sizes, mtimes), made once a process."""
    if not _CODE:
        here = Path(__file__).parent
        rows = []
        for p in sorted(here.rglob("*.py")):
            try:
                st = p.stat()
            except OSError:
                continue
            rows.append(f"{p.relative_to(here)}:{st.st_size}:{st.st_mtime_ns}")
        _CODE.append(hashlib.blake2b("\n".join(rows).encode(), digest_size=12).hexdigest())
    return _CODE[0]


def _remove(path: Path) -> None:
    try:
        path.unlink()
    except OSError:
        pass


def _encode(scene: Scene, key: dict, stats: dict) -> tuple[bytes, list, int]:
    """(the head: magic, head length, head JSON; the chunks after it: metadata JSON, padding
    and arrays; the entry's size in bytes)."""
    arrays = {name: getattr(scene, name) for name in ARRAYS}
    if scene.uvs is not None:
        arrays["uvs"] = scene.uvs
    if scene.texture_ids is not None:
        arrays["texture_ids"] = scene.texture_ids
    arrays.update({f"texture_{i}": t for i, t in enumerate(scene.textures)})
    table, offset = [], 0
    for name, a in arrays.items():
        table.append([name, a.dtype.name, list(a.shape), offset])
        offset += -(-a.nbytes // ALIGN) * ALIGN
    meta = {
        "key": key,
        "inputs": [[p, *stats[p]] for p in scene.inputs],
        "names": scene.names,
        "paths": None if scene.paths is None else [list(p) for p in scene.paths],
        "warnings": scene.warnings,
        "unit": scene.unit,
        "up_axis": scene.up_axis,
        "textures": len(scene.textures),
        "arrays": table,
    }
    body = json.dumps(meta).encode()
    chunks: list = [body, bytes(-len(body) % ALIGN)]
    for a in arrays.values():
        chunks += [np.ascontiguousarray(a).reshape(-1).view(np.uint8).data, bytes(-a.nbytes % ALIGN)]
    checksum = 0
    for chunk in chunks:
        checksum = zlib.crc32(chunk, checksum)
    head = json.dumps({"format": FORMAT, "checksum": checksum, "meta": len(body)}).encode()
    head = MAGIC + len(head).to_bytes(8, "little") + head
    head += bytes(-len(head) % ALIGN)
    return head, chunks, len(head) + sum(len(c) for c in chunks)


def _decode(data: mmap.mmap, key: dict, source: str) -> Scene | None:
    """The Scene in an entry's bytes, or None where anything is amiss."""
    if data[: len(MAGIC)] != MAGIC:
        return None
    n = int.from_bytes(data[len(MAGIC) : len(MAGIC) + 8], "little")
    start = len(MAGIC) + 8
    head = json.loads(bytes(data[start : start + n]))
    start += n + (-(start + n) % ALIGN)
    if not isinstance(head, dict) or head.get("format") != FORMAT:
        return None
    view = memoryview(data)[start:]
    if zlib.crc32(view) != head.get("checksum"):
        return None
    length = int(head["meta"])
    meta = json.loads(bytes(view[:length]))
    if meta["key"] != key or not _inputs_unchanged(meta["inputs"]):
        return None
    payload = start + length + (-length % ALIGN)
    arrays = {}
    for name, dtype, shape, offset in meta["arrays"]:
        if dtype != DTYPES.get(name, "uint8") or not all(isinstance(s, int) and s >= 0 for s in shape):
            return None
        count = int(np.prod(shape, dtype=np.int64))
        arrays[name] = np.frombuffer(data, dtype, count, payload + int(offset)).reshape(shape)
    return _scene(arrays, meta, source)


def _inputs_unchanged(inputs: list) -> bool:
    """Every file the scene was read from has its size and mtime still, and this user may
    still read it (else the load says why, as it would without the cache)."""
    for p, size, mtime_ns in inputs:
        try:
            if _stat(Path(p)) != (size, mtime_ns) or not os.access(p, os.R_OK):
                return False
        except OSError:
            return False
    return True


def _scene(a: dict, meta: dict, source: str) -> Scene | None:
    """The Scene of an entry's arrays and metadata when they fit together (cache_fits)."""
    textures = [a.pop(f"texture_{i}") for i in range(int(meta["textures"]))]  # KeyError: a miss
    if not fits(a, meta, textures):
        return None
    paths = meta["paths"]
    return Scene(
        names=list(meta["names"]),
        source=source,
        warnings=list(meta["warnings"]),
        inputs=[p for p, _, _ in meta["inputs"]],
        textures=textures,
        paths=None if paths is None else [tuple(p) for p in paths],
        unit=meta["unit"],
        up_axis=meta["up_axis"],
        **a,
    )
