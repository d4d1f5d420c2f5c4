"""Reliability runs: random extreme cameras checked against STD, and long soaks whose GL
object count and process memory must stay flat.

The GL object census asks the driver itself (glIs* over every name handed out so far),
so a leak is seen even when no Python object is left that refers to it.
"""

from __future__ import annotations

import ctypes
from collections.abc import Callable
from dataclasses import dataclass, field

import moderngl
import numpy as np

from ..gl.glraw import _lib
from ..gl.readback import to_atlas
from ..memory import rss_bytes
from ..passes.composite import MODES, Style
from ..passes.style import Mode
from ..renderer.renderer import Renderer
from ..renderer.snapshot import over_background
from ..scene.camera import Camera
from ..scene.model import Scene
from .compare import crease_limit, depth_mismatch, depth_tolerance, near_silhouettes

COLOR_TOL = 3  # of 255: the core's sprites-vs-STD tolerance
COLOR_FRACTION = 0.995  # of pixels within COLOR_TOL; depth: rtta.compare.depth_mismatch

_CENSUS = {  # kind -> (glIs*, glGen*, glDelete*); programs use glCreate/glDeleteProgram
    "buffers": ("glIsBuffer", "glGenBuffers", "glDeleteBuffers"),
    "textures": ("glIsTexture", "glGenTextures", "glDeleteTextures"),
    "framebuffers": ("glIsFramebuffer", "glGenFramebuffers", "glDeleteFramebuffers"),
    "renderbuffers": ("glIsRenderbuffer", "glGenRenderbuffers", "glDeleteRenderbuffers"),
    "vertex_arrays": ("glIsVertexArray", "glGenVertexArrays", "glDeleteVertexArrays"),
    "queries": ("glIsQuery", "glGenQueries", "glDeleteQueries"),
    "samplers": ("glIsSampler", "glGenSamplers", "glDeleteSamplers"),
    "programs": ("glIsProgram", None, "glDeleteProgram"),
}


def _newest_name(gen: str | None, delete: str) -> int:
    """The largest name of a kind handed out so far: a fresh name, given back at once."""
    gl = _lib()
    if gen is None:
        gl.glCreateProgram.restype = ctypes.c_uint
        name = gl.glCreateProgram()
        getattr(gl, delete)(ctypes.c_uint(name))
        return int(name)
    name = ctypes.c_uint(0)
    getattr(gl, gen)(1, ctypes.byref(name))
    getattr(gl, delete)(1, ctypes.byref(name))
    return int(name.value)


def live_names(kind: str) -> list[int]:
    """The live names of a kind of GL object (a key of _CENSUS): glIs* over every name
    handed out so far."""
    is_name, gen, delete = _CENSUS[kind]
    top = _newest_name(gen, delete)
    fn = getattr(_lib(), is_name)
    fn.restype = ctypes.c_ubyte
    return [name for name in range(1, top) if fn(ctypes.c_uint(name))]


def gl_census(ctx: moderngl.Context) -> dict[str, int]:
    """Live GL objects per kind in this context (moderngl's own and raw ones alike)."""
    _lib().glUseProgram(0)  # a deleted program still in use would count as live
    return {kind: len(live_names(kind)) for kind in _CENSUS}


def random_camera(rng: np.random.Generator, scene: Scene) -> tuple[Camera, str]:
    """An orbit, a camera inside an object, a near plane cutting the scene, or an extreme
    zoom; returns the camera and which kind it is."""
    kind = str(rng.choice(["orbit", "inside", "near-cross", "zoom"]))
    c, r = scene.center, scene.radius
    fov = float(rng.uniform(5.0, 150.0)) if rng.random() < 0.3 else float(rng.uniform(30.0, 70.0))
    if kind == "inside":
        oid = int(rng.integers(scene.count))
        lo, hi = scene.aabb_min[oid], scene.aabb_max[oid]
        eye = lo + (hi - lo) * rng.uniform(0.2, 0.8, 3)
        target = eye + rng.normal(size=3) * r
        cam = Camera(eye=eye, target=target, up=rng.normal(size=3), fov_y=fov)
        return cam.fit_depth(c, r), kind
    az, el = float(rng.uniform(0, 360)), float(rng.uniform(-89.9, 89.9))
    dist = float(10 ** rng.uniform(-3, 2.5)) if kind == "zoom" else float(rng.uniform(0.4, 4.0))
    cam = Camera.orbit(c, r, az, el, dist, fov_y=fov)
    if kind == "near-cross":
        d = float(np.linalg.norm(cam.eye - c))
        cam.near = max(d * rng.uniform(0.6, 1.2), cam.far * 1e-5)
        cam.far = max(cam.far, cam.near * 1.5)
    return cam, kind


def random_viewport(rng: np.random.Generator, low: int = 8, high: int = 320) -> tuple[int, int]:
    w, h = rng.integers(low, high + 1, 2)
    return int(w), int(h)


@dataclass
class FrameCheck:
    finite: bool
    gl_error: str
    color_fraction: float  # pixels with sprites within COLOR_TOL of STD
    depth_error: float  # max |sprites - STD| window depth, covered pixels off silhouettes
    depth_off: int  # covered pixels over the depth tolerance, off creases
    depth_crease: int  # ... on creases
    crease_limit: int  # 0.1% of covered pixels: how many of both may differ
    visible: int

    @property
    def ok(self) -> bool:
        """Colour as the composite tests demand; depth within the capture tests' slope
        tolerance except on at most 0.1% of covered pixels. Off-crease exceptions are
        counted apart: they are single pixels where two surfaces of one object lie within
        ~1e-4 window depth of each other and the displaced vertex snapped the other way."""
        return (
            self.finite
            and self.gl_error == "GL_NO_ERROR"
            and self.color_fraction >= COLOR_FRACTION
            and self.depth_off + self.depth_crease <= self.crease_limit
        )


def sprites_and_std(renderer: Renderer, camera: Camera, viewport: tuple[int, int]):
    """One view captured and composited as `sprites`, and drawn by STD: (records, whether
    the records are finite, sprites rgba and depth, STD's readback, per-pixel colour
    difference (max over RGB, of 255) between sprites and STD over the background)."""
    records = renderer.capture(camera, viewport)
    finite = all(np.isfinite(getattr(records, k)).all() for k in ("transform", "clip_ndc", "scale"))
    rgba, depth = renderer.composite("sprites").read()
    std = renderer.std(camera, viewport).read(viewport, 1)
    std_rgb = over_background(std["color"][0])[..., :3].astype(int)
    return records, finite, rgba, depth, std, np.abs(rgba[..., :3].astype(int) - std_rgb).max(-1)


def check_sprites_frame(renderer: Renderer, camera: Camera, viewport: tuple[int, int]) -> FrameCheck:
    """Capture, composite `sprites` and compare with STD, the core's reconstruction check."""
    records, finite, rgba, depth, std, color_diff = sprites_and_std(renderer, camera, viewport)
    close = color_diff <= COLOR_TOL
    std_id, std_depth = std["id"][0], std["depth"][0]
    if close.mean() < COLOR_FRACTION:
        close |= _depth_ties(renderer, records, ~close, std_id, depth)
    covered = std_id >= 0
    finite &= bool(np.isfinite(depth).all())
    inner = covered & ~near_silhouettes(std_id, std_depth, depth)
    err = float(np.abs(depth[inner] - std_depth[inner]).max()) if inner.any() else 0.0
    off, crease = depth_mismatch(depth, std_depth, covered, std_id)
    return FrameCheck(
        finite=finite,
        gl_error=renderer.ctx.error,
        color_fraction=float(close.mean()),
        depth_error=err,
        depth_off=off,
        depth_crease=crease,
        crease_limit=crease_limit(covered),
        visible=int(records.visible.sum()),
    )


def _depth_ties(renderer: Renderer, records, where: np.ndarray, std_id: np.ndarray, depth: np.ndarray) -> np.ndarray:
    """Pixels of `where` where STD's object lies in the atlas at the depth the sprite shows:
    coincident surfaces of two objects (touching parts), where either one is front-most."""
    tw, th, td = records.atlas_size
    atlas = renderer.atlas.read((tw, th), td, parts=("id", "depth"))
    tol = depth_tolerance(depth)
    tie = np.zeros(where.shape, bool)
    for oid in np.unique(std_id[where & (std_id >= 0)]):
        if not records.visible[oid]:
            continue
        y, x = np.nonzero(where & (std_id == oid))
        tx, ty = to_atlas(records, int(oid), x, y)
        layer = records.layer[oid]
        ok = atlas["id"][layer][ty, tx] == oid
        own = atlas["depth"][layer][ty, tx]
        tie[y, x] = ok & (np.abs(own - depth[y, x]) <= tol[y, x])
    return tie


@dataclass
class SweepResult:
    frames: int = 0
    failures: list = field(default_factory=list)  # (frame, kind, FrameCheck)
    kinds: dict = field(default_factory=dict)
    worst_color: float = 1.0
    worst_depth: float = 0.0


def sweep(renderer: Renderer, frames: int, seed: int = 0, progress: Callable | None = None) -> SweepResult:
    """`frames` random extreme cameras and viewports, each checked with check_sprites_frame."""
    rng = np.random.default_rng(seed)
    out = SweepResult()
    for i in range(frames):
        cam, kind = random_camera(rng, renderer.scene)
        check = check_sprites_frame(renderer, cam, random_viewport(rng))
        out.frames += 1
        out.kinds[kind] = out.kinds.get(kind, 0) + 1
        out.worst_color = min(out.worst_color, check.color_fraction)
        out.worst_depth = max(out.worst_depth, check.depth_error)
        if not check.ok:
            out.failures.append((i, kind, check))
        if progress:
            progress(i + 1)
    return out


@dataclass
class SoakSample:
    frame: int
    rss: int  # resident set size, bytes
    targets: int  # of which the render targets as allocated at that moment
    objects: dict  # the GL census

    @property
    def other(self) -> int:
        """RSS without the render targets: what must stay flat."""
        return self.rss - self.targets


def soak(
    renderer: Renderer,
    frames: int,
    samples: int = 10,
    seed: int = 0,
    progress: Callable | None = None,
    viewports: list | None = None,
) -> tuple[list[SoakSample], list[str]]:
    """Capture and composite `frames` frames, changing camera, focus set, mode and viewport
    size at random (from `viewports` when given); sample RSS and the GL census `samples`
    times. Returns the samples and the GL errors seen."""
    rng = np.random.default_rng(seed)
    scene = renderer.scene
    errors, out = [], []
    every = max(1, frames // samples)
    for i in range(frames):
        cam, _ = random_camera(rng, scene)
        viewport = (
            random_viewport(rng, 16, 400) if viewports is None else tuple(viewports[int(rng.integers(len(viewports)))])
        )
        renderer.capture(cam, viewport)
        focus = set(rng.choice(scene.count, size=int(rng.integers(0, 4)), replace=False).tolist())
        mode = str(rng.choice(["std", *MODES]))
        if mode == "std":
            renderer.std(cam, viewport)
        else:
            renderer.composite(Mode(mode), Style(focus=focus))
        if renderer.ctx.error != "GL_NO_ERROR":
            errors.append(f"frame {i}: GL error")
        if i % every == 0 or i == frames - 1:
            _reference_frame(renderer)
            out.append(SoakSample(i, rss_bytes(), renderer.target_bytes, gl_census(renderer.ctx)))
        if progress:
            progress(i + 1)
    return out, errors


# The reference frame is drawn this many times before a sample, so that the frames just before
# every reading are the same, and so that each of llvmpipe's few scenes (one flushed batch in
# flight: glraw.Throttle) draws it once and lets go of the framebuffer it held, the atlas
# that trim() just replaced among them (docs/reliability.md, Soak).
REFERENCE_REPEATS = 6


def _reference_frame(renderer: Renderer) -> None:
    """The same frame before every sample, with the render targets trimmed to it, so the
    targets and the driver's per-frame working memory (bins, sized by the viewport) are the
    same whenever RSS is read."""
    scene = renderer.scene
    camera = Camera.orbit(scene.center, scene.radius, 30.0, 20.0, 2.2)
    renderer.capture(camera, (320, 240))
    renderer.trim()
    for mode in MODES:  # every mode with a focus once: its shader variants exist from the first sample
        renderer.composite(Mode(mode), Style(focus={0}))
    for _ in range(REFERENCE_REPEATS):
        renderer.capture(camera, (320, 240))
        renderer.composite("ghosted-ao")
        renderer.ctx.finish()


def drift(samples: list[SoakSample], warmup: float = 0.2) -> tuple[float, dict]:
    """(memory drift, GL object change) after warm-up. Memory drift: the change of RSS without
    the render targets over the kept samples, from a least-squares line through them (single
    readings swing by several percent with the driver's caches), relative to their mean.
    GL objects: last sample against the first after warm-up."""
    kept = samples[min(len(samples) - 1, int(len(samples) * warmup)) :]
    frames = np.array([s.frame for s in kept], np.float64)
    other = np.array([s.other for s in kept], np.float64)
    slope = np.polyfit(frames, other, 1)[0] if len(kept) >= 2 and np.ptp(frames) > 0 else 0.0
    change = slope * (frames[-1] - frames[0]) / other.mean()
    start, end = kept[0], kept[-1]
    return float(change), {k: end.objects[k] - start.objects[k] for k in end.objects}
