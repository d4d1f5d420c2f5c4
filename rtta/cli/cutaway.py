"""The cutaway and exploded-view flags of snapshot, export and dataset, and the Staging made
from them (rtta.renderer.placing)."""

from __future__ import annotations

import argparse

from ..scene.cutaway import CAPS, MAX_SECTIONS, SECTION_SCOPES
from ..scene.explode import EXPLODE_MAX, EXPLODE_SCOPES


def cutaway_args(p: argparse.ArgumentParser, scopes: bool = True) -> None:
    """--section (repeatable), --caps, --explode; with `scopes` (commands that take a focus)
    --section-scope and --explode-scope too."""
    p.add_argument(
        "--section",
        action="append",
        default=[],
        metavar="SPEC",
        help=f"cut the scene (up to {MAX_SECTIONS} planes): x=V removes what lies beyond V on the x axis "
        "(y=V, z=V likewise; world units as `rtta info` prints the bounds), -x=V what lies below; "
        "x=P%% places the plane P%% of the way across the scene's bounds, x alone halfway; "
        "nx,ny,nz,d removes the points p with n.p > d",
    )
    p.add_argument(
        "--caps",
        default="solid",
        metavar="|".join(CAPS),
        help="cut faces of closed parts: filled in the part's colour, darker (solid, default), hatched, or open",
    )
    p.add_argument(
        "--explode",
        default="0",
        metavar="F",
        help=f"pull the parts apart along the part tree: 0 assembled (default), 1 fully exploded, up to "
        f"{EXPLODE_MAX:g}; sub-assemblies separate first",
    )
    if not scopes:
        return
    p.add_argument(
        "--section-scope",
        default="all",
        metavar="|".join(SECTION_SCOPES),
        help="cut every part (all, default) or the context only, the focus parts staying whole",
    )
    p.add_argument(
        "--explode-scope",
        default="all",
        metavar="|".join(EXPLODE_SCOPES),
        help="move every part (all, default) or the focus parts only, the rest staying assembled",
    )


def staging_of(args: argparse.Namespace):
    """A checked Staging from cutaway_args' flags."""
    from ..renderer.placing import make_staging

    return make_staging(
        list(getattr(args, "section", []) or []),
        getattr(args, "caps", "solid"),
        getattr(args, "section_scope", "all"),
        getattr(args, "explode", "0"),
        getattr(args, "explode_scope", "all"),
    )
