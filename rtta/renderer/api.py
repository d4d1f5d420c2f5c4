"""One call per picture for notebooks and scripts: `rtta.snapshot` and `rtta.capture`.

Beside the Renderer (for those who manage contexts and frames themselves), these take a
scene, a path or None (the built-in demo) and keyword arguments that mirror the CLI flags,
and give numpy arrays without going through files. They use the process's one headless
context (`shared_context`, the CLI's too: contexts are costly and creating many leaks), keep
a few loaded scenes (per path, mtime and load options) and one Renderer for the scene of
the last call; a call on another scene releases the old renderer's GPU resources first, so
nothing on the GPU grows with the number of calls. Not thread-safe: call from one thread.

The option builders (`make_settings`, `make_style`, `orbit_camera`, `check_size`) are in
.options, shared with `rtta snapshot` / `rtta export` so both read options alike; `Capture`
is in .captured. Both are re-exported here.
"""

from __future__ import annotations

import os
import warnings
from collections import OrderedDict
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path

import moderngl
import numpy as np

from ..errors import RttaError
from ..gl.context import Capabilities, CapturePath, CapturePathName, shared_context
from ..ldi.lens import Lens
from ..passes.projector import Projector
from ..scene.bounds import Bounds, BoundsName
from ..scene.camera import Camera, Projection
from ..scene.cutaway import Caps, SectionPlane, SectionScope
from ..scene.explode import ExplodeScope
from ..scene.framing import StandardView
from ..scene.loader import load_scene
from ..scene.model import Scene
from ..scene.preprocess import DEFAULT_SMOOTH_ANGLE
from .captured import Capture, empty_atlas
from .export import read_frame, records_json
from .options import (
    CORE_STYLE,
    STYLE_KEYS,
    check_choice,
    check_size,
    make_settings,
    make_style,
    opacities,
    orbit_camera,
    style_keywords,
)
from .placing import check_staging, make_staging, restage
from .renderer import Renderer, Settings
from .snapshot import SNAPSHOT_MODES, SnapshotModeName, make_lens, make_projector, render_modes, resolve_names

__all__ = [
    "CORE_STYLE",
    "STYLE_KEYS",
    "Capture",
    "capture",
    "check_size",
    "context",
    "make_settings",
    "make_style",
    "orbit_camera",
    "release",
    "snapshot",
]
SceneLike = Scene | str | os.PathLike | None
SCENE_CACHE = 4  # loaded scenes kept (CPU memory only)


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
    mode: SnapshotModeName = "ghosted-ao",
    *,
    focus: str | Iterable[str] = (),
    opacity: Mapping[str, float] | None = None,
    camera: Camera | str | Sequence[float] | None = None,
    size: Sequence[int] = (1024, 768),
    fov: float = 45.0,
    border: int = 1,
    atlas_max: str | tuple[int, int] | None = None,
    max_layers: int | None = None,
    capture_path: CapturePathName | CapturePath = "auto",
    region_scale: float = 1.0,
    context_scale: float | None = None,
    bounds: BoundsName | Bounds = "aabb",
    projector: str | Projector | None = None,
    projector_fov: float = 30.0,
    projector_shadows: bool = True,
    lens: str | Lens | None = None,
    lens_at: str | Sequence[float] | None = None,
    smooth_angle: float = DEFAULT_SMOOTH_ANGLE,
    smooth: bool = False,
    projection: Projection = "perspective",
    view: StandardView | None = None,
    hidden: str | Iterable[str] = (),
    sections: Iterable[str | SectionPlane] = (),
    caps: Caps = "solid",
    section_scope: SectionScope = "all",
    explode: float = 0.0,
    explode_scope: ExplodeScope = "all",
    **style,
) -> np.ndarray:
    """Render one picture of a scene in a compositing mode, headless.

    The picture `rtta snapshot --mode MODE --out` writes, pixel for pixel. The process's one
    headless context is made on the first call and reused; scenes are cached by path and
    modification time.

    Parameters
    ----------
    scene : str, Path, Scene or None
        A scene file, a loaded `Scene`, or None for the built-in demo.
    mode : str, default "ghosted-ao"
        "std", "sprites", "transparent", "ghosted" or "ghosted-ao".
    focus : str or iterable of str
        Objects highlighted (the focus set of the ghosted modes): names, group names or globs.
    opacity : mapping of str to float, optional
        Opacity per object or group name, in `transparent`.
    camera : Camera, str or sequence of float, optional
        An orbit (azimuth, elevation, distance in bounding radii), "AZ,EL,DIST", or a `Camera`;
        without a distance ("AZ,EL", or None: azimuth 35, elevation 25) the view frames the
        parts not hidden.
    size : sequence of int, default (1024, 768)
        Width and height in pixels.
    fov : float, default 45
        Vertical field of view in degrees.
    border : int, default 1
        Empty texels around each atlas region.
    atlas_max : str or tuple of int, optional
        The atlas's largest layer, "WxH" or (W, H); default the viewport plus the border.
    max_layers : int, optional
        The most atlas layers; regions are scaled down beyond them.
    capture_path : str, default "auto"
        "vs" (vertex shader, `GL_ARB_shader_viewport_layer_array`), "gs" (geometry shader) or "auto".
    region_scale : float, default 1
        Atlas texels per viewport pixel.
    context_scale : float, optional
        Texels per pixel of objects outside the focus, as a share of `region_scale` (0.25-1).
    bounds : str, default "aabb"
        The bounds projected for each region: "aabb", or "obb" (tighter for rotated parts).
    projector : str or Projector, optional
        "IMAGE[,AZ,EL,DIST]" as `--projector` takes it ("default" is the shipped grid).
    projector_fov : float, default 30
        The projector's field of view in degrees.
    projector_shadows : bool, default True
        Whether objects shadow the projected image.
    lens : str or Lens, optional
        "sphere[,R]", "box[,R]" or an object's name: cuts the context away in the ghosted modes.
    lens_at : str or sequence of float, optional
        The lens's centre "X,Y,Z" (default: the centre of the focus).
    smooth_angle : float, default 30
        Normals made at load are smoothed across faces within this angle (degrees).
    smooth : bool, default False
        Smooth the file's own normals too.
    projection : {"perspective", "ortho"}, default "perspective"
        An orthographic view shows at every depth the scale a perspective one shows at the target.
    view : {"front", "back", "left", "right", "top", "bottom", "iso"}, optional
        A standard view relative to the file's up axis (instead of the camera's direction).
    hidden : str or iterable of str
        Objects left out (names, group names or globs): not drawn, captured nor framed.
    sections, caps, section_scope, explode, explode_scope
        Cutaway and exploded view as the flags `--section SPEC` (each "x=V", "-x=V", ... or
        "nx,ny,nz,d", or a SectionPlane), `--caps`, `--section-scope`, `--explode F`, `--explode-scope`.
    **style
        Style keywords (see `Style`): context_opacity, desaturate, edge_width, edge_color,
        outline_width, outline_color, ao_radius, ao_strength, ao_objects, edge_objects, order,
        halo, default_opacity.

    Returns
    -------
    numpy.ndarray
        RGBA uint8 [H, W, 4], row 0 at the top (as images are).

    Raises
    ------
    RttaError
        An unreadable scene, an unknown object or keyword (with the close matches), a bad value.

    Examples
    --------
    >>> import rtta
    >>> rgba = rtta.snapshot(None, mode="ghosted", focus=["piston_1", "piston_2"], size=(320, 240))
    >>> rgba.shape
    (240, 320, 4)
    """
    check_choice("mode", mode, SNAPSHOT_MODES)
    extra = style_keywords(style)
    scene = _session.scene(scene, smooth_angle, smooth)
    viewport = check_size(size)
    hidden_ids = resolve_names(scene, [hidden] if isinstance(hidden, str) else list(hidden), "hidden")
    staging = make_staging(sections, caps, section_scope, explode, explode_scope)
    focus_ids = resolve_names(scene, [focus] if isinstance(focus, str) else list(focus), "focus")
    framed = check_staging(staging, scene, focus_ids, hidden_ids)
    cam = orbit_camera(
        framed, camera, fov, projection=projection, view=view, aspect=viewport[0] / viewport[1], hidden=hidden_ids
    )
    st = make_style(focus_ids, opacities(scene, opacity or {}), **{k: style[k] for k in CORE_STYLE if k in style})
    for key, value in extra.items():
        setattr(st, key, value)
    settings = make_settings(border, atlas_max, max_layers, capture_path, region_scale, bounds, context_scale)
    if isinstance(projector, str):
        projector = make_projector(scene, cam, projector, projector_fov, projector_shadows)
    if isinstance(lens, str):
        lens = make_lens(framed, lens, lens_at, st.focus)  # on the focus where explode moved it
    renderer = _prepare(scene, settings, projector, lens, hidden_ids, staging)
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
    capture_path: CapturePathName | CapturePath = "auto",
    region_scale: float = 1.0,
    bounds: BoundsName | Bounds = "aabb",
    smooth_angle: float = DEFAULT_SMOOTH_ANGLE,
    smooth: bool = False,
    projection: Projection = "perspective",
    view: StandardView | None = None,
    hidden: str | Iterable[str] = (),
    sections: Iterable[str | SectionPlane] = (),
    caps: Caps = "solid",
    explode: float = 0.0,
) -> Capture:
    """Capture one frame: every object's unoccluded images, as arrays.

    What `rtta export` writes: the atlas (every object's amodal colour, normal, depth and id in
    its region), the records of Algorithm 1 and the direct render. The atlas options are those
    of `snapshot`.

    Parameters
    ----------
    scene : str, Path, Scene or None
        A scene file, a loaded `Scene`, or None for the built-in demo.
    camera : Camera, str or sequence of float, optional
        An orbit (azimuth, elevation, distance in bounding radii), "AZ,EL,DIST", or a `Camera`.
    size : sequence of int, default (1024, 768)
        Width and height in pixels.
    fov : float, default 45
        Vertical field of view in degrees.
    border : int, default 1
        Empty texels around each atlas region.
    atlas_max : str or tuple of int, optional
        The atlas's largest layer, "WxH" or (W, H).
    max_layers : int, optional
        The most atlas layers.
    capture_path : str, default "auto"
        "vs", "gs" or "auto".
    region_scale : float, default 1
        Atlas texels per viewport pixel.
    bounds : str, default "aabb"
        "aabb" or "obb".
    smooth_angle : float, default 30
        Normals made at load are smoothed across faces within this angle (degrees).
    smooth : bool, default False
        Smooth the file's own normals too.
    projection : {"perspective", "ortho"}, default "perspective"
        The projection, as in `snapshot`.
    view : {"front", "back", "left", "right", "top", "bottom", "iso"}, optional
        A standard view relative to the file's up axis, as in `snapshot`.
    hidden : str or iterable of str
        Objects left out (not drawn, captured nor framed), as in `snapshot`.
    sections, caps, explode
        Cut and exploded, as in `snapshot` (no focus here: every part is cut and moved).

    Returns
    -------
    Capture
        The frame's arrays; row 0 is the bottom row (GL's order, as in the export's .npy files).

    Examples
    --------
    >>> import rtta
    >>> cap = rtta.capture(None, size=(320, 240))
    >>> alone = cap.amodal("piston_1")  # the whole piston, where the caliper hides it too
    >>> alone["color"].shape
    (240, 320, 4)
    """
    scene = _session.scene(scene, smooth_angle, smooth)
    viewport = check_size(size)
    hidden_ids = resolve_names(scene, [hidden] if isinstance(hidden, str) else list(hidden), "hidden")
    staging = make_staging(sections, caps, "all", explode)
    framed = check_staging(staging, scene, (), hidden_ids)
    aspect = viewport[0] / viewport[1]
    cam = orbit_camera(framed, camera, fov, projection=projection, view=view, aspect=aspect, hidden=hidden_ids)
    settings = make_settings(border, atlas_max, max_layers, capture_path, region_scale, bounds)
    renderer = _prepare(scene, settings, None, None, hidden_ids, staging)
    try:
        records, atlas, std = read_frame(renderer, cam, viewport)
    except ValueError as exc:
        raise RttaError(str(exc)) from None
    meta = records_json(renderer, cam, records, viewport)
    atlas = atlas if atlas is not None else empty_atlas()
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


def _prepare(scene: Scene, settings: Settings, projector: Projector | None, lens: Lens | None, hidden=(), staging=None):
    renderer = _session.renderer_for(scene, settings)
    renderer.projector, renderer.lens = projector, lens
    restage(renderer, staging)
    renderer.hidden = set(hidden)
    if projector is not None:
        # the projector pass re-uploads when id(image) changes; keeping the last image alive
        # means no later image can reuse its id while the pass still holds its texture
        _session.image = projector.image
    return renderer
