"""Headless snapshots: `std` or one of the composite modes, as RGBA arrays or PNG files."""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from functools import lru_cache
from pathlib import Path
from typing import Literal

import numpy as np

from ..errors import RttaError
from ..ldi.lens import SHAPES, Lens, LensShape, default_placement
from ..outputs import atomic_write_all, to_image
from ..passes.composite import BACKGROUND, MODES, Style
from ..passes.projector import Projector, default_image, load_image
from ..scene.camera import Camera, parse_orbit
from ..scene.model import Scene
from ..scene.select import resolve_names
from .renderer import Renderer

SNAPSHOT_MODES = ("std", *MODES)
SnapshotModeName = Literal["std", "sprites", "transparent", "ghosted", "ghosted-ao"]  # STD or a Mode
__all__ = ["SNAPSHOT_MODES", "over_background", "parse_opacities", "render_modes", "resolve_names", "write_pngs"]


def parse_opacities(scene: Scene, items: list[str]) -> dict[int, float]:
    out = {}
    for item in items:
        name, sep, value = item.rpartition("=")
        try:
            alpha = float(value)
        except ValueError:
            alpha = float("nan")
        if not sep or not np.isfinite(alpha) or not 0.0 <= alpha <= 1.0:
            raise RttaError(f"--opacity expects NAME=A with A in [0, 1], got '{item}'")
        for oid in resolve_names(scene, [name], "--opacity"):
            out[oid] = alpha
    return out


def make_lens(scene: Scene, spec: str, at: str | Sequence[float] | None, focus: Iterable[int]) -> Lens:
    """--lens SHAPE[,RADIUS] or --lens NAME, placed by --lens-at X,Y,Z (default: on the focus)."""
    center, radius = default_placement(scene, focus)
    if at is not None:
        text = at if isinstance(at, str) else ",".join(str(v) for v in at)
        try:
            center = np.array([float(v) for v in text.split(",")], float)
        except ValueError:
            center = np.zeros(0)
        if center.shape != (3,) or not (np.abs(center) <= 1e15).all():  # NaN fails too
            raise RttaError(f"--lens-at must be X,Y,Z with |values| up to 1e15, got '{text}'")
    kind, _, size = spec.partition(",")
    if kind in SHAPES:
        try:
            radius = float(size) if size else radius
        except ValueError:
            radius = float("nan")
        if not 0 < radius <= 1e15:
            raise RttaError(f"--lens radius must be a number in (0, 1e15], got '{size}'")
        return Lens.shape(LensShape(kind), center, radius)
    if size:
        raise RttaError(f"--lens {kind}: an object lens takes no radius")
    (oid,) = resolve_names(scene, [kind], "--lens", groups=False)
    lens = Lens.of_object(scene, oid)
    if at is not None:
        lens.center = center
    return lens


def make_projector(scene: Scene, camera: Camera, spec: str, fov: float = 30.0, shadows: bool = True) -> Projector:
    """--projector IMAGE[,AZ,EL,DIST]: the image file (or 'default') and where it stands
    (without an orbit, at the camera)."""
    name, orbit = spec, None
    parts = spec.rsplit(",", 3)
    if len(parts) == 4:
        try:
            orbit = parse_orbit(",".join(parts[1:]), "--projector", spec)
            name = parts[0]
        except RttaError:  # a file name with commas, or an image with a bad orbit
            if not Path(spec).exists() and (parts[0] == "default" or Path(parts[0]).exists()):
                raise
            orbit = None
    if not 0.5 <= fov <= 170:
        raise RttaError(f"--projector-fov must be in [0.5, 170] degrees, got {fov}")
    image = _default_image() if name == "default" else load_image(name)
    kw = {"image": image, "fov_y": fov, "shadows": shadows}
    if orbit is None:
        return Projector.at_camera(camera, scene.center, scene.radius, **kw)
    return Projector.orbit(scene.center, scene.radius, *orbit, up_axis=scene.up_axis, **kw)


@lru_cache(maxsize=1)
def _default_image() -> np.ndarray:
    """One shipped image per process: the projector pass re-uploads only when the array changes."""
    image = default_image()
    image.setflags(write=False)
    return image


def over_background(rgba: np.ndarray, background=BACKGROUND[:3]) -> np.ndarray:
    """Colour with alpha 0 where empty (STD, atlas layers) over a background, as opaque RGBA8."""
    a = rgba[..., 3:4].astype(np.float64) / 255.0
    bg = np.array(background) * 255.0
    rgb = rgba[..., :3] * a + bg * (1.0 - a)
    return np.concatenate([np.rint(rgb), np.full(a.shape, 255.0)], -1).astype(np.uint8)


def render_modes(renderer: Renderer, camera: Camera, viewport: tuple[int, int], modes, style: Style) -> dict:
    """One capture, then each requested mode composited from it: {mode: rgba [H, W, 4] (row 0 bottom)}."""
    out = {}
    if any(m != "std" for m in modes):
        renderer.capture(
            camera, viewport, focus=style.focus, normals=any(map(renderer.needs_normals, modes)), ids=False
        )  # no mode reads the id image
    for mode in modes:
        if mode == "std":
            out[mode] = over_background(renderer.std(camera, viewport, style.focus).read(viewport, 1)["color"][0])
        else:
            rgba, _ = renderer.composite(mode, style).read()
            out[mode] = rgba.copy()
    return out


def write_pngs(images: dict, paths: dict, also: Sequence[tuple] = ()) -> list[Path]:
    """Each image to its path, and each (path, write) of `also` (a --save-view), all of them or
    none (a full disk leaves no new file and every old one whole); their renames end the
    command (see rtta.outputs)."""

    def image(rgba_gl: np.ndarray, path: Path):
        return lambda tmp: save_image(to_image(rgba_gl), tmp, Path(path).suffix)

    writes = ((paths[mode], image(rgba, paths[mode])) for mode, rgba in images.items())
    return atomic_write_all([*writes, *also], final=True)


IMAGE_FORMATS = {".png": "PNG", ".jpg": "JPEG", ".jpeg": "JPEG", ".webp": "WEBP", ".tif": "TIFF", ".tiff": "TIFF"}


def save_image(im, target, suffix: str) -> None:
    """`im` (RGBA) written to `target` in the format of `suffix` (IMAGE_FORMATS): JPEG, which
    has no alpha, over white (a snapshot is opaque), at quality 95; WebP lossless."""
    kind = IMAGE_FORMATS[suffix.lower()]
    if kind == "JPEG":
        from PIL import Image

        flat = Image.alpha_composite(Image.new("RGBA", im.size, (255, 255, 255, 255)), im).convert("RGB")
        flat.save(target, format=kind, quality=95)
    else:
        im.save(target, format=kind, **({"lossless": True} if kind == "WEBP" else {}))
