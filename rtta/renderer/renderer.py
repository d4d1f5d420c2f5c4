"""One frame of RTTA for a scene: parameterize (GPU or CPU), capture, composite, plus the baselines.
The renderer owns the GPU resources of a scene and reuses them across frames; `release()`
frees them. It never creates a context: it takes a moderngl.Context.
"""

from __future__ import annotations

import warnings

import moderngl
import numpy as np

from ..atlas import scratch
from ..atlas.parameterize import KeepShare, Records, Thinning, default_atlas_max, parameterize
from ..atlas.records import GpuRecords
from ..gl import glraw, sync
from ..gl.context import Capabilities, CapturePath, CapturePathName
from ..gl.gpu import GpuScene
from ..gl.targets import LayeredTarget
from ..ldi.lens import Lens, LensPass
from ..passes import oit
from ..passes.atlas_gpu import GpuParameterize, Sizing
from ..passes.capture import CapturePass
from ..passes.composite import LENS_MODES, CompositePass, CompositeTarget, Style
from ..passes.direct import RttPass, StdPass
from ..passes.post import AtlasPostPass
from ..passes.projector import Projector, ProjectorPass
from ..passes.style import Mode, ModeName
from ..scene.camera import Camera, ortho_near, outline_eye
from ..scene.model import Scene
from .placing import Staging
from .settings import Settings, blend_on, parameterize_on
from .stages import stages_of


class Renderer:
    """One frame of RTTA for a scene, on a moderngl context (OpenGL 4.3 core) of your own.

    `capture` packs and draws every visible object into the atlas; `composite` renders a mode
    from it, re-running only what changed. `release()` frees the GPU resources it keeps.

    Parameters
    ----------
    ctx : moderngl.Context
        The context (`create_headless_context`, or a window's).
    scene : Scene
        The batched scene (`load_scene`, `from_meshes`).
    settings : Settings, optional
        Atlas settings; they may change between captures.
    """

    def __init__(self, ctx: moderngl.Context, scene: Scene, settings: Settings | None = None) -> None:
        self.ctx = ctx
        self.caps = Capabilities.of(ctx)
        self.scene = scene
        self.settings = settings or Settings()
        self.gpu = GpuScene(ctx, scene)
        self.gpu.cull_closed = self.settings.cull_closed
        self._capture: dict[str, CapturePass] = {}
        self._gpu_atlas: GpuParameterize | None | bool = None  # Algorithm 1 in compute shaders (on_gpu); False: failed
        self.atlas_sizing: Sizing = "exact"  # "ahead": no read waits for the GPU (rtta.passes.atlas_gpu)
        self._std: StdPass | None = None
        self._rtt: RttPass | None = None
        self.atlas = LayeredTarget(ctx, (64, 64), 1, depth_keyed=True)
        self._single: LayeredTarget | None = None
        self._composite: CompositePass | None = None
        self._post: AtlasPostPass | None = None
        self._view: tuple | None = None  # (camera, viewport, path) of the last capture
        self.captured_focus: frozenset[int] = frozenset()  # the focus the last capture was scaled for
        self._captures = 0
        self.target = CompositeTarget(ctx)
        self.last: tuple | None = None  # (records, view, proj) of the last capture
        self.projector: Projector | None = None  # painting the scene
        self._projector_pass: ProjectorPass | None = None
        self.lens: Lens | None = None  # cutting the context away in the ghosted modes
        self._lens_pass: LensPass | None = None
        self.hidden: set[int] = set()  # objects the user hid: not packed, captured, composited or drawn
        self.staging = Staging()  # sections and explode (rtta.renderer.placing)
        self.measure = False  # time each stage (waits for the GPU after each)
        self.timings: dict[str, float] = {}  # stage -> ms of its last run, when measuring
        self.stages = stages_of(self)  # `with self.stages[name]:` times a stage when measuring
        self.warnings: list[str] = []  # what was degraded (each said once)
        self.python_warnings = True  # also say it through warnings.warn (a viewer shows `warnings`)
        self._throttle = glraw.Throttle()  # one flushed batch in flight (glraw.Throttle)

    def matrices(self, camera: Camera, viewport: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
        camera, message = camera.depth_limited()
        if message:
            self._warn(message)
        return camera.view(self.scene.origin), camera.projection(viewport[0] / viewport[1])

    def _warn(self, message: str) -> None:
        """Say what was degraded, once per renderer (`warnings`, and Python's warnings unless
        python_warnings is off)."""
        if message not in self.warnings:
            self.warnings.append(message)
            if self.python_warnings:
                warnings.warn(message, stacklevel=3)

    def region_scales(self, focus=()) -> float | np.ndarray:
        """Atlas texels per pixel: region_scale for the focus, times context_scale for the rest."""
        s = self.settings
        if s.context_scale == 1.0:
            return s.region_scale
        scale = np.full(self.scene.count, s.region_scale * s.context_scale)
        scale[[o for o in focus if 0 <= o < self.scene.count]] = s.region_scale
        return scale

    def parameterize(
        self, camera: Camera, viewport: tuple[int, int], matrices=None, focus=(), thin: Thinning | None = None
    ) -> Records:
        """`thin`: picks objects not packed this time besides the hidden ones, from this
        frame's projection (fast navigation, rtta.renderer.navigation; atlas.parameterize)."""
        view, proj = matrices or self.matrices(camera, viewport)
        s = self.settings
        largest = max(s.region_scale, s.region_scale * s.context_scale)
        atlas_max = s.atlas_max or default_atlas_max(viewport, s.border, largest)
        atlas_max = (min(atlas_max[0], self.caps.max_texture), min(atlas_max[1], self.caps.max_texture))
        max_layers = min(s.max_layers or 2**31, self.caps.max_layers, self.atlas.layers_within(atlas_max))
        vpm = proj @ view
        if (thin is None or isinstance(thin, KeepShare)) and self.on_gpu:  # a KeepShare thins on the GPU too
            return self._parameterize_gpu(vpm, viewport, atlas_max, max_layers, focus, thin)
        hidden, corners = self.staging.staged(self.hidden_mask(), self.scene.box_corners(s.bounds))
        scales = self.region_scales(focus)
        return parameterize(
            corners, vpm, viewport, border=s.border, atlas_max=atlas_max, max_layers=max_layers,
            hidden=hidden, region_scale=scales, thin=thin,
        )  # fmt: skip

    @property
    def on_gpu(self) -> bool:
        """Whether Algorithm 1 runs on the GPU (Settings.parameterize; "auto" falls back to
        the CPU, saying so once, where the compute shaders do not build)."""
        if parameterize_on(self.settings.parameterize) == "cpu" or self._gpu_atlas is False:
            return False
        if self._gpu_atlas is None:
            self._gpu_atlas = GpuParameterize.attempt(
                self.ctx, self.atlas_sizing, self.settings.parameterize, self._warn
            )
        return bool(self._gpu_atlas)

    def _parameterize_gpu(self, vpm, viewport, atlas_max, max_layers, focus, thin=None) -> GpuRecords:
        """Algorithm 1 on the GPU (rtta.passes.atlas_gpu); the objects not packed and the scales
        wanted are made (over n) only when what they depend on changed."""
        s = self.settings
        assert isinstance(self._gpu_atlas, GpuParameterize), "on_gpu made it"
        self._gpu_atlas.sizing = self.atlas_sizing
        key = (frozenset(self.hidden), self.staging.key(focus), frozenset(focus), s.region_scale, s.context_scale)
        hidden = scales = None
        if not self._gpu_atlas.knows(key, self.scene.count):
            hidden, scales = self.staging.not_packed(self.hidden_mask()), self.region_scales(focus)
        return self._gpu_atlas.run(
            self.gpu, self.scene.box_corners(s.bounds), vpm, viewport, border=s.border, atlas_max=atlas_max,
            max_layers=max_layers, hidden=hidden, region_scale=scales, offsets=self.staging.offsets, key=key, thin=thin,
        )  # fmt: skip

    def hidden_mask(self) -> np.ndarray | None:
        """bool [n] of the hidden objects (None when none is hidden)."""
        if not self.hidden:
            return None
        mask = np.zeros(self.scene.count, bool)
        mask[[i for i in self.hidden if 0 <= i < self.scene.count]] = True
        return mask

    def shown_mask(self) -> np.ndarray | None:
        """bool [n] of the objects not hidden (None: all of them)."""
        mask = self.hidden_mask()
        return None if mask is None else ~mask

    def shown_ranges(self) -> list[tuple[int, int]] | None:
        """(first, count) index runs of the objects not hidden (None: all of them, one run).
        Objects lie contiguously in object order, so hiding k objects makes at most k + 1 runs."""
        shown = self.shown_mask()
        return None if shown is None else [(int(first), int(count)) for first, count in self.scene.index_runs(shown)]

    def scaled_for(self, focus) -> frozenset[int]:
        """The focus as far as it changes the capture (empty when every object has one scale)."""
        return frozenset() if self.settings.context_scale == 1.0 else frozenset(focus)

    @property
    def captured_normals(self) -> bool:
        """Whether the last capture wrote the normal image (the atlas keeps the answer)."""
        return self.atlas.normals_written

    def capture_pass(self, path: CapturePathName | CapturePath | None = None) -> CapturePass:
        path = self.caps.capture_path(path or self.settings.capture_path)
        if path not in self._capture:
            self._capture[path] = CapturePass(self.ctx, path)
        return self._capture[path]

    def capture(
        self,
        camera: Camera,
        viewport: tuple[int, int],
        path: CapturePathName | CapturePath | None = None,
        focus=(),
        normals: bool = True,
        ids: bool = True,
        thin: Thinning | None = None,
    ) -> Records:
        """Parameterize and capture every visible object into the atlas; returns R. With a
        context scale below 1, `focus` objects get full-scale regions and the rest smaller ones.
        normals=False leaves the normal image unwritten, for modes that read none
        (needs_normals); a composite that needs it then captures again. ids=False leaves the
        id image unwritten (compositing and picking never read it; the export does).
        `thin`: picks objects left out of this capture as if hidden (fast navigation)."""
        view, proj = self.matrices(camera, viewport)
        self.place(focus)
        self.last = None  # R of the last frame is read back before the GPU writes over it only if a caller holds it
        self.captured_focus = self.scaled_for(focus)
        self._view = (camera, viewport, path)
        with self.stages["parameterize"]:
            records = self.parameterize(camera, viewport, (view, proj), self.captured_focus, thin)
            sync.kick(self.ctx)  # a GPU packs while the capture's draws are made
        with self.stages["capture"]:
            self.capture_pass(path).render(
                gpu=self.gpu, records=records, view=view, proj=proj, atlas=self.atlas, normals=normals, ids=ids
            )
            self._throttle.flush()  # rasterize while Python goes on; bounds the driver's memory
        self.last = (records, view, proj)
        self._captures += 1
        return records

    def composite(self, mode: ModeName | Mode, style: Style | None = None) -> CompositeTarget:
        """Composite the last capture; re-run it alone when only the style or mode changes."""
        if self.last is None or self._view is None:
            raise RuntimeError("composite() needs a capture() first")
        style = style or Style()
        missing = self.needs_normals(mode) and not self.captured_normals
        stale = self.staging.key(style.focus) != self.staging.key(self.staging.focus)  # sections/explode
        if self.scaled_for(style.focus) != self.captured_focus or missing or stale:
            # the focus decides the region scales; AO, edges and the projector read normals
            self.capture(
                *self._view, focus=style.focus, normals=self.captured_normals or missing, ids=self.atlas.ids_written
            )
        records, view, proj = self.last
        if self._composite is None:
            self._composite = CompositePass(self.ctx)
        self._composite.blend = blend_on(self.settings.blend, sync.renderer(self.ctx))
        post = self.post_process(style) if mode == Mode.GHOSTED_AO else None
        if post is not None:
            sync.kick(self.ctx)  # a GPU shades while the compositing is made
        origin = self.scene.origin
        projection = self._projection()
        if projection is not None:
            projection = (*projection, origin)
        lens = None
        if self.lens is not None and mode in LENS_MODES:
            if self._lens_pass is None:
                self._lens_pass = LensPass(self.ctx)
            with self.stages["lens"]:
                self._lens_pass.textures(self.lens)  # built once per lens geometry, before compositing
            lens = (self._lens_pass, self.lens, origin)
        fallbacks = self._composite.fallbacks
        with self.stages["composite"]:
            self._composite.render(
                atlas=self.atlas,
                records=records,
                gpu=self.gpu,
                style=style,
                mode=mode,
                view=view,
                offsets=self.staging.offsets,
                target=self.target,
                post=post,
                view_proj=proj @ view,
                projection=projection,
                lens=lens,
                eye=outline_eye(view, proj, self.scene.radius),
                ortho_near=ortho_near(proj),
            )
            self._throttle.flush()
        if self._composite.fallbacks > fallbacks:
            self._warn(oit.fallback_message(self._composite.pixel_order_refusal, records.viewport))
        return self.target

    def needs_normals(self, mode: str) -> bool:  # also "std"
        """Whether compositing `mode` reads the atlas's normal image: AO and edges
        (ghosted-ao) and the projector's lighting do; the other modes read colour and depth."""
        return mode == Mode.GHOSTED_AO or self.projector is not None

    def _projection(self):
        """(ProjectorPass, Projector) with the shadow map up to date, or None without a projector."""
        if self.projector is None:
            return None
        if self._projector_pass is None:
            self._projector_pass = ProjectorPass(self.ctx)
        with self.stages["projector"]:
            self._projector_pass.render(gpu=self.gpu, projector=self.projector, ranges=self.shown_ranges())
        return self._projector_pass, self.projector

    def post_process(self, style: Style) -> AtlasPostPass:
        """Ambient occlusion and edges on the atlas (ghosted-ao only), per object as the
        style asks and once per capture (AtlasPostPass.shade)."""
        if self.last is None:
            raise RuntimeError("post_process() needs a capture() first")
        records, _, proj = self.last
        self._post = self._post or AtlasPostPass(self.ctx)
        with self.stages["post"]:
            self._post.shade(
                atlas=self.atlas, records=records, gpu=self.gpu, proj=proj, style=style, capture=self._captures
            )
        return self._post

    @property
    def single_target(self) -> LayeredTarget:
        if self._single is None:
            self._single = LayeredTarget(self.ctx, (64, 64), 1, normals=False, stencil=self.atlas.stencil)
        return self._single

    def place(self, focus=None) -> None:
        """Make `staging`'s sections and explode current for `focus` (None: the last; std() takes one too)."""
        self.staging.place(self.gpu, focus, [t for t in (self.atlas, self._single) if t is not None])

    def std(self, camera: Camera, viewport: tuple[int, int], focus=None) -> LayeredTarget:
        if self._std is None:
            self._std = StdPass(self.ctx)
        self.place(focus)
        view, proj = self.matrices(camera, viewport)
        projection = self._projection()
        with self.stages["std"]:
            self._std.render(
                gpu=self.gpu,
                view=view,
                proj=proj,
                target=self.single_target,
                viewport=viewport,
                projection=projection,
                objects=self.shown_mask(),
            )
            self._throttle.flush()
        return self.single_target

    def rtt(self, camera: Camera, viewport: tuple[int, int], objects, consume=None) -> None:
        if self._rtt is None:
            self._rtt = RttPass(self.ctx)
        self.place()
        view, proj = self.matrices(camera, viewport)
        self._rtt.render(
            gpu=self.gpu,
            view=view,
            proj=proj,
            target=self.single_target,
            viewport=viewport,
            objects=objects,
            consume=consume,
        )

    def trim(self) -> None:
        """Shrink the lazily sized targets (atlas, composite) to the last capture's needs now;
        their contents are lost, so capture again before compositing. For memory
        measurements that must see the same allocations every time, and for a viewer that
        wants memory back after a huge window."""
        if self.last is None:
            return
        tw, th, td = self.last[0].atlas_size
        self.atlas.trim((tw, th), td)
        self.target.trim()
        if isinstance(self._gpu_atlas, GpuParameterize):
            self._gpu_atlas.layers = 0  # the next frame sizes the atlas anew (sizing "ahead")

    @property
    def target_bytes(self) -> int:
        """Texture memory of the render targets as allocated now (they grow and shrink lazily
        with the views; a memory soak subtracts them to see what else changes)."""
        parts = [self.atlas, self._single, self.target, self._post]
        return sum(p.nbytes for p in parts if p is not None)

    def release(self) -> None:
        self.last = None
        self.gpu.keep_held()  # records a caller holds are read back while R is there
        self._throttle.release()
        for p in [
            *self._capture.values(),
            self._std,
            self._rtt,
            self._composite,
            self._post,
            self._projector_pass,
            self._lens_pass,
            self.staging,
            self._gpu_atlas or None,
        ]:
            if p is not None:
                p.release()
        self._capture.clear()
        self._std = self._rtt = self._gpu_atlas = None
        self.target.release()
        for t in (self.atlas, self._single):
            if t is not None:
                t.release()
        self.gpu.release()
        scratch.release()  # Algorithm 1's temporaries, sized for this scene (27 MB at 10^5 objects)
