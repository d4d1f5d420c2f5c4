"""What the `rtta` commands share: the scene argument, the load and view flags, and the
scene, Settings and Renderer made from them (checked; failures are RttaErrors)."""

from __future__ import annotations

import argparse

from ..errors import RttaError
from ..scene.camera import PROJECTIONS
from ..scene.framing import STANDARD_VIEWS
from ..scene.preprocess import DEFAULT_SMOOTH_ANGLE
from .guard import say


def parse_size(text: str, what: str = "--size") -> tuple[int, int]:
    """(W, H) from WxH, checked as the library checks it."""
    from ..renderer.options import check_size

    return check_size(text, what)


def scene_arg(p: argparse.ArgumentParser) -> None:
    """The optional scene file and the load options."""
    p.add_argument(
        "scene",
        nargs="?",
        help="glTF/GLB/OBJ/STL/PLY/3MF/OFF, STEP, IFC, COLLADA, USD or 3DXML file (default: the built-in demo)",
    )
    add_load_options(p)


def add_load_options(p: argparse.ArgumentParser) -> None:
    """Mesh preprocessing options of every command that loads a scene (the viewer's too)."""
    p.add_argument(
        "--smooth-angle",
        type=float,
        default=DEFAULT_SMOOTH_ANGLE,
        metavar="DEG",
        help="normals are smoothed across edges below this angle where the file has none "
        f"(default {DEFAULT_SMOOTH_ANGLE:g}; 0 = faceted, 180 = smooth everywhere)",
    )
    p.add_argument(
        "--smooth", action="store_true", help="recompute normals by --smooth-angle even where the file has its own"
    )
    p.add_argument(
        "--no-cache",
        action="store_true",
        help="read the file itself, neither reading nor writing the scene cache "
        "($RTTA_CACHE_DIR, else ~/.cache/rtta: a file opened before loads from there)",
    )


def view_args(p: argparse.ArgumentParser) -> None:
    """The camera, viewport and atlas flags of export and snapshot."""
    p.add_argument(
        "--camera",
        default=None,
        help="AZ,EL,DIST orbit (degrees, degrees, scene radii), or AZ,EL: the distance that frames "
        "the visible parts (default: 35,25)",
    )
    p.add_argument(
        "--view",
        choices=tuple(STANDARD_VIEWS),
        default=None,
        help="a standard view relative to the file's up axis (Z in CAD/BIM files, Y in glTF), framed",
    )
    p.add_argument(
        "--projection",
        choices=PROJECTIONS,
        default=None,
        help="perspective (default) or ortho: an orthographic view keeps the scale the perspective "
        "one shows at the target",
    )
    p.add_argument("--hide", nargs="+", default=[], metavar="NAME", help="objects left out (names, groups, globs)")
    p.add_argument("--size", default="1024x768", help="viewport WxH")
    p.add_argument("--fov", type=float, default=45.0, help="vertical field of view in degrees")
    p.add_argument("--border", type=int, default=1, help="border around each atlas region in pixels")
    p.add_argument("--atlas-max", default=None, help="maximum atlas layer size WxH (default: viewport + border)")
    p.add_argument("--max-layers", type=int, default=None, help="cap on atlas layers")
    p.add_argument("--capture-path", choices=("auto", "vs", "gs"), default="auto")
    p.add_argument(
        "--region-scale", type=float, default=1.0, help="atlas texels per viewport pixel (0.25 to 4; default 1)"
    )
    p.add_argument(
        "--bounds",
        choices=("aabb", "obb"),
        default="aabb",
        help="object bounds projected per frame: the paper's AABB or the tighter oriented box",
    )
    p.add_argument(
        "--parameterize",
        choices=("auto", "cpu", "gpu"),
        default="auto",
        help="where Algorithm 1, the capture's draw lists and compositing's order are made: compute shaders "
        "(gpu; auto: where they build) or numpy (cpu, the reference)",
    )
    p.add_argument(
        "--blend",
        choices=("auto", "raster", "compute"),
        default="auto",
        help="how a GPU-driven frame blends the ghosted context: sprites (raster) or a compute pass "
        "(compute; auto: on GPUs with few raster units, such as NVIDIA's H100)",
    )
    p.add_argument(
        "--context-scale",
        type=float,
        default=None,
        help="region scale of objects outside the focus, as a fraction of --region-scale "
        "(0.25 to 1; default: the library's, see docs/modes.md); upsampled depth-aware when composited",
    )


def load_options(args: argparse.Namespace) -> dict:
    """The loader's keyword arguments from add_load_options' flags (checked)."""
    if not 0.0 <= args.smooth_angle <= 180.0:
        raise RttaError(f"--smooth-angle must be between 0 and 180 degrees, got {args.smooth_angle:g}")
    return {"smooth_angle": args.smooth_angle, "smooth": args.smooth, "cache": not args.no_cache}


def load(args):
    """The scene of args.scene (the demo without one), its warnings said on stderr."""
    from ..scene.loader import load_scene_or_demo

    scene = load_scene_or_demo(args.scene, **load_options(args))
    for note in scene.warnings:
        say("warning", note, scene.source)
    return scene


def settings_of(args):
    """Checked Settings from view_args' flags."""
    from ..renderer.options import make_settings

    return make_settings(
        args.border,
        args.atlas_max,
        args.max_layers,
        args.capture_path,
        args.region_scale,
        args.bounds,
        getattr(args, "context_scale", None),
        getattr(args, "parameterize", "auto"),
        getattr(args, "blend", "auto"),
    )


def make_renderer(ctx, scene, settings):
    """A Renderer; what the driver lacks and the fallback used are said once on stderr."""
    from ..gl.context import Capabilities
    from ..renderer.renderer import Renderer

    caps = Capabilities.of(ctx)
    caps.capture_path(settings.capture_path)  # a path the driver lacks is an error, before any work
    for note in caps.notes if settings.capture_path == "auto" else []:
        say("note", note)
    return Renderer(ctx, scene, settings)


def camera_of(args, scene, viewport: tuple[int, int]):
    """(Camera, hidden object ids) of view_args' flags (--camera or --view, --projection, --fov,
    --hide), or of the view --view-file read (args.saved_view, set by views.saved_view_of)."""
    from ..renderer.snapshot import resolve_names
    from .views import camera_of_view, saved_view_of

    if getattr(args, "saved_view", None) is None:
        args.saved_view = saved_view_of(args)
    hidden = resolve_names(scene, args.hide, "--hide")
    return camera_of_view(args, args.saved_view, scene, viewport, hidden), hidden


NAME_LISTS = ("focus", "hide", "opacity")  # options of one or more names (argparse's nargs="+")


def scene_after_names(args, scene: str = "scene") -> None:
    """`--focus hub model.glb`: a list option takes every word after it, the scene file too.
    Where no scene is given, a list's last word that names a scene file (a suffix rtta reads)
    is taken back as the scene (`args.<scene>`): the default scene, the demo, has no part of
    such a name, and a file that is missing is then said to be."""
    if getattr(args, scene, "") is not None:
        return
    for name in NAME_LISTS:
        words = getattr(args, name, None)
        if words and names_scene_file(words[-1]):
            setattr(args, scene, words.pop())
            return


def names_scene_file(word: str) -> bool:
    """Whether `word` names a file of a format rtta reads (by its suffix)."""
    from pathlib import Path

    from ..scene.readers import SUFFIXES

    return Path(word).suffix.lower() in SUFFIXES
