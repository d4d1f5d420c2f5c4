"""Opening scenes in the viewer: now, or on a worker thread while the window keeps drawing."""

from __future__ import annotations

import threading
from pathlib import Path
from typing import TYPE_CHECKING

from rtta.errors import RttaError
from rtta.scene.loader import load_scene
from rtta.scene.model import Scene


class Loading:
    """Opening files (a part of `viewer.app.Viewer`)."""

    load_options: dict
    loading: tuple | None

    if TYPE_CHECKING:  # the viewer's own

        def set_scene(self, scene: Scene, mode: str | None = None) -> None: ...

        def say(self, text: str, error: bool = False) -> bool: ...

    def open_scene(self, path) -> bool:
        """Load `path` now; on failure show the error in the panel and keep the current scene."""
        return self._opened(path, *_read_scene(path, self.load_options))

    def open_scene_later(self, path) -> None:
        """Load `path` on a worker thread, so the window keeps drawing while a large file
        loads (seconds at 10^5 parts); `frame()` takes the scene, or the error, once it is
        there. The file browser and drag-and-drop open files this way."""
        if self.loading is not None:
            self.say(f"still loading {Path(self.loading[0]).name}; open another file when it is done", error=True)
            return
        box: dict = {}
        worker = threading.Thread(
            target=lambda: box.update(result=_read_scene(path, self.load_options)), name="rtta-load", daemon=True
        )
        self.loading = (path, worker, box)
        self.say(f"loading {Path(path).name} ...")
        worker.start()

    def _take_loaded(self) -> None:
        if self.loading is not None and not self.loading[1].is_alive():
            path, _, box = self.loading
            self.loading = None
            self._opened(path, *box.get("result", (None, f"{path}: cannot open (the load stopped)")))

    def _opened(self, path, scene: Scene | None, error: str | None) -> bool:
        if scene is None:
            return self.say(error or f"{path}: cannot open", error=True)
        self.set_scene(scene)
        self.say("; ".join([f"opened {Path(path).name}", *(f"warning: {w}" for w in scene.warnings)]))
        return True


def _read_scene(path, options: dict) -> tuple[Scene | None, str | None]:
    """(scene, None) or (None, the one-line error): a broken file never takes the session down."""
    try:
        scene = load_scene(str(path), **options)
        _ = scene.closed  # which parts cull back faces: worked out here, not in the drawing thread
        return scene, None
    except RttaError as exc:
        return None, str(exc)
    except Exception as exc:
        reason = str(exc).strip().splitlines()[0][:200] if str(exc).strip() else ""
        return None, f"{path}: cannot open ({type(exc).__name__}: {reason})"
