"""What the user chose in the viewer: mode, highlights, opacities, style and atlas settings.

Plain data and the operations the panel offers (toggle, all / none / invert over the
filtered list); no GL and no imgui, so it is tested directly.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from rtta.ldi.lens import LensShape, LensShapeName
from rtta.passes.composite import MODES, Style
from rtta.renderer.renderer import Settings

from .cutaway import CutawayState
from .parts import PartTree

VIEW_MODES = ("std", *MODES)
ATLAS_MAX_CHOICES = ("viewport", "512", "1024", "2048", "4096")
NAVIGATION_FPS = 10.0  # the frame rate fast navigation keeps by default (rtta.renderer.navigation)
GHOSTED = ("ghosted", "ghosted-ao")  # modes that show nothing but grey until a part is highlighted


@dataclass
class ProjectorState:
    """The projector as the panel and keys set it: attached to the camera, or placed on an
    orbit (azimuth, elevation in degrees, distance in scene radii) around the scene."""

    on: bool = False
    attached: bool = True
    az: float = 60.0
    el: float = 35.0
    dist: float = 2.5
    fov: float = 30.0
    strength: float = 1.0
    shadows: bool = True

    def nudge(self, d_az: float, d_el: float) -> None:
        self.az = (self.az + d_az) % 360.0
        self.el = max(-89.0, min(89.0, self.el + d_el))

    def key(self) -> tuple:
        return (self.on, self.attached, self.az, self.el, self.dist, self.fov, self.strength, self.shadows)


@dataclass
class LensState:
    """The cutaway lens of the ghosted modes: shape, radius (scene radii), and where it is
    (world; None: on the focus). It follows the mouse over the composite unless pinned."""

    on: bool = False
    shape: LensShapeName | LensShape = "sphere"
    radius: float = 0.35
    follow: bool = True
    center: tuple | None = None

    def key(self) -> tuple:
        return (self.on, self.shape, self.radius, self.center)


class TrackedSet(set):
    """A set of object ids that counts its changes, so a frame can tell whether the focus
    changed without sorting 10^5 ids (`ViewerState.style_key`)."""

    def __init__(self, items=()) -> None:
        super().__init__(items)
        self.version = 0


def _counting(method):
    def changed(self, *args):
        result = method(self, *args)
        self.version += 1
        return self if result is self else result

    return changed


for _name in (
    "add",
    "discard",
    "remove",
    "pop",
    "clear",
    "update",
    "difference_update",
    "intersection_update",
    "symmetric_difference_update",
    "__ior__",
    "__isub__",
    "__ixor__",
    "__iand__",
):
    setattr(TrackedSet, _name, _counting(getattr(set, _name)))


@dataclass
class ViewerState:
    names: list[str]
    mode: str = "ghosted-ao"
    style: Style = field(default_factory=Style)
    settings: Settings = field(default_factory=Settings)
    atlas_max: str = "viewport"
    show_atlas: bool = True
    atlas_layer: int = -1  # -1: all layers side by side
    filter: str = ""
    measure: bool = True  # time each stage (waits for the GPU after each: costs a little)
    navigation_fps: float = NAVIGATION_FPS  # fast navigation: while moving, the smallest parts are left out to keep
    # this frame rate (scenes of 500 parts or more); 0: off
    projector: ProjectorState = field(default_factory=lambda: ProjectorState())
    lens: LensState = field(default_factory=lambda: LensState())
    cutaway: CutawayState = field(default_factory=lambda: CutawayState())  # sections and explode
    paths: list[tuple[str, ...]] | None = None  # the part tree (Scene.paths)
    hidden: set[int] = field(default_factory=set)  # not captured, drawn or packed
    hidden_rev: int = 0  # bumped on every change of `hidden` (a cheap capture key)
    hover: int | None = None  # tree node under the mouse: its objects are outlined
    selected: int | None = None  # object picked in the composite: its row is revealed
    scroll_to: int | None = None  # tree node the panel scrolls to on its next frame
    show_cube: bool = True  # the view cube in the composite's corner
    touched: bool = False  # a part was highlighted, or a mode chosen, since the scene opened
    panel_width: int = 0  # the side panel's width as the splitter set it (0: views.PANEL_WIDTH)

    def __post_init__(self) -> None:
        if self.mode not in VIEW_MODES:
            raise ValueError(f"unknown mode {self.mode!r}; modes: {', '.join(VIEW_MODES)}")
        self.style.focus = TrackedSet(self.style.focus)
        self._lower = [n.lower() for n in self.names]
        self._filtered: tuple[str, list[int], np.ndarray] | None = None
        self._mask: tuple[tuple, np.ndarray] | None = None
        self.tree = PartTree(self.names, self.paths)

    def shown_mode(self) -> str:
        """The mode drawn now: a ghosted mode shows the scene solid (std) until the first
        highlight or a mode chosen (an all-grey ghost of a scene opened with nothing in focus
        shows nothing readable), then the mode itself."""
        if self.mode in GHOSTED and not self.touched:
            if not self.style.focus:
                return "std"
            self.touched = True
        return self.mode

    def choose_mode(self, mode: str) -> None:
        """The user picked `mode` (panel, key M): it is shown as it is from now on."""
        self.mode, self.touched = mode, True

    def hide(self, ids, on: bool = True) -> None:
        """Hide (or show again) these objects."""
        ids = {int(i) for i in ids}
        self.hidden = (self.hidden | ids) if on else (self.hidden - ids)
        self.hidden_rev += 1

    def isolate(self, ids) -> None:
        """Hide every object but these."""
        self.hidden = set(range(len(self.names))) - {int(i) for i in ids}
        self.hidden_rev += 1

    def show_all(self) -> None:
        self.hidden = set()
        self.hidden_rev += 1

    def toggle_group(self, ids) -> None:
        """A group's checkbox: all of its objects highlighted, or (when they all are) none."""
        ids = {int(i) for i in ids}
        if ids <= self.style.focus:
            self.style.focus -= ids
        else:
            self.style.focus |= ids

    def reveal(self, oid: int) -> None:
        """Select object `oid`: open the groups above its row and scroll the panel to it."""
        self.selected = oid
        self.filter = "" if self.filter and self.filter.strip().lower() not in self.names[oid].lower() else self.filter
        self.scroll_to = self.tree.reveal(oid)

    @property
    def highlighted(self) -> set[int]:
        return self.style.focus

    def filtered(self) -> list[int]:
        """Object ids whose name contains the filter text (case-insensitive); computed
        once per filter text (the panel asks every frame). Do not modify the list."""
        return self._filter()[1]

    def filtered_ids(self) -> np.ndarray:
        """`filtered()` as an int64 array."""
        return self._filter()[2]

    def _filter(self) -> tuple[str, list[int], np.ndarray]:
        f = self.filter.strip().lower()
        if self._filtered is None or self._filtered[0] != f:
            ids = list(range(len(self._lower))) if not f else [i for i, n in enumerate(self._lower) if f in n]
            self._filtered = (f, ids, np.asarray(ids, np.int64))
        return self._filtered

    def focus_mask(self) -> np.ndarray:
        """The highlighted objects as a bool mask over all objects (rebuilt only after a change)."""
        f = self.style.focus
        key = (id(f), getattr(f, "version", None), len(f))
        if self._mask is None or self._mask[0] != key or key[1] is None:
            mask = np.zeros(len(self.names), bool)
            ids = np.fromiter(f, np.int64, len(f))
            mask[ids[(ids >= 0) & (ids < len(mask))]] = True
            self._mask = (key, mask)
        return self._mask[1]

    def toggle(self, oid: int) -> None:
        self.style.focus ^= {oid}

    def select(self, how: str) -> None:
        """'all', 'none' or 'invert', applied to the filtered objects only."""
        ids = set(self.filtered())
        if not isinstance(self.style.focus, TrackedSet):
            self.style.focus = TrackedSet(self.style.focus)
        if how == "all":
            self.style.focus |= ids
        elif how == "none":
            self.style.focus -= ids
        elif how == "invert":
            self.style.focus ^= ids
        else:
            raise ValueError(how)

    def opacity(self, oid: int) -> float:
        return self.style.opacity.get(oid, self.style.default_opacity)

    def set_atlas_max(self, choice: str) -> None:
        self.atlas_max = choice
        self.settings.atlas_max = None if choice == "viewport" else (int(choice), int(choice))

    def style_key(self) -> tuple:
        """Changes whenever compositing must re-run (the capture need not)."""
        s = self.style
        focus = (id(s.focus), s.focus.version) if isinstance(s.focus, TrackedSet) else tuple(sorted(s.focus))
        return (
            self.mode,
            focus,
            len(s.focus),
            tuple(sorted(s.opacity.items())),
            s.default_opacity,
            s.context_opacity,
            s.desaturate,
            tuple(s.edge_color),
            tuple(s.outline_color),
            s.outline_width,
            s.edge_width,
            s.ao_radius,
            s.ao_strength,
            s.ao_objects,
            s.edge_objects,
            s.order,
            s.halo,
        )

    def capture_key(self) -> tuple:
        """Changes whenever the atlas must be captured again (besides camera and viewport)."""
        s = self.settings
        return (
            s.border,
            s.atlas_max,
            s.max_layers,
            s.capture_path,
            s.region_scale,
            s.context_scale,
            s.bounds,
            self.hidden_rev,
            self.cutaway.key(),
        )
