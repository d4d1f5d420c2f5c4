"""`rtta bench formats`: per scene file, the time the format's own library takes to read it
(trimesh, cascadio through trimesh, ifcopenshell's geometry iterator, usd-core) against
rtta's whole load (the library plus the tree, checks, normals and batching), and rtta's
overhead, which the issue bounds at 2 s."""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from pathlib import Path
from typing import TypeVar

from ..errors import RttaError
from ..outputs import write_text
from ..scene import readers
from ..scene.files import regular_file
from ..scene.loader import load_scene
from .tables import print_table

COLUMNS = ["format", "file", "parts", "triangles", "library load s", "rtta load s", "overhead s"]
OVERHEAD_S = 2.0
REPEATS = 2
SHARED = Path("../shared/data")


def library_load(path: Path) -> None:
    """What the format's library itself does to read the file, as a user of it would."""
    suffix = path.suffix.lower()
    if suffix == ".ifc":
        import ifcopenshell
        import ifcopenshell.geom

        model = ifcopenshell.open(str(path))
        settings = ifcopenshell.geom.settings()
        settings.set("use-world-coords", True)
        it = ifcopenshell.geom.iterator(settings, model, 4)
        ok = it.initialize()
        while ok:
            it.get()
            ok = it.next()
    elif suffix in (".usd", ".usda", ".usdc", ".usdz"):
        from pxr import Usd, UsdGeom

        stage = Usd.Stage.Open(str(path))
        for prim in Usd.PrimRange.Stage(stage, Usd.TraverseInstanceProxies(Usd.PrimDefaultPredicate)):
            if prim.IsA(UsdGeom.Mesh):
                UsdGeom.Mesh(prim).GetPointsAttr().Get()
    else:
        import trimesh

        trimesh.load(str(path), force="scene")  # STEP: cascadio through trimesh


def _files(paths: list[str]) -> list[Path]:
    if paths:
        files = [Path(p) for p in paths]
        for path in files:  # missing or unreadable: one line, before the libraries' own errors
            regular_file(path, "scene file")
        return files
    if not SHARED.is_dir():
        raise RttaError(f"no files given and {SHARED} does not exist")
    known = readers.SUFFIXES
    return sorted(p for p in SHARED.iterdir() if p.suffix.lower() in known)


T = TypeVar("T")


def _best(fn: Callable[[], T], runs: int = REPEATS) -> tuple[float, T]:
    """The fastest of `runs` calls (the first also pays imports and cold caches) and a result."""
    t0 = time.perf_counter()
    out = fn()
    best = time.perf_counter() - t0
    for _ in range(runs - 1):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def run_formats(paths: list[str], json_path: str | None = None) -> int:
    rows = []
    with readers.native_output():
        for path in _files(paths):
            lib, _ = _best(lambda p=path: library_load(p))
            ours, scene = _best(lambda p=path: load_scene(p, cache=False))
            rows.append(
                [
                    path.suffix.lower()[1:],
                    path.name,
                    scene.count,
                    len(scene.indices) // 3,
                    round(lib, 3),
                    round(ours, 3),
                    round(ours - lib, 3),
                ]
            )
    print_table(COLUMNS, rows)
    worst = max((r[-1] for r in rows), default=0.0)
    print(
        f"rtta's overhead over the library: at most {worst:.2f} s "
        f"({'within' if worst <= OVERHEAD_S else 'OVER'} the {OVERHEAD_S:g} s bound)"
    )
    if json_path:
        write_text(json_path, json.dumps({"columns": COLUMNS, "rows": rows}, indent=1))
    return 0 if worst <= OVERHEAD_S else 1
