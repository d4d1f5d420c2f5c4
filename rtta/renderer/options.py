"""The option builders shared by `rtta.snapshot` / `rtta.capture` and `rtta snapshot` / `rtta export`:
checked Settings, Style and Camera from the keyword arguments or the CLI's flags, so that both
read options alike (the messages name the CLI flags). `make_lens` and `make_projector` are in
.snapshot.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable, Mapping, Sequence

import numpy as np

from ..errors import RttaError
from ..gl.context import CAPTURE_PATHS, CapturePath, CapturePathName
from ..passes.style import ORDERS, ROLES, Order, OrderName, Role, RoleName, Style
from ..scene.bounds import BOUNDS, Bounds, BoundsName
from ..scene.camera import Camera, Projection
from ..scene.framing import StandardView, scene_orbit
from ..scene.model import Scene
from .renderer import Settings
from .settings import BLEND_ON, PARAMETERIZE_ON, BlendName, ParameterizeName, ParameterizeOn
from .snapshot import resolve_names

CORE_STYLE = (
    "context_opacity",
    "edge_width",
    "ao_radius",
    "ao_strength",
    "ao_objects",
    "edge_objects",
    "order",
    "halo",
)  # checked by make_style, as the CLI's flags
STYLE_KEYS = (*CORE_STYLE, "desaturate", "default_opacity", "outline_width", "outline_color", "edge_color")


def make_settings(
    border: int = 1,
    atlas_max: str | tuple[int, int] | None = None,
    max_layers: int | None = None,
    capture_path: CapturePathName | CapturePath = "auto",
    region_scale: float = 1.0,
    bounds: BoundsName | Bounds = "aabb",
    context_scale: float | None = None,
    parameterize: ParameterizeName | ParameterizeOn = "auto",
    blend: BlendName = "auto",
) -> Settings:
    """Checked Settings (the messages name the CLI flags, as `rtta snapshot` says them)."""
    if border < 0 or border > 64:
        raise RttaError(f"--border must be between 0 and 64, got {border}")
    if max_layers is not None and max_layers < 1:
        raise RttaError(f"--max-layers must be at least 1, got {max_layers}")
    if not (0.25 <= region_scale <= 4):
        raise RttaError(f"--region-scale must be between 0.25 and 4, got {region_scale}")
    context_scale = Settings.context_scale if context_scale is None else context_scale
    if not (0.25 <= context_scale <= 1):
        raise RttaError(f"--context-scale must be between 0.25 and 1, got {context_scale}")
    atlas_max = check_size(atlas_max, "--atlas-max") if atlas_max else None
    check_choice("--capture-path", capture_path, CAPTURE_PATHS)
    check_choice("--bounds", bounds, BOUNDS)
    check_choice("--parameterize", parameterize, PARAMETERIZE_ON)
    check_choice("--blend", blend, BLEND_ON)
    return Settings(
        border=border,
        atlas_max=atlas_max,
        max_layers=max_layers,
        capture_path=capture_path,
        region_scale=region_scale,
        bounds=bounds,
        context_scale=context_scale,
        parameterize=parameterize,
        blend=blend,
    )


def make_style(
    focus: Iterable[int] = (),
    opacity: Mapping[int, float] | None = None,
    *,
    context_opacity: float | None = None,
    edge_width: int = 1,
    ao_radius: float = 6.0,
    ao_strength: float = 1.0,
    ao_objects: RoleName | Role | None = None,
    edge_objects: RoleName | Role | None = None,
    order: OrderName | Order | None = None,
    halo: int = 0,
) -> Style:
    """A checked Style from object ids (resolved by the caller) and the compositing flags."""
    style = Style(focus=set(focus), opacity=dict(opacity or {}))
    if not (1 <= edge_width <= 8 and 0 < ao_radius <= 64 and 0 <= ao_strength <= 4):
        raise RttaError("--edge-width must be 1..8, --ao-radius in (0, 64], --ao-strength in [0, 4]")
    style.edge_width, style.ao_radius, style.ao_strength = edge_width, ao_radius, ao_strength
    roles = (("--ao-objects", ao_objects, ROLES), ("--edge-objects", edge_objects, ROLES), ("--order", order, ORDERS))
    for what, value, choices in roles:
        if value is not None:
            check_choice(what, value, choices)
            setattr(style, what[2:].replace("-", "_"), value)
    if not 0 <= halo <= 32:
        raise RttaError(f"--halo must be 0..32 pixels, got {halo}")
    style.halo = halo
    if context_opacity is not None:
        if not 0.0 <= context_opacity <= 1.0:
            raise RttaError(f"--context-opacity must be in [0, 1], got {context_opacity}")
        style.context_opacity = context_opacity
    return style


def orbit_camera(
    scene: Scene,
    camera: Camera | str | Sequence[float] | None,
    fov: float = 45.0,
    *,
    projection: Projection = "perspective",
    view: StandardView | None = None,
    aspect: float = 4 / 3,
    hidden: Iterable[int] = (),
) -> Camera:
    """A Camera as given, or the orbit AZ,EL,DIST (degrees, degrees, scene radii) about the
    scene; AZ,EL or a standard `view` (front, back, left, right, top, bottom, iso: relative to
    the file's up axis) and no distance frame the parts not `hidden` in a view of `aspect`
    (rtta.scene.framing). `projection`: 'perspective' or 'ortho'."""
    if isinstance(camera, Camera):
        return camera
    if not 1.0 <= fov <= 170.0:  # NaN fails too
        raise RttaError(f"--fov must be between 1 and 170 degrees, got {fov}")
    hidden = tuple(hidden)
    orbit = scene_orbit(scene, camera, fov, projection=projection, view=view, aspect=aspect, hidden=hidden)
    return orbit.camera(scene, hidden)


def check_size(size: str | Sequence[int], what: str = "size") -> tuple[int, int]:
    """(W, H) from 'WxH' or a pair of ints, each in 1..16384 (the CLI's --size and --atlas-max)."""
    text = size if isinstance(size, str) else None
    try:
        w, h = (int(v) for v in (text.lower().split("x") if text is not None else size))
    except (TypeError, ValueError):
        expected = "WxH (e.g. 1024x768)" if text is not None else "(W, H)"
        raise RttaError(f"{what} expects {expected}, got '{size}'") from None
    if not (1 <= w <= 16384 and 1 <= h <= 16384):
        raise RttaError(f"{what} {text or f'{w}x{h}'}: width and height must be between 1 and 16384")
    return w, h


def check_choice(what: str, value: str, choices: Sequence[str]) -> None:
    """Refuse a value outside `choices`, naming the closest one."""
    if value not in choices:
        close = difflib.get_close_matches(str(value), choices, n=1, cutoff=0.5)
        hint = f"; did you mean {close[0]}?" if close else ""
        raise RttaError(f"{what} must be one of {', '.join(choices)}, got '{value}'{hint}")


def style_keywords(style: dict) -> dict:
    """Check the style keywords; return those beyond the CLI's four, checked."""
    for key in style:
        if key not in STYLE_KEYS:
            close = difflib.get_close_matches(key, STYLE_KEYS, n=1, cutoff=0.5)
            hint = f"; did you mean {close[0]}?" if close else f"; style keywords: {', '.join(STYLE_KEYS)}"
            raise TypeError(f"snapshot() got an unexpected keyword argument '{key}'{hint}")
    extra = {k: v for k, v in style.items() if k not in CORE_STYLE}
    for key in ("desaturate", "default_opacity"):
        if key in extra and not 0.0 <= _real(extra[key], text=False) <= 1.0:  # NaN and what is no number fail too
            raise RttaError(f"{key} must be in [0, 1], got {extra[key]!r}")
    if "outline_width" in extra and not 1 <= _real(extra["outline_width"], text=False) <= 8:
        raise RttaError(f"outline_width must be 1..8, got {extra['outline_width']!r}")
    for key in ("outline_color", "edge_color"):
        if key in extra:
            value = extra[key]
            c = tuple(_real(v) for v in value) if isinstance(value, (list, tuple, np.ndarray)) else ()
            if len(c) != 4 or not all(0.0 <= v <= 1.0 for v in c):
                raise RttaError(f"{key} must be RGBA, four numbers in [0, 1], got {value!r}")
            extra[key] = c
    return extra


def _real(value, text: bool = True) -> float:
    """`value` as a float; NaN for what is not a number ('red', True, None, 10**400; with
    `text` False, any string), so the range checks refuse it with their own message (a colour
    of strings raised ValueError: found by fuzzing, issue 42)."""
    if isinstance(value, (bool, np.bool_, bytes)) or (not text and isinstance(value, str)):
        return float("nan")
    try:
        return float(value)
    except (TypeError, ValueError, OverflowError):
        return float("nan")


def opacities(scene: Scene, opacity: Mapping[str, float]) -> dict[int, float]:
    out = {}
    for name, alpha in opacity.items():
        if not (isinstance(alpha, (int, float)) and np.isfinite(alpha) and 0.0 <= alpha <= 1.0):
            raise RttaError(f"opacity expects name -> alpha in [0, 1], got {name!r}: {alpha!r}")
        for oid in resolve_names(scene, [name], "opacity"):  # a group or glob sets each of its objects
            out[oid] = float(alpha)
    return out
