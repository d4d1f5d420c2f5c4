"""Every format's reader, in one table (READERS: suffix -> module here, the import it needs,
the extra that installs it, what it gives), and the one dispatch the loader calls (`load`).

The mesh formats (glTF/GLB, OBJ, STL, PLY, 3MF, OFF) are gathered by `mesh` (rtta's own
readers, else trimesh) into a Scene. The assembly formats' readers (STEP: cascadio, IFC:
ifcopenshell, USD, COLLADA, 3DXML) each return an `Assembly`: the parts in world
coordinates, in the file's own length unit, with their colours and their path in the
file's part tree; `load` batches it. A file whose extra is missing is refused with one line
naming it.
"""

from __future__ import annotations

import importlib
import importlib.util
import os
import re
import sys
import tempfile
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal, NamedTuple

import numpy as np

from ...errors import RttaError
from .. import batch
from ..model import Scene, from_batch
from ..precheck import ZIP_ERRORS, check_size


class Reader(NamedTuple):
    """How a format is read: `module` here, the import it `needs`, the `extra` that installs
    it ('' = the base install) and what the module `gives`: a 'scene' (its `load(path,
    smooth_angle, smooth)`) or an 'assembly' (its `read(path)`, batched by `load` here)."""

    module: str
    needs: str
    extra: str
    gives: Literal["scene", "assembly"]


_MESH = Reader("mesh", "trimesh", "", "scene")
READERS = {
    ".glb": _MESH,
    ".gltf": _MESH,
    ".obj": _MESH,
    ".stl": _MESH,
    ".ply": _MESH,
    ".3mf": _MESH,
    ".off": _MESH,
    ".step": Reader("step", "cascadio", "cad", "assembly"),
    ".stp": Reader("step", "cascadio", "cad", "assembly"),
    ".ifc": Reader("ifc", "ifcopenshell", "bim", "assembly"),
    ".dae": Reader("collada", "collada", "all", "assembly"),
    ".zae": Reader("collada", "collada", "all", "assembly"),
    ".usd": Reader("usd", "pxr", "usd", "assembly"),
    ".usda": Reader("usd", "pxr", "usd", "assembly"),
    ".usdc": Reader("usd", "pxr", "usd", "assembly"),
    ".usdz": Reader("usd", "pxr", "usd", "assembly"),
    ".3dxml": Reader("threedxml", "trimesh", "all", "assembly"),
}
SUFFIXES = tuple(READERS)  # every format rtta reads
MESHES = tuple(s for s, r in READERS.items() if r.gives == "scene")  # those read by `mesh`
ISOLATED = {"step": "OpenCASCADE (cascadio)", "ifc": "ifcopenshell", "usd": "USD"}  # read in a child process
MAX_COORDINATE = 1e15  # as the mesh loader's: float64 keeps ~0.1 units of precision there


@dataclass
class Assembly:
    """What a reader gives the loader: per part (name, world vertices [V,3], faces [F,3])."""

    names: list[str] = field(default_factory=list)
    vertices: list[np.ndarray] = field(default_factory=list)
    faces: list[np.ndarray] = field(default_factory=list)
    colors: list[list[float] | None] = field(default_factory=list)
    paths: list[tuple[str, ...]] = field(default_factory=list)
    unit: str = ""
    up_axis: str = "z"
    warnings: list[str] = field(default_factory=list)

    def add(self, name: str, vertices, faces, color, path: tuple[str, ...]) -> None:
        self.names.append(name)
        self.vertices.append(np.asarray(vertices, np.float64).reshape(-1, 3))
        self.faces.append(np.asarray(faces, np.int64).reshape(-1, 3))
        self.colors.append(color)
        self.paths.append(tuple(p.replace("/", "\u2215") for p in path))


def load(path: Path, smooth_angle: float, smooth: bool) -> Scene:
    """The Scene of `path` (suffix in SUFFIXES) through its reader in READERS; normals
    smoothed by `smooth_angle` degrees where the file has none, or everywhere with `smooth`.
    RttaError when it cannot be read."""
    if READERS[path.suffix.lower()].gives == "assembly":
        scene = _assembled(read(path), path, 180.0 if smooth else smooth_angle)
        scene.inputs = [str(path.resolve())]
        return scene
    module = importlib.import_module(f"{__name__}.{reader_of(path).module}")
    return module.load(path, smooth_angle, smooth)


def reader_of(path: Path) -> Reader:
    """The reader of `path`'s format (a suffix in SUFFIXES) once the import it needs is found,
    else RttaError naming the extra that installs it."""
    reader = READERS[path.suffix.lower()]
    try:
        found = importlib.util.find_spec(reader.needs) is not None
    except (ImportError, ValueError):
        found = False
    if not found:
        install = f"pip install 'rtta[{reader.extra}]'" if reader.extra else "pip install rtta"
        raise RttaError(f"reading {path.suffix.lower()} files needs {reader.needs}: {install}", path) from None
    return reader


def read(path: Path) -> Assembly:
    """The assembly in `path` (an assembly format of READERS); RttaError when it cannot be read."""
    module = reader_of(path).module
    if module in ISOLATED:  # native libraries: a crash or a hang stays in a child
        from . import isolated

        return isolated.read(f"{__name__}.{module}", path, ISOLATED[module])
    reader = importlib.import_module(f"{__name__}.{module}")
    return reader.read(path)


@contextmanager
def native_output():
    """Catch what native libraries print (OpenCASCADE's progress and errors) on the process's
    stdout and stderr: a command's output stays its own (one error line, a parseable stdout).
    Yields a list that holds the caught lines, ANSI colours removed, once the block ends."""
    caught: list[str] = []
    sys.stdout.flush()
    sys.stderr.flush()
    saved = os.dup(1), os.dup(2)
    with tempfile.TemporaryFile() as sink:  # anonymous: never next to the user's file
        try:
            os.dup2(sink.fileno(), 1)
            os.dup2(sink.fileno(), 2)
            yield caught
        finally:
            sys.stdout.flush()
            sys.stderr.flush()
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
            os.close(saved[0])
            os.close(saved[1])
            sink.seek(0)
            text = re.sub(r"\x1b\[[0-9;]*m", "", sink.read(1 << 20).decode("utf-8", "replace"))
            caught.extend(line.strip() for line in text.splitlines() if line.strip())


UNIT_NAMES = {1e-3: "mm", 1e-2: "cm", 1.0: "m", 0.0254: "in", 0.3048: "ft", 1e3: "km"}
MAX_ARCHIVE_BYTES = 2 * 1024**3


def unit_name(meters: float) -> str:
    """'mm', 'cm', 'm', 'in', 'ft' for a length unit in metres; else e.g. '0.5 m'."""
    return next((n for s, n in UNIT_NAMES.items() if abs(s - meters) <= 1e-9 * s), f"{meters:g} m")


def check_archive(path: Path) -> None:
    """A zip archive (.zae, .usdz, .3dxml) that is whole and not a zip bomb, with no member
    outside it (absolute or '..' names), before a library unpacks it."""
    import zipfile

    try:
        with zipfile.ZipFile(path) as z:
            members = z.infolist()
    except ZIP_ERRORS as exc:
        raise RttaError(f"not a readable zip archive ({exc})", path) from None
    total = sum(m.file_size for m in members)
    if total > MAX_ARCHIVE_BYTES:
        raise RttaError(f"the archive unpacks to {total:,} bytes, over the {MAX_ARCHIVE_BYTES >> 30} GiB limit", path)
    for m in members:
        name = m.filename.replace("\\", "/")
        if name.startswith("/") or ".." in name.split("/") or ":" in name.split("/")[0]:
            raise RttaError(f"archive member '{m.filename}' points outside the archive", path)


def srgb_from_linear(c) -> list[float]:
    """Linear RGB(A) in [0, 1] back to sRGB, the colour the CAD program shows; alpha kept."""
    c = np.clip(np.asarray(c, np.float64).reshape(-1), 0.0, 1.0)
    rgb = np.where(c[:3] <= 0.0031308, 12.92 * c[:3], 1.055 * c[:3] ** (1 / 2.4) - 0.055)
    return [*rgb.tolist(), *(c[3:4].tolist() or [1.0])]


def _assembled(asm: Assembly, path: Path, smooth_angle: float) -> Scene:
    """The Scene of an assembly file's parts: checked (finite, in range, within the memory
    limit), degenerate ones left out with a warning, normals smoothed by `smooth_angle`
    in the loader's whole-scene passes (rtta.scene.batch: no Python loop per part, so a
    building of 10^5 elements smooths as fast as a glTF assembly)."""
    names, arrays, colors, paths = [], [], [], []
    vertices = triangles = 0
    for name, v, f, color, group in zip(asm.names, asm.vertices, asm.faces, asm.colors, asm.paths, strict=True):
        if not len(f):
            continue
        if not np.isfinite(v).all() or np.abs(v).max() > MAX_COORDINATE:
            raise RttaError(f"part '{name}' has coordinates that are not finite or beyond ±{MAX_COORDINATE:.0e}", path)
        if f.min() < 0 or f.max() >= len(v):
            raise RttaError(f"part '{name}' has face indices out of range", path)
        vertices, triangles = vertices + len(v), triangles + len(f)
        check_size(vertices, triangles, path)
        names.append(name)
        arrays.append((v, f))
        colors.append(color)
        paths.append(group)
    every = _meshes(arrays) if arrays else None
    area = batch.has_area(every) if every is not None else np.zeros(0, bool)
    keep = np.flatnonzero(area).tolist()
    if every is None or not keep:
        raise RttaError("the file has no parts with triangle geometry", path)
    kept = every if len(keep) == len(arrays) else _meshes([arrays[i] for i in keep])
    meshes = batch.preprocess(kept, np.ones(len(keep), bool), smooth_angle)
    scene = from_batch([names[i] for i in keep], meshes, [colors[i] for i in keep], source=str(path), consume=True)
    scene.paths, scene.unit, scene.up_axis = [paths[i] for i in keep], asm.unit, asm.up_axis
    dropped = [names[i] for i in np.flatnonzero(~area)]
    if dropped:
        asm.warnings.append(
            f"{len(dropped)} part(s) with only degenerate (zero-area) triangles left out: "
            + ", ".join(dropped[:5])
            + (" ..." if len(dropped) > 5 else "")
        )
    scene.warnings = asm.warnings + scene.warnings
    return scene


def _meshes(arrays: list[tuple[np.ndarray, np.ndarray]]) -> batch.Meshes:
    """Parts (vertices, faces) as one batch.Meshes, normals to be smoothed."""
    vcount = np.array([len(v) for v, _ in arrays], np.int64)
    return batch.Meshes(
        np.concatenate([np.asarray(v, np.float64) for v, _ in arrays]),
        np.concatenate([np.asarray(f, np.int64) for _, f in arrays]),
        vcount,
        np.array([len(f) for _, f in arrays], np.int64),
        np.zeros((int(vcount.sum()), 3), np.float32),
    )


def graph_paths(loaded, nodes: list[str]) -> list[tuple[str, ...]] | None:
    """The tree above each node of a trimesh scene graph (glTF, OBJ...): its ancestors' names,
    root first, the base frame left out; None when every node sits at the top (a flat file)."""
    parents = loaded.graph.transforms.parents
    base = loaded.graph.base_frame
    out = []
    for node in nodes:
        chain, current = [], node
        while current in parents and len(chain) < 256:
            current = parents[current]
            if current == base:
                break
            chain.append(str(current).replace("/", "\u2215"))
        out.append(tuple(reversed(chain)))
    return out if any(out) else None
