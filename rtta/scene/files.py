"""What a scene may read: regular files only (never a FIFO, device or socket, which would
hang or never end), inside the scene's folder, within the memory limit; images checked
from their headers before anything decodes them. Every file a scene reads goes through
here, trimesh's included (`SafeResolver`).
"""

from __future__ import annotations

import io
import math
import os
import re
import stat
import warnings
from pathlib import Path
from urllib.parse import unquote

from ..errors import RttaError, reason

DEFAULT_LIMIT_MB = 4096
MAX_FILE_BYTES = 2 * 1024**3
MAX_TEXTURE_PIXELS = 8192 * 8192  # 256 MiB as RGBA8; the material atlas halves anything over 4032 anyway
TEXTURE_BYTES_PER_PIXEL = 12  # decoded RGBA, the atlas copy, its mip levels
MAX_OBJECTS = 10_000  # objects any scene file may make (loading costs ~0.25 ms each, OBJ ~0.5)
BYTES_PER_OBJECT = 256  # larger files: one object per this many bytes of the file
MAX_OBJECTS_LARGE = 1_000_000  # and never more than this
PARTS_ENV = "RTTA_MAX_PARTS"  # parts any file may make, replacing the rule above (max_objects)
MAX_PARTS_SET = 5_000_000  # (the glTF graph walk counts up to 10 x MAX_OBJECTS_LARGE)
PARTS_HINT = f"{PARTS_ENV}=N allows more"
IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tga", ".tif", ".tiff", ".gif", ".webp")


WALK_PER_OBJECT = 50  # nodes (node paths) a reader's graph walk may visit per object a file may make


def max_objects(path: Path, extra_bytes: int = 0) -> int:
    """Objects the scene file at `path` (with `extra_bytes` of files it refers to, such as a
    glTF's buffers) may make: 10,000, or for larger files one per 256 bytes (up to 1,000,000).
    A small file cannot take minutes through instancing or many tiny objects (a GLB of 50,000
    shared-mesh nodes in 2 MB took 63 s to snapshot), while a real 100,000-part assembly
    (tens of MB of geometry) loads. RTTA_MAX_PARTS (1 to 5,000,000) replaces the rule, for a
    small file that instances more on purpose (PARTS_HINT in every refusal says so)."""
    raw = os.environ.get(PARTS_ENV, "").strip()
    if raw:
        try:
            parts = int(raw)
        except ValueError:
            parts = 0
        if not 1 <= parts <= MAX_PARTS_SET:
            raise RttaError(f"{PARTS_ENV} must be a whole number of parts from 1 to {MAX_PARTS_SET:,}, got '{raw}'")
        return parts
    try:
        size = path.stat().st_size + extra_bytes
    except OSError:
        size = extra_bytes
    return max(MAX_OBJECTS, min(size // BYTES_PER_OBJECT, MAX_OBJECTS_LARGE))


def memory_limit() -> int:
    """Bytes a scene may need: RTTA_MEMORY_LIMIT_MB (default 4096 MiB), a positive finite number."""
    raw = os.environ.get("RTTA_MEMORY_LIMIT_MB", "").strip()
    try:
        mb = float(raw) if raw else DEFAULT_LIMIT_MB
    except ValueError:
        mb = math.nan
    if not (math.isfinite(mb) and 0 < mb <= 2**40):
        raise RttaError(f"RTTA_MEMORY_LIMIT_MB must be a positive number of MiB (up to 2^40), got '{raw}'")
    return int(mb * 2**20)


def regular_file(path: Path, what: str = "file") -> int:
    """The size of `path`; RttaError unless it is an existing regular file (links followed)
    that this user may read (so that every reader says the same when it may not)."""
    try:
        st = os.stat(path)
    except FileNotFoundError:
        raise RttaError("no such file", path) from None
    except NotADirectoryError:
        raise RttaError("no such file (a part of the path is not a folder)", path) from None
    except OSError as exc:
        raise RttaError(f"cannot read the {what} ({reason(exc)})", path) from None
    except ValueError:  # NUL byte in the path
        raise RttaError("the path contains a NUL byte", str(path).replace("\0", "\\0")) from None
    if stat.S_ISDIR(st.st_mode):
        raise RttaError(f"is a directory, expected a {what}", path)
    if not stat.S_ISREG(st.st_mode):
        must = f"; the {what} must be a file" if what.strip() else ""
        raise RttaError(f"is not a regular file (a FIFO, device or socket){must}", path)
    try:
        with open(path, "rb"):
            pass
    except OSError as exc:
        raise RttaError(f"cannot read the {what} ({reason(exc)})", path) from None
    return st.st_size


def local_file(uri: str, path: Path, what: str) -> Path:
    """The file a URI in a scene names, inside the scene's folder (no URLs, no '..' out of
    it, no absolute paths)."""
    if re.match(r"^[a-zA-Z][a-zA-Z0-9+.-]*:", uri) and not re.match(r"^[a-zA-Z]:[\\/]", uri):
        raise RttaError(f"{what} '{uri[:80]}' is a URL; only files next to the scene are read", path)
    name = unquote(uri)
    if "\0" in name:
        raise RttaError(f"{what} '{uri[:80]!r}' contains a NUL byte", path)
    folder = path.resolve().parent
    try:
        target = (folder / name).resolve()
    except (OSError, RuntimeError):
        raise RttaError(f"{what} '{uri[:80]}' cannot be resolved (a link loop?)", path) from None
    if Path(name).is_absolute() or folder not in target.parents:
        raise RttaError(f"{what} '{uri[:80]}' is outside the scene's folder", path)
    return target


def read_limited(target: Path, path: Path, what: str) -> bytes:
    """The bytes of `target`, a regular file within the size limits; RttaError(`what` <problem>)
    naming the scene `path` otherwise."""
    try:
        size = regular_file(target, what)
    except RttaError as exc:
        problem = "is missing" if exc.message.startswith("no such file") else exc.message
        problem = problem.replace(f"cannot read the {what} (", "cannot be read (")
        raise RttaError(f"{what} {problem}", path) from None
    if size > min(MAX_FILE_BYTES, memory_limit()):
        raise RttaError(f"{what} has {size:,} bytes, over the memory limit (RTTA_MEMORY_LIMIT_MB)", path)
    try:
        with open(target, "rb") as f:
            return f.read(size + 1)[:size]
    except OSError as exc:
        raise RttaError(f"{what} cannot be read ({reason(exc)})", path) from None


class TextureBudget:
    """The memory a scene's textures may take together (decoded RGBA, the material atlas's
    copy and its mip levels: TEXTURE_BYTES_PER_PIXEL each), half the memory limit; many
    large textures that each compress to a few KiB must not add up to gigabytes."""

    def __init__(self) -> None:
        self.left = memory_limit() // 2

    def take(self, w: int, h: int) -> str | None:
        need = w * h * TEXTURE_BYTES_PER_PIXEL
        if need > self.left:
            return f"is {w}x{h} pixels, more than the textures' share of the memory limit has left"
        self.left -= need
        return None


def image_problem(stream: io.BytesIO, budget: TextureBudget | None = None) -> str | None:
    """Why an image cannot be used as a texture (None if it can): not an image, damaged,
    more pixels than MAX_TEXTURE_PIXELS, or over what `budget` has left. Only the header
    and structure are read."""
    from PIL import Image

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            with Image.open(stream) as im:
                w, h = im.size
                if w < 1 or h < 1:
                    return "is an empty image"
                if w * h > MAX_TEXTURE_PIXELS:
                    return f"is {w}x{h} pixels, too large to use (at most {MAX_TEXTURE_PIXELS:,} pixels)"
                im.verify()
        except Image.DecompressionBombError:
            return "is too large to decode (a decompression bomb?)"
        except Exception:
            return "cannot be read as an image"
    return budget.take(w, h) if budget is not None else None


def open_image(path: Path, what: str = "image"):
    """A PIL image from a regular file, checked as textures are (size, damage), decoded; no
    decompression-bomb warning reaches stderr."""
    from PIL import Image

    try:
        regular_file(path, what)
    except RttaError as exc:
        raise RttaError(f"no such {what} file" if exc.message == "no such file" else exc.message, path) from None
    data = read_limited(path, path, f"the {what}")
    problem = image_problem(io.BytesIO(data))
    if problem:
        raise RttaError(f"{what} {problem}", path)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            im = Image.open(io.BytesIO(data))
            im.load()
        except Exception as exc:
            raise RttaError(f"cannot read the {what} ({reason(exc)})", path) from None
    return im


class SafeResolver:
    """A trimesh resolver over the scene's folder that reads only regular files inside it,
    within the limits; images are checked first. What it refuses becomes a warning (the
    loaders treat a failed read as a missing material or texture), and it remembers every
    file it read (`inputs`)."""

    def __init__(self, scene: Path) -> None:
        self.scene = scene
        self.parent = str(scene.resolve().parent)
        self.file_name = scene.name
        self.file_path = str(scene)
        self.inputs: list[Path] = []
        self.warnings: list[str] = []
        self.budget = TextureBudget()

    def get(self, name: str) -> bytes:
        name = str(name)
        candidates = (name.strip(), name.strip().lstrip("/"), re.split(r"[\\/]", name.strip())[-1])
        problem = None
        for candidate in dict.fromkeys(candidates):
            try:
                target = local_file(candidate, self.scene, "file")
                data = read_limited(target, self.scene, "")
            except RttaError as exc:  # said of the name by _warn: not twice
                problem = problem or exc.message.removeprefix(f"file '{candidate[:80]}' ").strip()
                continue
            if target.suffix.lower() in IMAGE_SUFFIXES:
                bad = image_problem(io.BytesIO(data), self.budget)
                if bad:
                    self._warn(name, bad)
                    raise OSError(bad)
            self.inputs.append(target)
            return data
        self._warn(name, problem or "is missing")
        raise OSError(problem or "missing")

    def _warn(self, name: str, problem: str) -> None:
        what = "texture" if Path(name).suffix.lower() in IMAGE_SUFFIXES else "file"
        note = f"{what} '{name[:120]}' {problem}"
        if what == "texture":
            note += "; objects using it keep their material colour"
        if note not in self.warnings:
            self.warnings.append(note)

    def __getitem__(self, name: str) -> bytes:
        return self.get(name)

    def namespaced(self, namespace: str) -> SafeResolver:
        return self

    def keys(self):
        return iter(())

    def write(self, name: str, data) -> None:
        raise OSError("rtta never writes next to a scene")
