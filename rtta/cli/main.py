"""The `rtta` command: export, snapshot, info, ldi, dataset, bench. Expected failures print one line and exit 2."""

from __future__ import annotations

import argparse
import re
import shlex
import sys

from ..errors import RttaError
from .bench import add_parsers as add_bench
from .bench import cmd_bench
from .common import add_load_options, load_options, names_scene_file, parse_size, scene_after_names, scene_arg
from .common import load as _load
from .guard import OneLineParser, hold_closed_streams, run_command, say
from .render import add_parsers as add_render
from .render import cmd_export, cmd_snapshot

__all__ = ["add_load_options", "build_parser", "load_options", "main", "parse_size"]


def build_parser() -> argparse.ArgumentParser:
    parser = OneLineParser(prog="rtta", description="Render-to-texture-atlas for ghosted views.")
    sub = parser.add_subparsers(dest="command", required=True)
    add_render(sub)
    p = sub.add_parser("info", help="list the objects of a scene (--tree: its part tree), its unit and up axis")
    scene_arg(p)
    from .info import add_arguments

    add_arguments(p)
    bsub = add_bench(sub)
    from .dataset import add_parsers as add_dataset
    from .ldi import add_parser as add_ldi

    add_ldi(sub)
    add_dataset(sub, bsub, (add_load_options, load_options, parse_size))
    return parser


def cmd_info(args) -> int:
    from .info import run

    return run(_load(args), args.tree)


def section_values(argv: list[str]) -> list[str]:
    """`--section -x=V` as `--section=-x=V`: a plane that removes what lies below starts with a
    dash, which argparse would take for an option of its own."""
    out: list[str] = []
    for arg in argv:
        if out and out[-1] == "--section" and re.fullmatch(r"-[xyzXYZ](=.*)?", arg):
            out[-1] = f"--section={arg}"
        else:
            out.append(arg)
    return out


COMMANDS = ("export", "snapshot", "info", "bench", "ldi", "dataset")


def _scene_first(argv: list[str]) -> RttaError | None:
    """The error for `rtta FILE` (a scene where the command goes, as a viewer is called): what
    to run instead; None where the first argument is no scene file."""
    from pathlib import Path

    first = argv[0] if argv else ""
    if not first or first.startswith("-") or first in COMMANDS:
        return None
    if not names_scene_file(first) and not Path(first).is_file():
        return None
    name = shlex.quote(first)
    return RttaError(
        f"a command comes first: `rtta-view {name}` opens it, `rtta snapshot {name} -o view.png` renders it "
        "(`rtta --help` lists the commands)",
        first,
    )


def main(argv: list[str] | None = None) -> int:
    from ..memory import steady_heap
    from .dataset import cmd_dataset
    from .ldi import cmd_ldi

    if argv is None:  # the whole process: `rtta info x.glb >&-` must not hand fd 1 to a file it opens
        hold_closed_streams()
    argv = sys.argv[1:] if argv is None else argv
    try:
        args = build_parser().parse_args(section_values(argv))
    except RttaError as exc:
        say("error", str(_scene_first(argv) or exc))
        return 2
    scene_after_names(args)
    steady_heap()
    handler = {
        "export": cmd_export,
        "snapshot": cmd_snapshot,
        "info": cmd_info,
        "bench": cmd_bench,
        "ldi": cmd_ldi,
        "dataset": cmd_dataset,
    }[args.command]
    return run_command(handler, args, process=argv is None)


if __name__ == "__main__":
    sys.exit(main())
