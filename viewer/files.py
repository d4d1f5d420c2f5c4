"""A small imgui file browser (folders and supported scene files), so opening a scene
needs no desktop dialog program; and the per-frame statistics the panel shows."""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Callable
from pathlib import Path
from typing import Literal

from imgui_bundle import imgui

from rtta.errors import printable
from rtta.scene.readers import SUFFIXES

POPUP = "Open scene"
Frames = Literal["all", "moving", "rest"]


def listing(folder: Path) -> tuple[list[Path], list[Path]]:
    """(sub-folders, scene files) of `folder`, sorted by name, hidden entries left out."""
    dirs, files = [], []
    try:
        entries = sorted(folder.iterdir(), key=lambda p: p.name.lower())
    except OSError:
        return [], []
    for p in entries:
        if p.name.startswith("."):
            continue
        try:
            if p.is_dir():
                dirs.append(p)
            elif p.suffix.lower() in SUFFIXES:
                files.append(p)
        except OSError:
            continue
    return dirs, files


class FileBrowser:
    """`open(folder)` shows the popup; a chosen file is passed to `on_choose`."""

    def __init__(self, on_choose: Callable[[Path], None]) -> None:
        self.on_choose = on_choose
        self.folder = Path.cwd()
        self._want_open = False
        self.visible = False

    def open(self, folder: Path) -> None:
        self.folder = Path(folder)
        self._want_open = True

    def draw(self) -> None:
        if self._want_open:
            imgui.open_popup(POPUP)
            self._want_open = False
        imgui.set_next_window_size(imgui.ImVec2(520, 420), imgui.Cond_.appearing.value)
        self.visible, _ = imgui.begin_popup_modal(POPUP, None)
        if not self.visible:
            return
        imgui.text_wrapped(printable(self.folder))  # names of any bytes: imgui takes UTF-8
        imgui.begin_child("entries", imgui.ImVec2(0, -30), imgui.ChildFlags_.borders.value)
        dirs, files = listing(self.folder)
        if self.folder.parent != self.folder and imgui.selectable("../", False)[0]:
            self.folder = self.folder.parent
        for d in dirs:
            if imgui.selectable(printable(d.name) + "/", False)[0]:
                self.folder = d
        for f in files:
            if imgui.selectable(printable(f.name), False)[0]:
                imgui.close_current_popup()
                self.on_choose(f)
        imgui.end_child()
        if imgui.button("Cancel") or imgui.is_key_pressed(imgui.Key.escape):
            imgui.close_current_popup()
        imgui.end_popup()


class Stats:
    """Frame times: every frame's (the plot), those of frames drawn while the view moved (the
    rate a user navigates at, not the idle redraw's), and the stages of the last frame that
    rendered, which add up to its time (what the frame spent outside them is 'other')."""

    def __init__(self, keep: int = 240) -> None:
        self.history: deque[float] = deque(maxlen=keep)  # ms between frame starts
        self.moving_ms: deque[float] = deque(maxlen=keep)  # the same, of frames where the view moved
        self.rest_ms: deque[float] = deque(maxlen=keep)  # of frames where it did not
        self.stage_ms: dict[str, float] = {}  # stages run in the last frame
        self.last_ms: dict[str, float] = {}  # the last time each stage ran, whenever that was
        self.rendered: tuple[float, dict[str, float]] | None = None  # (frame ms, its stages) of the last render
        self.moving = False  # the frame being drawn moves the view (set by the viewer)
        self._last = time.perf_counter()

    def tick(self) -> None:
        """A frame starts: the time since the last start is the last frame's."""
        now = time.perf_counter()
        ms = (now - self._last) * 1e3
        self.history.append(ms)
        (self.moving_ms if self.moving else self.rest_ms).append(ms)
        self._last = now

    def done(self, moving: bool, frame_ms: float, stages: dict[str, float] | None) -> None:
        """The frame drawn: whether the view moved, its time in the viewer and the stages
        it ran (None: it rendered nothing, only the panel)."""
        self.moving = moving
        if stages is not None:
            self.rendered = (frame_ms, dict(stages))

    def mean_ms(self, frames: int = 30, which: Frames = "all") -> float:
        """Mean frame time over the last `frames` frames: 'all', 'moving' or 'rest' ones."""
        data = {"all": self.history, "moving": self.moving_ms, "rest": self.rest_ms}[which]
        recent = list(data)[-frames:]
        return sum(recent) / len(recent) if recent else 0.0

    def fps(self, which: Frames = "all") -> float:
        ms = self.mean_ms(which=which)
        return 1e3 / ms if ms > 0 else 0.0
