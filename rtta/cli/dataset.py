"""`rtta dataset SCENE... --out DIR`, `rtta dataset merge INPUT... --out FILE` and
`rtta bench dataset`: amodal segmentation datasets (docs/datasets.md)."""

from __future__ import annotations

import argparse
import signal
import threading
from pathlib import Path

from ..errors import RttaError
from .cutaway import cutaway_args, staging_of


def add_parsers(sub, bench_sub, common: tuple) -> None:
    """The dataset command and its benchmark. `common` is main's (add_load_options,
    load_options, parse_size), handed in so that this module never imports main."""
    add_load_options = common[0]
    p = sub.add_parser(
        "dataset",
        help="amodal datasets in COCO form: every part's full and visible mask "
        "(and its unoccluded appearance) for many views; 'merge' joins shards",
        description="rtta dataset SCENE... --out DIR [options], or rtta dataset merge INPUT... --out FILE.json",
    )
    p.add_argument(
        "scenes",
        nargs="*",
        metavar="SCENE",
        help="scene files, folders or globs (default: the demo); 'merge INPUT...' joins annotation files",
    )
    p.add_argument(
        "-o",
        "--out",
        required=True,
        help="dataset folder (created; resumed when it holds the same "
        "settings); for merge, the annotations file to write",
    )
    p.add_argument("--views", type=int, default=10, help="cameras per scene (default 10)")
    p.add_argument("--seed", type=int, default=0, help="seed of the camera sampling")
    p.add_argument("--size", default="640x480", help="image WxH")
    for name, default, what in (
        ("azimuth", "0,360", "degrees about +Y"),
        ("elevation", "10,60", "degrees"),
        ("distance", "1.4,2.6", "bounding radii"),
        ("fov", "40,60", "vertical, degrees"),
    ):
        p.add_argument(
            f"--{name}",
            default=default,
            metavar="LO,HI",
            help=f"range sampled uniformly, {what} (one value: fixed; default {default})",
        )
    p.add_argument(
        "--cameras",
        default=None,
        metavar="FILE.json",
        help='explicit cameras instead: [{"orbit": [AZ, EL, DIST], "fov": F} or '
        '{"eye": [..], "target": [..], "up": [..], "fov": F}, ...]',
    )
    p.add_argument(
        "--projection",
        choices=("perspective", "ortho"),
        default="perspective",
        help="perspective (default) or ortho: an orthographic view keeps the scale perspective shows at the target",
    )
    p.add_argument(
        "--view-file",
        default=None,
        metavar="FILE.json",
        help="one view per scene: the camera, projection and hidden parts saved by `rtta snapshot --save-view`",
    )
    cutaway_args(p, scopes=False)
    p.add_argument(
        "--depth",
        choices=("png", "npy"),
        default="png",
        help="depth.png (16-bit, x depth_scale = world units) or depth.npy (float32)",
    )
    p.add_argument(
        "--appearance",
        action="store_true",
        help="also write each annotated object's RGBA image alone (alpha = amodal mask)",
    )
    p.add_argument(
        "--category-by",
        choices=("name", "group", "ifc-class"),
        default="name",
        help="one category per object name, group (part-tree parent or name stem) or IFC class",
    )
    p.add_argument(
        "--min-visible",
        type=int,
        default=0,
        metavar="PX",
        help="leave out objects with fewer visible pixels (default 0: hidden objects are kept)",
    )
    p.add_argument("--shard", default="0/1", metavar="I/N", help="render only the I-th of N slices of the views")
    p.add_argument("--workers", type=int, default=1, help="local processes, one GL context each")
    p.add_argument(
        "--keep-going",
        action="store_true",
        help="skip scenes that cannot be read (exit 2 at the end) instead of stopping",
    )
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    add_load_options(p)
    p.set_defaults(common=common)
    b = bench_sub.add_parser(
        "dataset", help="views/s and amodal masks/s: one RTTA capture per view against each object rendered alone (RTT)"
    )
    b.add_argument("--size", default="640x480")
    b.add_argument("--views", type=int, default=5, help="views per scene")
    b.add_argument("--appearance", action="store_true", help="write the objects' RGBA images too")
    b.add_argument("--quick", action="store_true", help="the demo and a 200-part scene at 320x240, 2 views")
    b.add_argument("--json", default=None)
    b.set_defaults(common=common)


def _range(text: str, name: str, lo: float, hi: float) -> tuple[float, float]:
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        values = []
    if len(values) == 1:
        values *= 2
    if len(values) != 2 or not (lo <= values[0] <= values[1] <= hi):
        raise RttaError(f"--{name} expects LO,HI (or one value) with {lo:g} <= LO <= HI <= {hi:g}, got '{text}'")
    return values[0], values[1]


def _shard(text: str) -> tuple[int, int]:
    try:
        i, n = (int(v) for v in text.split("/"))
    except ValueError:
        i, n = -1, 0
    if not 0 <= i < n:
        raise RttaError(f"--shard expects I/N with 0 <= I < N, got '{text}'")
    return i, n


def cmd_dataset(args: argparse.Namespace) -> int:
    if args.scenes[:1] == ["merge"]:
        return _merge(args)
    from ..dataset.options import Options, Run, parse_cameras
    from ..dataset.run import run

    _, load_options, parse_size = args.common
    load = load_options(args)
    if not 1 <= args.views <= 1_000_000 or args.workers < 1 or args.min_visible < 0:
        raise RttaError("--views must be 1..1000000, --workers at least 1, --min-visible at least 0")
    if args.seed < 0:  # numpy's seeds are non-negative
        raise RttaError(f"--seed must be a non-negative integer, got {args.seed}")
    staging = staging_of(args)  # checked before any scene is read
    opts = Options(
        scenes=args.scenes,
        views=args.views,
        seed=args.seed,
        size=parse_size(args.size),
        azimuth=_range(args.azimuth, "azimuth", -720, 720),
        elevation=_range(args.elevation, "elevation", -90, 90),
        distance=_range(args.distance, "distance", 1e-3, 1e6),
        fov=_range(args.fov, "fov", 0.5, 170),
        cameras=parse_cameras(args.cameras) if args.cameras else None,
        depth=args.depth,
        appearance=args.appearance,
        category_by=args.category_by,
        min_visible=args.min_visible,
        smooth_angle=load["smooth_angle"],
        smooth=load["smooth"],
        projection=args.projection,
        view_file=_view_file(args),
        sections=list(args.section),
        caps=args.caps,
        explode=staging.explode,
    )
    how = Run(
        out=Path(args.out).absolute(),
        shard=_shard(args.shard),
        workers=args.workers,
        keep_going=args.keep_going,
        progress=False if args.no_progress else None,
        cache=load["cache"],
    )
    main_thread = threading.current_thread() is threading.main_thread()
    previous = signal.signal(signal.SIGTERM, _interrupted) if main_thread else None  # a scheduler's kill
    try:
        return run(opts, how)
    finally:
        if main_thread:
            signal.signal(signal.SIGTERM, previous)


def _view_file(args: argparse.Namespace) -> dict | None:
    """--view-file's document, checked (its camera and projection replace the sampled ones)."""
    if args.view_file is None:
        return None
    from ..renderer.view_file import read_view

    view = read_view(args.view_file)
    if view.orbit is None:
        raise RttaError("a dataset's view file needs a camera", args.view_file)
    if args.cameras:
        raise RttaError("--view-file and --cameras both give the cameras: use one of them")
    return view.to_json()


def _interrupted(*_) -> None:
    raise KeyboardInterrupt


def _merge(args: argparse.Namespace) -> int:
    """rtta dataset merge INPUT... --out FILE: folders give their shard files (or annotations.json)."""
    from ..dataset import coco
    from ..outputs import check_file, write_text

    inputs: list[Path] = []
    for arg in args.scenes[1:]:
        path = Path(arg)
        if path.is_dir():
            found = sorted(path.glob("annotations-shard-*.json")) or sorted(path.glob("annotations.json"))
            if not found:
                raise RttaError("holds no annotations.json or annotations-shard-*.json", path)
            inputs += found
        elif path.is_file():
            inputs.append(path)
        else:
            raise RttaError("no such file or folder", path)
    if not inputs:
        raise RttaError("rtta dataset merge needs at least one INPUT (a dataset folder or annotations file)")
    out = Path(args.out)
    if any(out.resolve() == p.resolve() for p in inputs):
        raise RttaError("--out is one of the inputs; write the merged file elsewhere", out)
    check_file(out)  # a file this user may write (a folder, a read-only file: refused)
    if out.exists() and not _ours(out):
        raise RttaError("exists and is not an annotations file written by rtta; not replaced", out)
    doc = coco.merge(inputs, out)
    write_text(out, coco.dumps(doc))
    print(f"wrote {out}: {len(doc['images'])} images, {len(doc['annotations'])} annotations from {len(inputs)} file(s)")
    return 0


def _ours(path: Path) -> bool:
    """Whether `path` is an annotations file rtta wrote (the only kind merge replaces)."""
    from ..dataset import coco

    try:
        return path.is_file() and str(coco.read_document(path).get("info", {})).find("rtta") >= 0
    except RttaError:
        return False


def cmd_bench_dataset(args: argparse.Namespace) -> int:
    from ..bench.dataset import run_bench

    parse_size = args.common[2]
    if args.views < 1:
        raise RttaError("--views must be at least 1")
    return run_bench(
        parse_size(args.size), views=args.views, quick=args.quick, appearance=args.appearance, json_path=args.json
    )
