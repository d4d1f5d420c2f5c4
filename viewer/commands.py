"""What the panels, the controls and the overlay may read and call on the viewer app.

They type against these protocols, not against `Viewer`, so they sit below `viewer.app`
and never import it (no import cycle); `Viewer` satisfies all three as it is. Attributes
here are only read (or mutated in place), never rebound by those modules.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Protocol

if TYPE_CHECKING:
    from pathlib import Path

    from moderngl_window.context.base import BaseWindow
    from moderngl_window.integrations.imgui_bundle import ModernglWindowRenderer

    from rtta.atlas.parameterize import Records
    from rtta.renderer.renderer import Renderer

    from .files import FileBrowser, Stats
    from .orbit import Orbit
    from .ruler import Ruler
    from .saved import Views
    from .state import ViewerState
    from .views import Layout, Rect


class Host(Protocol):
    """What all three read: the user's choices, the screen layout, the renderer (its scene,
    atlas and caps) and the last capture's records (None before the first capture)."""

    state: ViewerState
    layout: Layout
    renderer: Renderer
    records: Records | None
    orbit: Orbit
    ruler: Ruler  # the measure tool's points and measurements
    camera_still: bool  # the camera did not move in the last frame (R on the GPU may be read)

    def turn_to(self, az: float, el: float) -> None: ...

    def say(self, text: str, error: bool = False) -> bool: ...


class OverlayHost(Host, Protocol):
    """The overlay: where the atlas layers are on screen, and where the mouse is."""

    @property
    def mouse(self) -> tuple[float, float]: ...

    @property
    def splitting(self) -> bool: ...  # the splitter is being dragged

    def atlas_tiles(self) -> list[tuple[int, Rect]]: ...


class ControlsHost(Host, Protocol):
    """The controls: the window (events, keys, buttons), imgui's event sink, the camera,
    the file browser, and the app's actions."""

    wnd: BaseWindow
    files: FileBrowser
    scene_dir: Path

    @property
    def imgui(self) -> ModernglWindowRenderer: ...  # read only here: the app's is a subclass

    def move_lens(self, x: float, y: float) -> None: ...

    def measure_at(self, x: float, y: float) -> None: ...

    def stop_turn(self) -> None: ...

    def frame_objects(self, ids=None) -> None: ...

    def open_scene(self, path) -> bool: ...

    def open_scene_later(self, path) -> None: ...

    def screenshot(self) -> list[Path]: ...


class PanelsHost(Host, Protocol):
    """The side panel: scene label and message, the camera, the file browser, frame
    stats, the capture paths the GL offers, and where it leaves the object checkboxes."""

    files: FileBrowser
    stats: Stats
    views: Views  # the scene's saved views
    scene_dir: Path
    screenshot_dir: Path
    scene_label: str
    message: str
    message_is_error: bool
    item_rects: dict[int, tuple]
    left_out: int  # parts fast navigation left out of the last capture

    @property
    def capture_paths(self) -> list[str]: ...

    def frame_objects(self, ids=None) -> None: ...

    def screenshot(self) -> list[Path]: ...


def records_to_read(host: Host) -> Records | None:
    """The last capture's records where reading them costs no frame: on the CPU already, or
    the camera at rest. While it moves, R stays on the GPU (a GpuRecords read back would make
    every frame wait for the GPU and copy R: 8 MB at 100,000 parts), so the atlas view's
    region outlines, its tooltip and the panel's counts wait for the view to rest."""
    rec = host.records
    if rec is None or (getattr(rec, "on_gpu", False) and not getattr(rec, "is_read", True) and not host.camera_still):
        return None
    return rec
