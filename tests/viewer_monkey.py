"""A monkey for the viewer (issue 42): a long seeded random stream of user actions sent to
the real window, for tests/test_monkey.py and scripts/monkey.py.

Run as `python tests/viewer_monkey.py OUT_DIR --scene demo|engine|large|PATH --seed S
(--actions N | --seconds T)` with DISPLAY set (Xvfb), from a folder of its own (the file
browser and screenshots write there). Events go through the pyglet window's own dispatch,
as in tests/viewer_driver.py: drags (orbit, pan), the wheel, every key the viewer binds,
clicks in the composite, the atlas, the panel and the view cube, tree rows (left and right
click), filter typing, files opened through the browser and dropped (good and bad ones),
resizes, the splitter, modes, style, sections and explode (keys X and E, the plane placed on a
clicked surface, its handle dragged, flipped, toggled, shown, reset, the explode animated),
saved views, the measure tool (Esc, clear, a measurement removed), the view cube and its
projection switch.

Fails (exit 1, the findings in `result.json` and on stderr) on an exception (in an event
handler, a frame or a worker thread), a GL error, a camera that is not finite, a frame over
MAX_FRAME_S, or GL objects, their storage (rtta.bench.gl_memory) or RSS grown more than GROWTH
(RSS: --rss-growth) after the warm-up, all counted in one settled state (the main scene set
again, the first window size, llvmpipe's idle command scenes handed the current framebuffer).
Prints a summary.
"""

from __future__ import annotations

import argparse
import ctypes
import gc
import itertools
import json
import math
import os
import random
import shutil
import sys
import threading
import time
import traceback
import warnings
from pathlib import Path

from pyglet.window import key, mouse

HERE = Path(__file__).parent
sys.path.insert(0, str(HERE))  # bad_inputs (run as a script from anywhere)

from bad_inputs import make_corpus  # noqa: E402
from monkey_actions import LARGEST, Actions  # noqa: E402

from rtta.bench.gl_memory import gl_bytes  # noqa: E402
from rtta.bench.reliability import gl_census  # noqa: E402
from rtta.errors import printable  # noqa: E402
from rtta.gl import glraw  # noqa: E402
from rtta.memory import rss_bytes, steady_heap  # noqa: E402
from rtta.renderer.renderer import Settings  # noqa: E402
from rtta.scene.cutaway import CAPS, SECTION_SCOPES  # noqa: E402
from rtta.scene.generators.assembly import write_assembly  # noqa: E402
from rtta.scene.generators.demo import demo_path  # noqa: E402
from rtta.scene.loader import load_scene, load_scene_or_demo  # noqa: E402
from viewer import controls, cutaway  # noqa: E402
from viewer.app import Viewer  # noqa: E402
from viewer.run import create_window  # noqa: E402
from viewer.state import VIEW_MODES  # noqa: E402

MAX_FRAME_S = 10.0
GROWTH = 0.05  # of the warm-up's GL objects and RSS
RSS_EVERY = 20  # actions between the RSS samples of the result
SIZE = (1280, 720)
ENGINE = HERE.parent.parent / "shared" / "data" / "engine_2cyl.glb"


def scene_path(name: str, folder: Path, parts: int) -> Path | None:
    """The scene a run works on: None for the demo, the engine (or a generated stand-in), a
    `parts`-part generated assembly, or a path."""
    if name == "demo":
        return None
    if name == "engine":
        return ENGINE if ENGINE.exists() else write_assembly(folder / "engine_standin.glb", 60, seed=2)
    if name == "large":
        return write_assembly(folder / "assembly.glb", parts)
    return Path(name)


class Monkey(Actions):
    def __init__(self, out: Path, scene: str, seed: int, parts: int) -> None:
        self.out, self.rng = out, random.Random(seed)
        self.files = out / "files"  # what the browser lists and the drops take: good and bad files
        self.files.mkdir(parents=True, exist_ok=True)
        bad = self.files / "bad"
        bad.mkdir(exist_ok=True)
        self.bad = [c.path for c in make_corpus(bad)]  # missing, too long, folders: as a user may drop
        self.good = [
            Path(shutil.copy(demo_path(), self.files / "demo.glb")),
            Path(shutil.copy(demo_path(), self.files / os.fsdecode(b"caf\xe9 demo.glb"))),  # a name not UTF-8
            write_assembly(self.files / "small.glb", 300, seed=1),
        ]
        path = scene_path(scene, out, parts)
        self.main = load_scene_or_demo(None) if path is None else load_scene(path)
        self.wnd = create_window(SIZE)
        self.app = Viewer(self.wnd, self.main, screenshot_dir=out / "shots", views_dir=out / "views")
        self.pw = self.wnd._window
        self.findings: list[str] = []
        self.actions: dict[str, int] = {}
        self.rss_mb: list[float] = []  # every RSS_EVERY actions
        self.reached, self.said = {"scenes": 0, "errors_said": 0}, ("", False, 0)
        self.frames_drawn, self.max_frame_s, self.t0 = 0, 0.0, time.perf_counter()
        warnings.showwarning = self.warned  # a warning (numpy's overflow, ...) is a finding, with where it came from
        threading.excepthook = lambda a: self.findings.append(
            "thread: " + "".join(traceback.format_exception(a.exc_type, a.exc_value, a.exc_traceback))
        )

    def warned(self, message, category, filename, lineno, file=None, line=None) -> None:
        stack = "".join(traceback.format_stack(limit=10)[:-1])
        self.findings.append(f"{category.__name__} in {self.last}: {message} ({filename}:{lineno})\n{stack}")

    # ---- events and frames ----------------------------------------------------------------
    def send(self, event: str, *args) -> None:
        self.pw.dispatch_event(event, *args)

    def frames(self, n: int = 1) -> None:
        app = self.app
        for _ in range(n):
            t = time.perf_counter()
            app.frame()
            self.wnd.swap_buffers()
            dt = time.perf_counter() - t
            self.frames_drawn += 1
            self.max_frame_s = max(self.max_frame_s, dt)
            if dt > MAX_FRAME_S:
                self.findings.append(f"frame {self.frames_drawn} took {dt:.1f} s ({self.last})")
            said = (app.message, app.message_is_error, id(app.renderer.scene))
            if said != self.said:  # what the run reached: scenes opened, errors said
                self.reached["scenes"] += said[2] != self.said[2]
                self.reached["errors_said"] += said[1] and said[:2] != self.said[:2]
                self.said = said
            err = app.ctx.error
            if err != "GL_NO_ERROR":
                self.findings.append(f"GL error {err} after {self.last}")
            cam = app.orbit.camera()
            values = [*cam.eye, *cam.target, app.orbit.dist, app.orbit.az, app.orbit.el]
            if not all(math.isfinite(float(v)) for v in values):
                self.findings.append(f"camera not finite after {self.last}: {values}")
                app.frame_objects()

    def h(self) -> int:  # window height: pyglet's y runs up
        return self.wnd.size[1]

    def point(self, rect) -> tuple[int, int]:
        x, y, w, h = rect
        return int(x + self.rng.random() * max(w - 1, 1)), int(y + self.rng.random() * max(h - 1, 1))

    def click(self, x: float, y: float, button: int = mouse.LEFT, modifiers: int = 0, tap: bool = False) -> None:
        x, y = int(x), int(y)
        self.send("on_mouse_motion", x, self.h() - y, 0, 0)
        self.frames()
        self.send("on_mouse_press", x, self.h() - y, button, modifiers)
        if not tap:
            self.frames()
        self.send("on_mouse_release", x, self.h() - y, button, modifiers)
        self.frames(2)  # imgui takes queued input a frame at a time

    def drag(self, rect, button: int) -> None:
        x, y = self.point(rect)
        steps, dx, dy = self.rng.randint(2, 8), self.rng.randint(-200, 200), self.rng.randint(-150, 150)
        self.send("on_mouse_motion", x, self.h() - y, 0, 0)
        self.send("on_mouse_press", x, self.h() - y, button, 0)
        for i in range(1, steps + 1):
            px, py = x + dx * i // steps, self.h() - (y + dy * i // steps)
            self.send("on_mouse_drag", px, py, dx // steps, -dy // steps, button, 0)
            self.frames()
        self.send("on_mouse_release", x + dx, self.h() - (y + dy), button, 0)
        self.frames()

    def press(self, symbol: int, modifiers: int = 0) -> None:
        self.send("on_key_press", symbol, modifiers)
        self.send("on_key_release", symbol, modifiers)
        self.frames()

    def anywhere(self) -> tuple[int, int]:
        return self.point((0, 0, *self.wnd.size))

    def act(self, name: str | None = None) -> None:
        name = name or self.rng.choices(list(self.WEIGHTS), weights=list(self.WEIGHTS.values()))[0]
        self.last = name
        self.actions[name] = self.actions.get(name, 0) + 1
        getattr(self, f"a_{name}")()
        if sum(self.actions.values()) % RSS_EVERY == 0:
            self.rss_mb.append(round(rss_bytes() / 2**20, 1))
        files = self.app.files
        if self.out not in (files.folder, *files.folder.parents):
            files.folder = self.files  # '../' out of the run's folder: back into it
        if self.app.loading is not None and self.rng.random() < 0.5:
            t = time.perf_counter()
            while self.app.loading is not None and time.perf_counter() - t < 120:
                self.frames()  # a load under way: sometimes wait for it, drawing meanwhile

    def tour(self) -> None:
        """The warm-up's start: every action once and every mode shown once (with a part in focus),
        so what is made once on first use (a pass's program, a shader's JIT code) is made; the
        modes in the largest window a resize makes, the composite taking all of it, so that
        the driver's memory reaches the high-water mark of the run's largest frames too
        (llvmpipe keeps what its first `transparent` frame there took: some 40 MB)."""
        names = list(self.WEIGHTS)
        self.rng.shuffle(names)
        for name in names:
            self.act(name)
        self.resize_to(LARGEST)
        shown = self.app.state.show_atlas
        self.app.state.show_atlas = False
        for mode in VIEW_MODES:
            self.app.state.choose_mode(mode)
            self.app.state.toggle(self.rng.randrange(self.app.renderer.scene.count))
            self.frames(2)
        self.app.state.show_atlas = shown
        c = self.app.state.cutaway  # every mode under every kind of cap and scope of a section and an explode
        for mode, caps, scope in itertools.product(VIEW_MODES, CAPS, SECTION_SCOPES):
            self.app.state.choose_mode(mode)
            c.axis, c.caps, c.scope, c.explode = "y", caps, scope, 0.5
            self.frames(2)
        cutaway.reset(self.app)
        self.frames()

    # ---- the settled state where growth is counted -------------------------------------------
    def settle(self) -> dict:
        app = self.app
        t = time.perf_counter()
        while app.loading is not None and time.perf_counter() - t < 300:
            self.frames()
        if app.files.visible:
            self.press(key.ESCAPE)
        s = app.state  # what set_scene keeps from the last scene: back to the defaults
        s.settings, s.atlas_max, s.show_atlas, s.panel_width, s.show_cube = Settings(), "viewport", True, 0, True
        app.orbit.projection = "perspective"
        self.resize_to(SIZE)
        app.set_scene(self.main, mode="ghosted-ao")
        self.frames(3)
        for _ in range(8):  # llvmpipe's idle scenes keep the framebuffer each drew last, and so
            app.ctx.screen.use()  # textures rtta deleted (glraw.Throttle): flushed clears, one
            app.ctx.clear(0.0, 0.0, 0.0, 0.0)  # scene each, hand them all this frame's instead
            glraw._lib().glFlush()
        app.ctx.finish()
        gc.collect()
        trim = getattr(ctypes.CDLL(None), "malloc_trim", None)  # glibc: freed heap back, so RSS is what lives
        if trim is not None:
            trim(0)
        gl_mb = sum(gl_bytes(app.ctx).values()) / 2**20  # what rtta and the viewer hold through GL
        size = list(self.wnd.buffer_size)
        return {"gl": gl_census(app.ctx), "gl_mb": gl_mb, "rss_mb": rss_bytes() / 2**20, "size": size}

    def resize_to(self, size: tuple[int, int]) -> None:
        """The window at `size`, drawn there."""
        self.pw.set_size(*size)
        for _ in range(50):  # the window system may take a few rounds to resize the window
            self.pw.dispatch_events()
            self.frames()
            if tuple(self.wnd.buffer_size) == size:
                break
            time.sleep(0.05)


def grown(settled: list[dict], rss_growth: float = GROWTH) -> list[str]:
    """Growth over the settled samples (the first after the warm-up): GL objects, the last
    against the first; RSS, the lower of the last two against the higher of the first two, so
    the heap's ups and downs (some 10% on llvmpipe) are not taken for growth, but a leak is."""
    out, first, last = [], settled[0], settled[-1]
    total = (sum(first["gl"].values()), sum(last["gl"].values()))
    if total[1] > total[0] * (1 + GROWTH):
        out.append(f"GL objects grew {total[0]} -> {total[1]}: {first['gl']} -> {last['gl']}")
    if last["gl_mb"] > first["gl_mb"] * (1 + GROWTH):
        out.append(f"GL storage grew {first['gl_mb']:.1f} -> {last['gl_mb']:.1f} MB")
    rss = (max(r["rss_mb"] for r in settled[:2]), min(r["rss_mb"] for r in settled[-2:]))
    if len(settled) > 2 and rss[1] > rss[0] * (1 + rss_growth):
        out.append(f"RSS grew {rss[0]:.0f} -> {rss[1]:.0f} MB (settled: {[round(r['rss_mb']) for r in settled]})")
    return out


def main() -> int:
    p = argparse.ArgumentParser()
    p.add_argument("out", type=Path)
    p.add_argument("--scene", default="demo", help="demo, engine, large, or a scene file")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--actions", type=int, default=0, help="this many actions (0: --seconds decides)")
    p.add_argument("--seconds", type=float, default=60.0, help="act until this long has passed")
    p.add_argument("--warmup", type=float, default=0.2, help="part of the run before the growth baseline")
    p.add_argument("--settles", type=int, default=4, help="settled samples of GL objects and RSS (>= 2)")
    p.add_argument("--parts", type=int, default=20_000, help="parts of the large scene")
    p.add_argument("--rss-growth", type=float, default=GROWTH, help="RSS growth that is a finding (GL objects: GROWTH)")
    a = p.parse_args()
    a.out.mkdir(parents=True, exist_ok=True)
    steady_heap()  # as rtta-view does (viewer/__init__.py)
    m = Monkey(a.out, a.scene, a.seed, a.parts)
    controls.DOUBLE_CLICK_S = 2.0  # llvmpipe on a loaded machine: a double-click's frames take long
    result: dict = {"scene": a.scene, "seed": a.seed, "objects": m.main.count}
    m.last = "start"
    done, t0, settled = 0, time.perf_counter(), []

    def progress() -> float:
        return done / a.actions if a.actions else (time.perf_counter() - t0) / a.seconds

    try:
        m.frames(3)
        m.tour()
        done = len(m.WEIGHTS)
        while progress() < 1:
            m.act()
            done += 1
            step = (1 - a.warmup) / max(a.settles - 1, 1)  # settled samples: the warm-up's end, then evenly
            if progress() >= a.warmup + step * len(settled) and len(settled) < a.settles - 1:
                settled.append({"actions": done, "s": round(time.perf_counter() - t0, 1), **m.settle()})
            if m.findings:
                break
        settled.append({"actions": done, "s": round(time.perf_counter() - t0, 1), **m.settle()})
        m.findings += grown(settled, a.rss_growth) if len(settled) > 1 else []
    except Exception:
        m.findings.append(f"exception in {m.last}: {traceback.format_exc()}")
    result["settled"] = settled
    result.update(actions=done, by_action=m.actions, frames=m.frames_drawn, seconds=time.perf_counter() - t0)
    result.update(max_frame_s=m.max_frame_s, findings=m.findings, rss_mb=m.rss_mb, reached=m.reached)
    (a.out / "result.json").write_text(json.dumps(result, indent=1))
    w, e = (settled[0], settled[-1]) if settled else ({}, {})
    print(
        f"monkey {printable(a.scene)} seed {a.seed}: {done} actions, {m.frames_drawn} frames "
        f"in {result['seconds']:.0f} s, "
        f"max frame {m.max_frame_s:.2f} s; GL objects {sum(w.get('gl', {}).values())} -> "
        f"{sum(e.get('gl', {}).values())} ({w.get('gl_mb', 0):.1f} -> {e.get('gl_mb', 0):.1f} MB), "
        f"RSS {w.get('rss_mb', 0):.0f} -> {e.get('rss_mb', 0):.0f} MB; "
        f"{m.reached['scenes']} scenes shown, {m.reached['errors_said']} errors said; {len(m.findings)} findings"
    )
    for f in m.findings:
        print("FINDING:", f, file=sys.stderr)
    try:
        m.app.release()
    except Exception:
        traceback.print_exc()
        return 1
    return 1 if m.findings else 0


if __name__ == "__main__":
    sys.exit(main())
