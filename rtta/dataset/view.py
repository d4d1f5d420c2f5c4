"""One view of `rtta dataset`: the direct render (rgb, depth, visible ids) and every object's
amodal mask from ONE RTTA capture, or, as the benchmark's baseline, from each object rendered
alone (RTT); then its COCO annotations, and the view's folder written in one rename.

Images here are in image orientation (row 0 at the top), as the files and COCO have them;
the renderer's arrays (GL, row 0 at the bottom) are flipped once on the way in.
"""

from __future__ import annotations

import shutil
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from PIL import Image

from ..outputs import staging_dir
from ..renderer.export import replace_dir, world_matrices
from ..renderer.renderer import Renderer
from ..scene.camera import Camera, view_depth
from .alone import Alone, alone_rtt, alone_rtta
from .coco import encode_flat

PNG_LEVEL = 1  # zlib level of every PNG written: 3-4x faster than Pillow's 6, files ~20% larger
MAX_PNG_ID = 65534  # visible_id.png holds id + 1 in 16 bits; larger scenes get visible_id.npy


@dataclass
class View:
    """A rendered view: images, and every object in view (a non-empty rectangle) with its
    masks in the flat layout of coco.layout (what encoding reads)."""

    rgb: np.ndarray  # uint8 [H, W, 3]
    depth: np.ndarray  # float32 [H, W]: distance along the view axis, world units; 0 = none
    ids: np.ndarray  # int32 [H, W]: the front-most object, -1 = none
    oids: np.ndarray  # int64 [N]
    rects: np.ndarray  # int64 [N, 4]: x, y, w, h in image pixels (y down)
    amodal: np.ndarray  # bool, flat: the object alone (and any pixel STD shows of it)
    visible: np.ndarray  # bool, flat: where STD shows it
    nearest: np.ndarray  # float [N]: window depth of its nearest surface (1: none)
    colors: list[np.ndarray] | None = None  # RGBA [h, w, 4] of each object alone, alpha = amodal


def _std(renderer: Renderer, viewport) -> dict[str, np.ndarray]:
    """The STD render drawn last (Renderer.std), read back in image orientation."""
    std = renderer.single_target.read(viewport, 1)
    return {k: v[0][::-1] for k, v in std.items()}


def linear_depth(window: np.ndarray, proj: np.ndarray) -> np.ndarray:
    """Window depth [0, 1] -> distance along the view axis (world units); 1 (empty) -> 0."""
    z = view_depth(window, proj)  # perspective or orthographic
    return np.where(window < 1.0, z, 0.0).astype(np.float32)


def _view(std: dict, proj, objects: Alone) -> View:
    """The view from each object's image alone and the direct render: visible = STD's id,
    amodal = alone or visible, nearest depth, appearance."""
    oids, rects, lay, alone, alone_depth = objects.oids, objects.rects, objects.lay, objects.mask, objects.depth
    raw_colors = objects.colors
    h, w = std["id"].shape
    col, pix = lay["col"], lay["pixel"]
    co = lay["col_obj"]
    at = (rects[co, 1] * w + rects[co, 0] + lay["col_index"])[col] + lay["row"] * w  # image pixel, pads off
    ids = np.ascontiguousarray(std["id"]).ravel()
    visible = (ids.take(at, mode="clip") == oids[co][col]) & pix
    amodal = alone | visible
    std_depth = np.ascontiguousarray(std["depth"]).ravel().take(at, mode="clip")
    depth = np.where(alone, alone_depth, np.where(visible, std_depth, 1.0))
    nearest = np.minimum.reduceat(depth, lay["offsets"][:-1]) if len(oids) else np.zeros(0)
    colors = None
    if raw_colors is not None:
        colors = []
        for i, raw in enumerate(raw_colors):
            a, b = lay["offsets"][i : i + 2]
            shape = (rects[i, 2], rects[i, 3] + 2)
            m = {
                k: v[a:b].reshape(shape)[:, 1:-1].T for k, v in (("alone", alone), ("vis", visible), ("amodal", amodal))
            }
            color = np.array(raw)
            x, y, cw, ch = rects[i]
            extra = m["vis"] & ~m["alone"]
            color[extra] = std["color"][y : y + ch, x : x + cw][extra]
            color[..., 3] = np.where(m["amodal"], 255, 0)
            colors.append(color)
    return View(
        rgb=np.ascontiguousarray(std["color"][..., :3]),
        depth=linear_depth(std["depth"], proj),
        ids=std["id"].astype(np.int32),
        oids=oids,
        rects=rects,
        amodal=amodal,
        visible=visible,
        nearest=nearest,
        colors=colors,
    )


def render_rtta(renderer: Renderer, camera: Camera, viewport: tuple[int, int], appearance: bool = False) -> View:
    """The view from ONE capture: every object's image alone from its atlas region, and STD."""
    alone = alone_rtta(renderer, camera, viewport, appearance, queue=lambda: renderer.std(camera, viewport))
    return _view(_std(renderer, viewport), renderer.matrices(camera, viewport)[1], alone)


def render_rtt(renderer: Renderer, camera: Camera, viewport: tuple[int, int], appearance: bool = False) -> View:
    """The baseline: every object in view drawn alone with RTT and read back, and STD."""
    renderer.std(camera, viewport)
    std = _std(renderer, viewport)  # before RTT, which draws into the same target
    return _view(std, renderer.matrices(camera, viewport)[1], alone_rtt(renderer, camera, viewport, appearance))


def camera_entry(renderer: Renderer, camera: Camera, viewport: tuple[int, int]) -> dict:
    """`view` and `proj` exactly as records.json has them, the intrinsics K (OpenCV convention:
    x right, y down, z forward = view's y and z negated; pixel (0, 0) is the top-left corner
    of the top-left pixel), and the camera's own parameters."""
    view, proj = world_matrices(renderer, camera, viewport)
    used, _ = camera.depth_limited()
    w, h = viewport
    k = [
        [proj[0, 0] * w / 2, 0.0, w / 2 * (1 - proj[0, 2])],
        [0.0, proj[1, 1] * h / 2, h / 2 * (1 + proj[1, 2])],
        [0.0, 0.0, 1.0],
    ]
    return {
        "view": view.tolist(),
        "proj": proj.tolist(),
        "K": [[float(v) for v in row] for row in k],
        "eye": camera.eye.tolist(),
        "target": camera.target.tolist(),
        "up": camera.up.tolist(),
        "fov_y": float(camera.fov_y),
        "near": float(used.near),
        "far": float(used.far),
        "projection": camera.kind,
    }


def annotate(
    view: View, meta: list[dict], image_id: int, min_visible: int = 0, appearance_dir: str | None = None
) -> list[dict]:
    """COCO annotations (no ids yet; `category` by name) of the view's objects that cover a
    pixel. depth_order ranks them by nearest depth (0 = nearest, ties by id); objects with
    fewer than `min_visible` visible pixels are then left out."""
    h, w = view.ids.shape
    vis, vis_area, vis_box = encode_flat(view.visible, view.rects, h, w)
    amo, amo_area, amo_box = encode_flat(view.amodal, view.rects, h, w)
    shown = np.flatnonzero(amo_area > 0)
    order = np.zeros(len(view.oids), np.int64)
    order[shown[np.lexsort((view.oids[shown], view.nearest[shown]))]] = np.arange(len(shown))
    occlusion = 1.0 - vis_area / np.maximum(amo_area, 1)
    columns = [v.tolist() for v in (view.oids, vis_area, vis_box, amo_area, amo_box, occlusion, order)]
    out = []
    for i in shown[vis_area[shown] >= min_visible].tolist():
        oid, area, box, amodal_area, amodal_box, occluded, rank = (c[i] for c in columns)
        info = meta[oid]
        a = {
            "image_id": image_id,
            "category": info["category"],
            "segmentation": vis[i],
            "area": area,
            "bbox": box,
            "iscrowd": 0,
            "amodal_segmentation": amo[i],
            "amodal_area": amodal_area,
            "amodal_bbox": amodal_box,
            "occlusion_rate": occluded,
            "depth_order": rank,
            "object_id": oid,
            "object_name": info["name"],
            "object_path": info["path"],
        }
        if appearance_dir is not None and view.colors is not None:
            a["appearance"] = {"file": f"{appearance_dir}/objects/{oid:05d}.png", "rect": view.rects[i].tolist()}
        out.append(a)
    return out


def depth_scale(camera_json: dict) -> float:
    """World units per step of depth.png: the far plane at 65535."""
    return camera_json["far"] / 65535.0


def write_view(
    view: View, folder: Path, depth_format: str, scale: float, big: bool = False, keep: set[int] | None = None
) -> None:
    """rgb.png, depth.png (uint16, value x scale = world units, 0 = none) or depth.npy (float32),
    visible_id.png (uint16, id + 1, 0 = none; with `big`, scenes of over MAX_PNG_ID objects,
    visible_id.npy, uint32) and
    objects/<id>.png for the objects in `keep` with appearance, written into a temporary
    folder beside `folder` and renamed into place (an older `folder` is replaced whole)."""
    folder.parent.mkdir(parents=True, exist_ok=True)
    tmp = staging_dir(folder)  # an error names the view's folder, not the temporary
    try:
        Image.fromarray(view.rgb).save(tmp / "rgb.png", compress_level=PNG_LEVEL)
        if depth_format == "npy":
            np.save(tmp / "depth.npy", view.depth)
        else:
            steps = np.clip(np.rint(view.depth / scale), 0, 65535).astype(np.uint16)
            Image.fromarray(steps).save(tmp / "depth.png", compress_level=PNG_LEVEL)
        ids = view.ids.astype(np.int64) + 1
        if big:
            np.save(tmp / "visible_id.npy", ids.astype(np.uint32))
        else:
            Image.fromarray(ids.astype(np.uint16)).save(tmp / "visible_id.png", compress_level=PNG_LEVEL)
        crops = [
            (oid, c)
            for oid, c in zip(view.oids.tolist(), view.colors or [], strict=False)
            if keep is None or oid in keep
        ]
        if crops:
            (tmp / "objects").mkdir()
        for oid, color in crops:
            Image.fromarray(color).save(tmp / "objects" / f"{oid:05d}.png", compress_level=PNG_LEVEL)
        replace_dir(tmp, folder)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def view_files(folder_rel: str, depth_format: str, big: bool) -> dict:
    """The image entry's file fields for a view folder (relative to the dataset root)."""
    return {
        "file_name": f"{folder_rel}/rgb.png",
        "depth_file": f"{folder_rel}/depth.{depth_format}",
        "visible_id_file": f"{folder_rel}/visible_id.{'npy' if big else 'png'}",
    }
