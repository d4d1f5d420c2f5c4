"""`rtta export`: per-object amodal images (atlas) plus the direct render, for pipelines.

Written to a temporary sibling folder and renamed into place, so an existing output
folder is replaced whole or not at all.
"""

from __future__ import annotations

import json
import os
import shutil
import tempfile
from pathlib import Path

import numpy as np

from ..atlas.parameterize import Records
from ..errors import RttaError
from ..imageio import save_png
from ..scene.camera import Camera
from .renderer import Renderer


def world_matrices(renderer: Renderer, camera: Camera, viewport) -> tuple[np.ndarray, np.ndarray]:
    """(view, proj) for world coordinates: clip = proj · view · [x, y, z, 1] (the renderer's
    own view matrix is relative to the scene origin)."""
    view, proj = renderer.matrices(camera, viewport)
    shift = np.identity(4)
    shift[:3, 3] = -renderer.scene.origin
    return view @ shift, proj


def records_json(renderer: Renderer, camera: Camera, records, viewport) -> dict:
    view, proj = world_matrices(renderer, camera, viewport)
    objects = []
    for oid, name in enumerate(renderer.scene.names):
        vis = bool(records.visible[oid])
        objects.append({
            "id": oid, "name": name, "visible": vis,
            "viewport_rect": [int(v) for v in records.viewport_rect[oid]],
            "atlas_rect": [int(v) for v in records.atlas_rect[oid]],
            "layer": int(records.layer[oid]), "scale": float(records.scale[oid]),
        })
    return {
        "view": view.tolist(), "proj": proj.tolist(), "viewport": list(viewport),
        "atlas": list(records.atlas_size), "border": records.border,
        "camera": {"eye": camera.eye.tolist(), "target": camera.target.tolist(), "up": camera.up.tolist(),
                   "fov_y": camera.fov_y, "near": camera.near, "far": camera.far},
        "objects": objects,
    }


def read_frame(renderer: Renderer, camera: Camera, viewport: tuple[int, int]) -> tuple[Records, dict | None, dict]:
    """Capture once and read back what an export holds: (records, atlas images [layers, Th, Tw(, C)]
    or None when nothing is visible, the direct render [1, H, W(, C)]); row 0 is the bottom row.
    Shared by `export` and `rtta.capture`."""
    records = renderer.capture(camera, viewport)
    tw, th, td = records.atlas_size
    atlas = renderer.atlas.read((tw, th), td) if td else None
    std = renderer.std(camera, viewport).read(viewport, 1)
    return records, atlas, std


def export(renderer: Renderer, camera: Camera, viewport: tuple[int, int], out_dir: str | Path) -> Path:
    """Capture once and write the export format (see README) to out_dir atomically."""
    out_dir = Path(out_dir).resolve()
    if out_dir.exists() and not out_dir.is_dir():
        raise RttaError("exists and is not a directory", out_dir)
    parent = out_dir.parent
    if not parent.is_dir():
        raise RttaError("parent directory does not exist", parent)
    records, atlas, std = read_frame(renderer, camera, viewport)
    td = records.atlas_size[2]
    tmp = Path(tempfile.mkdtemp(prefix=f".{out_dir.name}.", dir=parent))
    try:
        (tmp / "records.json").write_text(json.dumps(records_json(renderer, camera, records, viewport), indent=1))
        if atlas is not None:
            for layer in range(td):
                save_png(tmp / f"atlas_color_{layer}.png", atlas["color"][layer])
            np.save(tmp / "atlas_depth.npy", atlas["depth"].astype(np.float32))
            np.save(tmp / "atlas_id.npy", atlas["id"].astype(np.int32))
        else:
            np.save(tmp / "atlas_depth.npy", np.ones((0, 0, 0), np.float32))
            np.save(tmp / "atlas_id.npy", np.full((0, 0, 0), -1, np.int32))
        save_png(tmp / "std_color.png", std["color"][0])
        np.save(tmp / "std_depth.npy", std["depth"][0].astype(np.float32))
        np.save(tmp / "std_id.npy", std["id"][0].astype(np.int32))
        replace_dir(tmp, out_dir)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return out_dir


def replace_dir(new: Path, target: Path) -> None:
    """Swap `new` into `target`: the old folder is moved aside first and removed last."""
    if not target.exists():
        os.replace(new, target)
        return
    old = Path(tempfile.mkdtemp(prefix=f".{target.name}.old.", dir=target.parent))
    os.rmdir(old)
    os.replace(target, old)
    try:
        os.replace(new, target)
    except BaseException:
        os.replace(old, target)
        raise
    shutil.rmtree(old, ignore_errors=True)
