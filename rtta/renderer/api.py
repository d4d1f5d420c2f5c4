"""One call per picture for notebooks and scripts: `rtta.snapshot` and `rtta.capture`.

Beside the Renderer (for those who manage contexts and frames themselves), these take a
scene, a path or None (the built-in demo) and keyword arguments that mirror the CLI flags,
and give numpy arrays without going through files. They use the process's one headless
context (`shared_context`, the CLI's too: contexts are costly and creating many leaks), keep
a few loaded scenes (per path, mtime and load options) and one Renderer for the scene of
the last call; a call on another scene releases the old renderer's GPU resources first, so
nothing on the GPU grows with the number of calls. Not thread-safe: call from one thread.

The option builders here (`make_settings`, `make_style`, `orbit_camera`, `check_size`; and
`make_lens`, `make_projector` in .snapshot) are shared with `rtta snapshot` / `rtta export`,
so both read options alike.
"""

from __future__ import annotations

import difflib
import os
import warnings
from collections import OrderedDict
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import moderngl
import numpy as np

from ..atlas.parameterize import Records
from ..errors import RttaError
from ..gl.context import Capabilities, shared_context
from ..gl.readback import map_back
from ..ldi.lens import Lens
from ..passes.composite import Style
from ..passes.oit import ORDERS
from ..passes.projector import Projector
from ..scene.camera import DEFAULT_ORBIT, Camera, parse_orbit
from ..scene.loader import load_scene
from ..scene.model import Scene
from ..scene.preprocess import DEFAULT_SMOOTH_ANGLE
from .export import read_frame, records_json
from .renderer import Renderer, Settings
from .snapshot import SNAPSHOT_MODES, make_lens, make_projector, render_modes, resolve_names

SceneLike = Scene | str | os.PathLike | None
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
SCENE_CACHE = 4  # loaded scenes kept (CPU memory only)


# ---- option builders shared with the CLI ------------------------------------------------


def make_settings(
    border: int = 1,
    atlas_max: str | tuple[int, int] | None = None,
    max_layers: int | None = None,
    capture_path: str = "auto",
    region_scale: float = 1.0,
    bounds: str = "aabb",
    context_scale: float | None = None,
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
    _choice("--capture-path", capture_path, ("auto", "vs", "gs"))
    _choice("--bounds", bounds, ("aabb", "obb"))
    return Settings(
        border=border,
        atlas_max=atlas_max,
        max_layers=max_layers,
        capture_path=capture_path,
        region_scale=region_scale,
        bounds=bounds,
        context_scale=context_scale,
    )


def make_style(
    focus: Iterable[int] = (),
    opacity: Mapping[int, float] | None = None,
    *,
    context_opacity: float | None = None,
    edge_width: int = 1,
    ao_radius: float = 6.0,
    ao_strength: float = 1.0,
    ao_objects: str | None = None,
    edge_objects: str | None = None,
    order: str | None = None,
    halo: int = 0,
) -> Style:
    """A checked Style from object ids (resolved by the caller) and the compositing flags."""
    style = Style(focus=set(focus), opacity=dict(opacity or {}))
    if not (1 <= edge_width <= 8 and 0 < ao_radius <= 64 and 0 <= ao_strength <= 4):
        raise RttaError("--edge-width must be 1..8, --ao-radius in (0, 64], --ao-strength in [0, 4]")
    style.edge_width, style.ao_radius, style.ao_strength = edge_width, ao_radius, ao_strength
    roles = (
        ("--ao-objects", ao_objects, ("focus", "all")),
        ("--edge-objects", edge_objects, ("focus", "all")),
        ("--order", order, ORDERS),
    )
    for what, value, choices in roles:
        if value is not None:
            _choice(what, value, choices)
            setattr(style, what[2:].replace("-", "_"), value)
    if not 0 <= halo <= 32:
        raise RttaError(f"--halo must be 0..32 pixels, got {halo}")
    style.halo = halo
    if context_opacity is not None:
        if not 0.0 <= context_opacity <= 1.0:
            raise RttaError(f"--context-opacity must be in [0, 1], got {context_opacity}")
        style.context_opacity = context_opacity
    return style


def orbit_camera(scene: Scene, camera: Camera | str | Sequence[float] | None, fov: float = 45.0) -> Camera:
    """A Camera as given, or the orbit AZ,EL,DIST (degrees, degrees, scene radii) about the scene."""
    if isinstance(camera, Camera):
        return camera
    if not 1.0 <= fov <= 170.0:  # NaN fails too
        raise RttaError(f"--fov must be between 1 and 170 degrees, got {fov}")
    if camera is None:
        orbit = DEFAULT_ORBIT
    else:
        orbit = parse_orbit(camera if isinstance(camera, str) else ",".join(str(v) for v in camera))
    return Camera.orbit(scene.center, scene.radius, *orbit, fov_y=fov, up_axis=scene.up_axis)


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


def _choice(what: str, value: str, choices: Sequence[str]) -> None:
    if value not in choices:
        close = difflib.get_close_matches(str(value), choices, n=1, cutoff=0.5)
        hint = f"; did you mean {close[0]}?" if close else ""
        raise RttaError(f"{what} must be one of {', '.join(choices)}, got '{value}'{hint}")


# ---- the process's context, scenes and renderer -----------------------------------------


class _Session:
    """Loaded scenes (LRU, CPU only) and one Renderer for the last scene used."""

    def __init__(self) -> None:
        self.scenes: OrderedDict[tuple, Scene] = OrderedDict()
        self.renderer: Renderer | None = None
        self.image: np.ndarray | None = None  # the last projector image, kept alive (see _prepare)

    def scene(self, scene: SceneLike, smooth_angle: float, smooth: bool) -> Scene:
        if isinstance(scene, Scene):
            return scene
        if not 0.0 <= smooth_angle <= 180.0:
            raise RttaError(f"--smooth-angle must be between 0 and 180 degrees, got {smooth_angle:g}")
        if scene is None:
            from ..scene.generators.demo import demo_path

            scene = demo_path()
        path = Path(scene)
        try:
            st = path.stat()
        except OSError:
            return load_scene(str(path), smooth_angle=smooth_angle, smooth=smooth)  # says what is wrong
        key = (str(path.resolve()), st.st_mtime_ns, st.st_size, float(smooth_angle), bool(smooth))
        if key in self.scenes:
            self.scenes.move_to_end(key)
            return self.scenes[key]
        loaded = load_scene(str(path), smooth_angle=smooth_angle, smooth=smooth)
        for note in loaded.warnings:
            warnings.warn(f"{loaded.source}: {note}", stacklevel=3)
        self.scenes[key] = loaded
        while len(self.scenes) > SCENE_CACHE:
            self.scenes.popitem(last=False)
        return loaded

    def renderer_for(self, scene: Scene, settings: Settings) -> Renderer:
        ctx = shared_context()
        Capabilities.of(ctx).capture_path(settings.capture_path)  # a path the driver lacks: error first
        if self.renderer is None or self.renderer.scene is not scene:
            self.release()
            self.renderer = Renderer(ctx, scene, settings)
        self.renderer.settings = settings
        return self.renderer

    def release(self) -> None:
        if self.renderer is not None:
            self.renderer.release()
        self.renderer = None
        self.image = None


_session = _Session()


def release() -> None:
    """Free the GPU resources kept between calls (the next call makes them again)."""
    _session.release()


def context() -> moderngl.Context:
    """The moderngl context these calls render with (the process's one headless context)."""
    return shared_context()


# ---- the calls --------------------------------------------------------------------------


def snapshot(
    scene: SceneLike = None,
    mode: str = "ghosted-ao",
    *,
    focus: str | Iterable[str] = (),
    opacity: Mapping[str, float] | None = None,
    camera: Camera | str | Sequence[float] | None = None,
    size: Sequence[int] = (1024, 768),
    fov: float = 45.0,
    border: int = 1,
    atlas_max: str | tuple[int, int] | None = None,
    max_layers: int | None = None,
    capture_path: str = "auto",
    region_scale: float = 1.0,
    context_scale: float | None = None,
    bounds: str = "aabb",
    projector: str | Projector | None = None,
    projector_fov: float = 30.0,
    projector_shadows: bool = True,
    lens: str | Lens | None = None,
    lens_at: str | Sequence[float] | None = None,
    smooth_angle: float = DEFAULT_SMOOTH_ANGLE,
    smooth: bool = False,
    **style,
) -> np.ndarray:
    """The picture `rtta snapshot --mode MODE --out` writes, as RGBA uint8 [H, W, 4], row 0 at
    the top (as images are; pixel for pixel the PNG). `mode`: std, sprites, transparent,
    ghosted or ghosted-ao. `focus`: object names; `opacity`: name -> alpha; `camera`: (AZ, EL,
    DIST) orbit, 'AZ,EL,DIST' or a Camera; `size`: (W, H). `projector`/`lens` take the CLI's
    strings (or a Projector / Lens). Style keywords: context_opacity, edge_width, ao_radius,
    ao_strength, ao_objects, edge_objects, order, halo, desaturate, default_opacity, outline_width,
    outline_color, edge_color."""
    _choice("mode", mode, SNAPSHOT_MODES)
    extra = _style_keywords(style)
    scene = _session.scene(scene, smooth_angle, smooth)
    viewport = check_size(size)
    cam = orbit_camera(scene, camera, fov)
    focus_ids = resolve_names(scene, [focus] if isinstance(focus, str) else list(focus), "focus")
    st = make_style(focus_ids, _opacities(scene, opacity or {}), **{k: style[k] for k in CORE_STYLE if k in style})
    for key, value in extra.items():
        setattr(st, key, value)
    settings = make_settings(border, atlas_max, max_layers, capture_path, region_scale, bounds, context_scale)
    if isinstance(projector, str):
        projector = make_projector(scene, cam, projector, projector_fov, projector_shadows)
    if isinstance(lens, str):
        lens = make_lens(scene, lens, lens_at, st.focus)
    renderer = _prepare(scene, settings, projector, lens)
    try:
        rgba = render_modes(renderer, cam, viewport, [mode], st)[mode]
    except ValueError as exc:
        raise RttaError(str(exc)) from None
    return np.ascontiguousarray(rgba[::-1])


def capture(
    scene: SceneLike = None,
    *,
    camera: Camera | str | Sequence[float] | None = None,
    size: Sequence[int] = (1024, 768),
    fov: float = 45.0,
    border: int = 1,
    atlas_max: str | tuple[int, int] | None = None,
    max_layers: int | None = None,
    capture_path: str = "auto",
    region_scale: float = 1.0,
    bounds: str = "aabb",
    smooth_angle: float = DEFAULT_SMOOTH_ANGLE,
    smooth: bool = False,
) -> Capture:
    """Capture one frame and give what `rtta export` writes as arrays (see `Capture`):
    every object's amodal (unoccluded) images in the atlas, their records and the direct render."""
    scene = _session.scene(scene, smooth_angle, smooth)
    viewport = check_size(size)
    cam = orbit_camera(scene, camera, fov)
    renderer = _prepare(
        scene, make_settings(border, atlas_max, max_layers, capture_path, region_scale, bounds), None, None
    )
    try:
        records, atlas, std = read_frame(renderer, cam, viewport)
    except ValueError as exc:
        raise RttaError(str(exc)) from None
    meta = records_json(renderer, cam, records, viewport)
    if atlas is None:
        atlas = {
            "color": np.zeros((0, 0, 0, 4), np.uint8),
            "normal": np.zeros((0, 0, 0, 3), np.float32),
            "depth": np.ones((0, 0, 0), np.float32),
            "id": np.full((0, 0, 0), -1, np.int32),
        }
    return Capture(
        records=records,
        names=tuple(scene.names),
        camera=cam,
        view=np.array(meta["view"]),
        proj=np.array(meta["proj"]),
        color=atlas["color"],
        normal=atlas.get("normal"),
        depth=atlas["depth"].astype(np.float32, copy=False),
        id=atlas["id"].astype(np.int32, copy=False),
        std_color=std["color"][0],
        std_depth=std["depth"][0].astype(np.float32, copy=False),
        std_id=std["id"][0].astype(np.int32, copy=False),
    )


def _prepare(scene: Scene, settings: Settings, projector: Projector | None, lens: Lens | None) -> Renderer:
    renderer = _session.renderer_for(scene, settings)
    renderer.projector, renderer.lens = projector, lens
    if projector is not None:
        # the projector pass re-uploads when id(image) changes; keeping the last image alive
        # means no later image can reuse its id while the pass still holds its texture
        _session.image = projector.image
    return renderer


def _style_keywords(style: dict) -> dict:
    """Check the style keywords; return those beyond the CLI's four, checked."""
    for key in style:
        if key not in STYLE_KEYS:
            close = difflib.get_close_matches(key, STYLE_KEYS, n=1, cutoff=0.5)
            hint = f"; did you mean {close[0]}?" if close else f"; style keywords: {', '.join(STYLE_KEYS)}"
            raise TypeError(f"snapshot() got an unexpected keyword argument '{key}'{hint}")
    extra = {k: v for k, v in style.items() if k not in CORE_STYLE}
    for key in ("desaturate", "default_opacity"):
        if key in extra and not 0.0 <= extra[key] <= 1.0:
            raise RttaError(f"{key} must be in [0, 1], got {extra[key]}")
    if "outline_width" in extra and not 1 <= extra["outline_width"] <= 8:
        raise RttaError(f"outline_width must be 1..8, got {extra['outline_width']}")
    for key in ("outline_color", "edge_color"):
        if key in extra:
            c = tuple(float(v) for v in extra[key])
            if len(c) != 4 or not all(0.0 <= v <= 1.0 for v in c):
                raise RttaError(f"{key} must be RGBA, four numbers in [0, 1], got {extra[key]!r}")
            extra[key] = c
    return extra


def _opacities(scene: Scene, opacity: Mapping[str, float]) -> dict[int, float]:
    out = {}
    for name, alpha in opacity.items():
        if not (isinstance(alpha, (int, float)) and np.isfinite(alpha) and 0.0 <= alpha <= 1.0):
            raise RttaError(f"opacity expects name -> alpha in [0, 1], got {name!r}: {alpha!r}")
        for oid in resolve_names(scene, [name], "opacity"):  # a group or glob sets each of its objects
            out[oid] = float(alpha)
    return out


@dataclass
class Capture:
    """One captured frame, as `rtta export` writes it (README, "Export format"), in arrays.

    Atlas arrays are [layers, Th, Tw(, C)]: `color` RGBA uint8 (alpha 255 where an object
    covers the texel), `normal` float32 xyz, `depth` float32 window depth (1.0 where empty),
    `id` int32 (-1 where empty); `std_*` the direct render [H, W(, C)]. Rows follow GL window
    coordinates like the .npy files and the rectangles: row 0 is the BOTTOM row (the PNGs,
    and `snapshot`, are top row first: flip with [::-1]). `view`/`proj` are world-space.
    """

    records: Records
    names: tuple[str, ...]
    camera: Camera
    view: np.ndarray
    proj: np.ndarray
    color: np.ndarray
    normal: np.ndarray | None
    depth: np.ndarray
    id: np.ndarray
    std_color: np.ndarray
    std_depth: np.ndarray
    std_id: np.ndarray

    @property
    def viewport(self) -> tuple[int, int]:
        return self.records.viewport

    @property
    def border(self) -> int:
        return self.records.border

    @property
    def visible(self) -> np.ndarray:
        return self.records.visible

    @property
    def viewport_rect(self) -> np.ndarray:
        """[n, 4] x0, y0, x1, y1: each object's clipped projected bounds, in pixels."""
        return self.records.viewport_rect

    @property
    def atlas_rect(self) -> np.ndarray:
        """[n, 4] x, y, w, h: each object's atlas region in texels, border included."""
        return self.records.atlas_rect

    @property
    def layer(self) -> np.ndarray:
        return self.records.layer

    @property
    def scale(self) -> np.ndarray:
        """Atlas texels per viewport pixel (1 unless the atlas was too small)."""
        return self.records.scale

    def index(self, obj: str | int) -> int:
        """The id of an object given by name or id (names as `rtta info` lists them)."""
        if isinstance(obj, (int, np.integer)):
            if not 0 <= obj < len(self.names):
                raise RttaError(f"object id {obj} out of range 0..{len(self.names) - 1}")
            return int(obj)
        if obj in self.names:
            return self.names.index(obj)
        close = difflib.get_close_matches(obj, self.names, n=4, cutoff=0.5)
        raise RttaError(f"no object named '{obj}'" + (f"; did you mean {', '.join(close)}?" if close else ""))

    def region(self, obj: str | int) -> dict[str, np.ndarray]:
        """The object's atlas region (border included) of each atlas image; empty if not visible."""
        oid = self.index(obj)
        if not self.visible[oid]:
            return {k: np.zeros((0, 0, *v.shape[3:]), v.dtype) for k, v in self._atlas().items()}
        x, y, w, h = (int(v) for v in self.atlas_rect[oid])
        return {k: v[self.layer[oid], y : y + h, x : x + w].copy() for k, v in self._atlas().items()}

    def amodal(self, obj: str | int) -> dict[str, np.ndarray]:
        """The object's amodal images mapped back to the viewport [H, W(, C)] (nearest texel),
        empty (colour 0, depth 1, id -1) outside it: the whole object, occluded parts too.
        Row 0 is the bottom row, as in the other arrays."""
        return map_back(self._atlas(), self.records, self.index(obj))

    def _atlas(self) -> dict[str, np.ndarray]:
        parts = {"color": self.color, "depth": self.depth, "id": self.id}
        if self.normal is not None:
            parts["normal"] = self.normal
        return parts
