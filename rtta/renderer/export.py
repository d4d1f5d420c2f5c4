"""`rtta export`: per-object amodal images (atlas) plus the direct render, for pipelines.

Written to a temporary sibling folder and renamed into place, so an existing output
folder is replaced whole or not at all.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..atlas.parameterize import Records
from ..outputs import check_folder, os_error, remove_tree, replace_dir, staging_dir, to_image
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
    offsets = np.zeros((renderer.scene.count, 3)) + renderer.staging.shift
    for oid, name in enumerate(renderer.scene.names):
        vis = bool(records.visible[oid])
        objects.append(
            {
                "id": oid,
                "name": name,
                "visible": vis,
                "viewport_rect": [int(v) for v in records.viewport_rect[oid]],
                "atlas_rect": [int(v) for v in records.atlas_rect[oid]],
                "layer": int(records.layer[oid]),
                "scale": float(records.scale[oid]),
                "offset": [float(v) for v in offsets[oid]],  # world translation (explode), 0 assembled
            }
        )
    return {
        "view": view.tolist(),
        "proj": proj.tolist(),
        "viewport": list(viewport),
        "atlas": list(records.atlas_size),
        "border": records.border,
        "camera": {
            "eye": camera.eye.tolist(),
            "target": camera.target.tolist(),
            "up": camera.up.tolist(),
            "fov_y": camera.fov_y,
            "near": camera.near,
            "far": camera.far,
            "projection": camera.kind,
            "height": camera.half_height() if camera.kind == "ortho" else None,
        },
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


def export(
    renderer: Renderer,
    camera: Camera,
    viewport: tuple[int, int],
    out_dir: str | Path,
    inputs: list[str | Path] | None = None,
) -> Path:
    """Capture once and write the export format (docs/library.md) to out_dir atomically. An
    existing out_dir is replaced only when rtta export wrote it (see rtta.outputs), never
    when it holds an input (the scene's files, and `inputs`)."""
    out_dir = check_folder(out_dir, [*renderer.scene.inputs, *(inputs or [])])
    out_dir = out_dir.parent.resolve() / out_dir.name
    records, atlas, std = read_frame(renderer, camera, viewport)
    tmp = None
    try:
        tmp = staging_dir(out_dir)
        _write(tmp, renderer, camera, records, viewport, atlas, std)
        replace_dir(tmp, out_dir, final=True)
    except OSError as exc:
        raise os_error(exc, out_dir) from None
    finally:
        if tmp is not None and tmp.exists():
            remove_tree(tmp)
    return out_dir


def _write(tmp: Path, renderer: Renderer, camera: Camera, records, viewport, atlas, std) -> None:
    """The export's files into the staging folder (not yet visible under the output's name)."""
    (tmp / "records.json").write_text(json.dumps(records_json(renderer, camera, records, viewport), indent=1))
    if atlas is not None:
        for layer in range(records.atlas_size[2]):
            to_image(atlas["color"][layer]).save(tmp / f"atlas_color_{layer}.png", format="PNG")
        np.save(tmp / "atlas_depth.npy", atlas["depth"].astype(np.float32))
        np.save(tmp / "atlas_id.npy", atlas["id"].astype(np.int32))
    else:
        np.save(tmp / "atlas_depth.npy", np.ones((0, 0, 0), np.float32))
        np.save(tmp / "atlas_id.npy", np.full((0, 0, 0), -1, np.int32))
    to_image(std["color"][0]).save(tmp / "std_color.png", format="PNG")
    np.save(tmp / "std_depth.npy", std["depth"][0].astype(np.float32))
    np.save(tmp / "std_id.npy", std["id"][0].astype(np.int32))
