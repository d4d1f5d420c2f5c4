"""What every viewer driver (tests/viewer_*driver.py) does with the real window: draw frames,
save a screenshot on the last of them, note GL errors, and send pyglet events."""

from __future__ import annotations

from pathlib import Path

from rtta.gl import glraw
from rtta.outputs import save_png


class Frames:
    """`frames(n, shot)`: n frames of `app` in `wnd`, a screenshot OUT/shot.png of the last;
    `errors` lists the frames after which the context had a GL error."""

    def __init__(self, app, wnd, out: Path) -> None:
        self.app, self.wnd, self.out = app, wnd, out
        self.errors: list[str] = []

    def __call__(self, n: int = 1, shot: str | None = None) -> None:
        for i in range(n):
            self.app.frame()
            if shot and i == n - 1:
                save_png(self.out / f"{shot}.png", glraw.read_window(*self.wnd.buffer_size))
            self.wnd.swap_buffers()
            if self.app.ctx.error != "GL_NO_ERROR":
                self.errors.append(f"after {shot or 'frame'}")

    def send(self, event: str, *args) -> None:
        """A pyglet event sent to the window, as the window system would."""
        self.wnd._window.dispatch_event(event, *args)
