"""rtta-view: the desktop viewer (moderngl-window + pyglet, imgui-bundle panels)."""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

NO_DISPLAY = (
    "rtta-view: no display found (DISPLAY and WAYLAND_DISPLAY are not set); "
    "for images without a display use `rtta snapshot`"
)


def build_parser() -> argparse.ArgumentParser:
    from rtta.cli.guard import OneLineParser
    from rtta.cli.main import add_load_options
    from rtta.renderer.snapshot import SNAPSHOT_MODES
    from rtta.scene.camera import PROJECTIONS
    from rtta.scene.framing import STANDARD_VIEWS

    from .state import NAVIGATION_FPS

    p = OneLineParser(prog="rtta-view", description="Interactive ghosted views of multi-part models.")
    p.add_argument("scene", nargs="?", help="scene file (default: the built-in demo)")
    p.add_argument("--scene", dest="scene_opt", metavar="FILE", help="scene file (same as the positional)")
    p.add_argument("--size", default="1280x720", help="window size WxH")
    p.add_argument("--mode", default="ghosted-ao", choices=SNAPSHOT_MODES)
    p.add_argument(
        "--screenshot-dir",
        default=None,
        metavar="DIR",
        help="folder for screenshots (F12; default: rtta in your pictures folder, $XDG_PICTURES_DIR or ~/Pictures)",
    )
    p.add_argument(
        "--bench",
        type=int,
        default=0,
        metavar="FRAMES",
        help="orbit for FRAMES frames per mode and print frame times, then exit (without a display: in "
        "a headless EGL window)",
    )
    p.add_argument(
        "--bench-modes", default=None, metavar="MODE,...", help="with --bench: only these modes (default: every mode)"
    )
    p.add_argument(
        "--navigation-fps",
        default=None,
        metavar="FPS",
        help="fast navigation: while the camera moves, leave out the parts smallest on screen to keep "
        f"this frame rate (default {NAVIGATION_FPS:g}; scenes of 500 parts or more; a view at rest "
        "shows every part); 0: off",
    )
    p.add_argument("--focus", nargs="+", default=[], metavar="NAME", help="objects highlighted (names, groups, globs)")
    p.add_argument("--hide", nargs="+", default=[], metavar="NAME", help="objects hidden (names, groups, globs)")
    p.add_argument(
        "--camera", default=None, help="AZ,EL (framed) or AZ,EL,DIST (scene radii) orbit, as `rtta snapshot` takes it"
    )
    p.add_argument("--view", default=None, choices=tuple(STANDARD_VIEWS), help="a standard view, framed")
    p.add_argument("--projection", default=None, choices=PROJECTIONS, help="perspective (default) or ortho (key 5)")
    p.add_argument(
        "--view-file", default=None, metavar="FILE.json", help="open on a view saved by `rtta snapshot --save-view`"
    )
    p.add_argument(
        "--section",
        default=None,
        metavar="SPEC",
        help="open cut by one plane, as `rtta snapshot --section` takes it: x=V, -x=V, x=P%%, x (halfway), "
        "y and z likewise, or nx,ny,nz,d (the cutaway panel moves it)",
    )
    p.add_argument("--caps", default="solid", metavar="solid|hatch|off", help="cut faces of closed parts")
    p.add_argument("--explode", default="0", metavar="F", help="open exploded by F (0 to 4, as `rtta snapshot`)")
    add_load_options(p)
    return p


def main(argv: list[str] | None = None) -> int:
    from rtta.cli.common import scene_after_names
    from rtta.cli.main import load_options, parse_size, section_values
    from rtta.errors import RttaError, printable
    from rtta.memory import steady_heap

    try:
        args = build_parser().parse_args(section_values(sys.argv[1:] if argv is None else argv))
    except RttaError as exc:
        print(f"rtta-view: error: {printable(exc)}", file=sys.stderr)
        return 2
    if args.scene_opt is None:
        scene_after_names(args)  # `rtta-view --focus hub model.glb`
    steady_heap()  # long sessions resize targets often: keep the heap from creeping
    if args.bench < 0:
        print(
            f"rtta-view: error: --bench: expected a number of frames (0: no bench), got {args.bench}", file=sys.stderr
        )
        return 2
    if not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        if not (args.bench or os.environ.get("PYGLET_HEADLESS")):  # headless asked for: scripted runs
            print(NO_DISPLAY, file=sys.stderr)
            return 2
        import pyglet  # --bench needs no screen: pyglet's headless window, an EGL surface

        pyglet.options["headless"] = True
    try:
        _import_native()
    except ImportError as exc:
        print(f"rtta-view: broken install ({exc}); reinstall rtta: pip install --force-reinstall rtta", file=sys.stderr)
        return 2
    from .run import run
    from .start import Start

    start = Start(
        args.focus,
        args.hide,
        args.camera,
        args.view,
        args.projection,
        args.view_file,
        section=args.section,
        caps=args.caps,
        explode=args.explode,
    )
    try:
        size = parse_size(args.size)
        bench_modes = _modes(args.bench_modes)
        return run(
            args.scene_opt or args.scene,
            size=size,
            mode=args.mode,
            screenshot_dir=Path(args.screenshot_dir) if args.screenshot_dir else None,
            bench=args.bench,
            load=load_options(args),
            bench_modes=bench_modes,
            navigation_fps=_fps(args.navigation_fps),
            start=start,
        )
    except RttaError as exc:
        print(f"rtta-view: error: {printable(exc)}", file=sys.stderr)
        return 2


def _fps(text: str | None) -> float | None:
    import math

    from rtta.errors import RttaError

    if text is None:
        return None
    try:
        fps = float(text)
    except ValueError:
        fps = math.nan
    if not (math.isfinite(fps) and 0 <= fps <= 240):
        raise RttaError(f"--navigation-fps: expected frames per second from 0 (off) to 240, got {text!r}")
    return fps


def _modes(text: str | None) -> tuple[str, ...] | None:
    from rtta.errors import RttaError

    from .state import VIEW_MODES

    if not text:
        return None
    modes = tuple(m.strip() for m in text.split(",") if m.strip())
    unknown = [m for m in modes if m not in VIEW_MODES]
    if unknown or not modes:
        raise RttaError(
            f"--bench-modes: unknown mode(s) {', '.join(unknown) or '(none)'}; modes: {', '.join(VIEW_MODES)}"
        )
    return modes


def _import_native() -> None:
    """The window's, the GUI's and the scene readers' native libraries, imported with signals
    held (under cli()'s handlers, as the `rtta` command does): trimesh wraps its imports in `except
    BaseException`, so a Ctrl-C while it imported was swallowed and the viewer opened anyway,
    and one inside a native module's start can crash the process. A signal that came in is
    raised once they are in."""
    from rtta import outputs

    with outputs.signals_held():
        import moderngl_window  # noqa: F401
        import trimesh  # noqa: F401
        from imgui_bundle import imgui  # noqa: F401


def cli() -> None:
    """The command: rtta's signal handlers for the whole run (SIGINT, SIGTERM, SIGHUP raise
    KeyboardInterrupt, held while native code that must not be cut runs: rtta.outputs), and
    Ctrl-C, while starting or drawing, closes the viewer quietly."""
    try:
        from rtta import outputs  # numpy and the rest: a tenth of a second, before any handler is in
    except KeyboardInterrupt:
        sys.exit(130)
    old = outputs.install_signal_handlers()
    try:
        code = main()
    except KeyboardInterrupt:
        code = 130
    finally:
        outputs.restore_signal_handlers(old)
    sys.exit(code)
