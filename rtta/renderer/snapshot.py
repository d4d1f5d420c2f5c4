"""Headless snapshots: `std` or one of the composite modes, as RGBA arrays or PNG files."""

from __future__ import annotations

import difflib
from pathlib import Path

import numpy as np

from ..errors import RttaError
from ..imageio import save_png
from ..passes.composite import BACKGROUND, MODES, Style
from ..scene.camera import Camera
from ..scene.model import Scene
from .renderer import Renderer

SNAPSHOT_MODES = ("std", *MODES)


def resolve_names(scene: Scene, names: list[str], flag: str) -> list[int]:
    """Object ids for names; an unknown name is an error that lists close matches."""
    ids = []
    for name in names:
        if name in scene.names:
            ids.append(scene.index(name))
            continue
        close = difflib.get_close_matches(name, scene.names, n=4, cutoff=0.5)
        hint = f"; did you mean {', '.join(close)}?" if close else "; `rtta info` lists the objects"
        raise RttaError(f"{flag}: no object named '{name}' in {Path(scene.source).name}{hint}")
    return ids


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
        out[resolve_names(scene, [name], "--opacity")[0]] = alpha
    return out


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
        renderer.capture(camera, viewport, focus=style.focus)
    for mode in modes:
        if mode == "std":
            out[mode] = over_background(renderer.std(camera, viewport).read(viewport, 1)["color"][0])
        else:
            rgba, _ = renderer.composite(mode, style).read()
            out[mode] = rgba.copy()
    return out


def write_pngs(images: dict, paths: dict) -> list[Path]:
    return [save_png(paths[mode], rgba) for mode, rgba in images.items()]
