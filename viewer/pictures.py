"""Screenshots (F12): the composite and the atlas as PNGs, never overwriting a file."""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from rtta.errors import RttaError
from rtta.outputs import check_file, save_png
from rtta.renderer.snapshot import over_background

from .views import ATLAS_BACKGROUND

if TYPE_CHECKING:
    from rtta.atlas.parameterize import Records
    from rtta.renderer.renderer import Renderer

    from .orbit import Orbit
    from .state import ViewerState


def default_dir() -> Path:
    """Where screenshots go unless `--screenshot-dir` says: an rtta folder in the user's
    pictures folder ($XDG_PICTURES_DIR, else the one user-dirs.dirs names, else ~/Pictures).
    Never the current folder (it is often the one the scene files are in)."""
    home = Path.home()
    pictures = os.environ.get("XDG_PICTURES_DIR", "")
    if not pictures:
        config = Path(os.environ.get("XDG_CONFIG_HOME") or home / ".config") / "user-dirs.dirs"
        try:
            for line in config.read_text(encoding="utf-8", errors="replace").splitlines():
                if line.startswith("XDG_PICTURES_DIR="):
                    pictures = line.split("=", 1)[1].strip().strip('"').replace("$HOME", str(home))
        except OSError:
            pass
    return Path(pictures or home / "Pictures") / "rtta"


class Pictures:
    """The viewer's screenshots (a part of `viewer.app.Viewer`)."""

    renderer: Renderer
    state: ViewerState
    orbit: Orbit
    records: Records | None
    scene_label: str
    screenshot_dir: Path
    screenshot_dir_default: bool  # the user's pictures folder: made on the first screenshot

    if TYPE_CHECKING:  # the viewer's own

        @property
        def viewport(self) -> tuple[int, int]: ...

        def say(self, text: str, error: bool = False) -> bool: ...

    def screenshot(self) -> list[Path]:
        """PNGs of the composite and the atlas (layers side by side); never overwrites."""
        images = {"composite": self.composite_image(), "atlas": self.atlas_image()}
        images = {k: v for k, v in images.items() if v is not None}
        stem = re.sub(r"[^\w.-]", "_", Path(self.scene_label).stem)[:80] or "scene"
        if self.screenshot_dir_default:
            try:
                self.screenshot_dir.mkdir(parents=True, exist_ok=True)
            except OSError as exc:
                self.say(f"screenshot not written: {self.screenshot_dir}: {exc.strerror or exc}", error=True)
                return []
        n = 0
        while True:
            n += 1
            paths = {k: self.screenshot_dir / f"rtta-{stem}-{n:03d}-{k}.png" for k in images}
            if any(p.exists() or p.is_symlink() for p in paths.values()):
                continue
            try:
                for p in paths.values():
                    check_file(p, self.renderer.scene.inputs, suffix=".png", what="screenshot")
                written = [save_png(paths[k], img, overwrite=False) for k, img in images.items()]
            except FileExistsError:
                continue
            except (RttaError, OSError) as exc:
                self.say(f"screenshot not written: {exc}", error=True)
                return []
            self.say(f"saved {', '.join(p.name for p in written)} in {self.screenshot_dir}")
            return written

    def composite_image(self) -> np.ndarray | None:
        vp = self.viewport
        if vp[0] < 1 or vp[1] < 1:
            return None
        if self.state.shown_mode() == "std":
            return over_background(self.renderer.std(self.orbit.camera(), vp).read(vp, 1)["color"][0])
        return self.renderer.target.read()[0].copy()

    def atlas_image(self) -> np.ndarray | None:
        rec = self.records
        if rec is None or rec.atlas_size[2] == 0:
            return None
        tw, th, td = rec.atlas_size
        color = self.renderer.atlas.read((tw, th), td, parts=("color",))["color"]
        return np.concatenate(list(over_background(color, ATLAS_BACKGROUND)), axis=1)  # layers left to right
