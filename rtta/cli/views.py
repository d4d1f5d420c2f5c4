"""--view-file and --save-view: the view of snapshot, export and dataset as a SavedView
(rtta.renderer.view_file), from the flags or from a file, and the camera it gives."""

from __future__ import annotations

import argparse

from ..errors import RttaError


def view_file_args(p: argparse.ArgumentParser, save: bool = False) -> None:
    """--view-file (and, for snapshot, --save-view)."""
    p.add_argument(
        "--view-file",
        default=None,
        metavar="FILE.json",
        help="render the view saved by --save-view: its camera, projection, hidden parts, sections and "
        "explode (and for snapshot its mode, focus, opacities and style) replace the flags",
    )
    if save:
        p.add_argument(
            "--save-view",
            default=None,
            metavar="FILE.json",
            help="also save this view (camera, projection, mode, focus, hidden parts, opacities, style, "
            "sections, explode) as a JSON file that --view-file renders again, byte for byte",
        )


def saved_view_of(args: argparse.Namespace):
    """The SavedView of --view-file (its cutaway and explode copied into the flags, which
    staging_of reads), or of the flags, with the orbit still to resolve (camera_of_view)."""
    from ..renderer.options import CORE_STYLE
    from ..renderer.view_file import SavedView, read_view

    if getattr(args, "view_file", None):
        given = [f for f in ("camera", "view", "projection") if getattr(args, f, None) is not None]
        if given:
            raise RttaError(f"--view-file gives the camera: leave out --{given[0]}")
        view = read_view(args.view_file)
        _to_flags(args, view)
        return view
    view = SavedView(hidden=list(getattr(args, "hide", [])))
    if hasattr(args, "mode"):  # snapshot
        view.mode, view.focus = args.mode, list(args.focus)
        view.opacity = _opacities(args.opacity)
        view.style = {k: getattr(args, k) for k in CORE_STYLE}
    planes = list(getattr(args, "section", []) or [])
    if planes:
        view.sections = {"planes": planes, "caps": args.caps, "scope": args.section_scope}
    if str(getattr(args, "explode", "0")) not in ("0", "0.0"):
        view.explode = {"factor": _float(args.explode), "scope": args.explode_scope}
    return view


def camera_of_view(args: argparse.Namespace, view, scene, viewport: tuple[int, int], hidden):
    """The view's Camera; its orbit resolved from --camera/--view/--projection/--fov first
    when it came from the flags (framing the parts not `hidden` in `viewport`)."""
    from ..scene.framing import scene_orbit

    if view.orbit is None:
        if not 1.0 <= args.fov <= 170.0:  # NaN fails too
            raise RttaError(f"--fov must be between 1 and 170 degrees, got {args.fov}")
        view.orbit = scene_orbit(
            scene,
            args.camera,
            args.fov,
            projection=args.projection or "perspective",
            view=args.view,
            aspect=viewport[0] / viewport[1],
            hidden=hidden,
        )
    return view.orbit.camera(scene, hidden)


def _to_flags(args: argparse.Namespace, view) -> None:
    """The file's mode, focus, opacities, style, hidden parts, cutaway and explode into args."""
    args.hide = list(view.hidden)
    if hasattr(args, "mode"):
        args.mode, args.focus = view.mode, list(view.focus)
        args.opacity = [f"{name}={alpha!r}" for name, alpha in view.opacity.items()]
        for key, value in view.style.items():
            setattr(args, key, value)
    if hasattr(args, "section"):
        s, e = view.sections or {}, view.explode or {}
        args.section = list(s.get("planes", []))
        args.caps, args.section_scope = s.get("caps", "solid"), s.get("scope", "all")
        args.explode, args.explode_scope = repr(float(e.get("factor", 0.0))) if e else "0", e.get("scope", "all")


def _opacities(items: list[str]) -> dict[str, float]:
    """NAME=A flags as a name -> alpha mapping (checked again, with the scene, by parse_opacities)."""
    out = {}
    for item in items:
        name, _, value = item.rpartition("=")
        out[name] = _float(value)
    return out


def _float(text) -> float:
    try:
        return float(text)
    except (TypeError, ValueError):
        return float("nan")
