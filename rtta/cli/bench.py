"""`rtta bench ...`: the benchmarks that print tables (rtta.bench), their flags and their runs."""

from __future__ import annotations

from ..errors import RttaError
from .common import parse_size


def add_parsers(sub):
    """The bench subcommand and its benchmarks; gives the benchmarks' subparsers (dataset adds one)."""
    p = sub.add_parser("bench", help="benchmarks that print tables")
    bsub = p.add_subparsers(dest="bench", required=True)
    b = bsub.add_parser("capture", help="STD / RTT / RTTA frame times on the paper's Table 1 sizes")
    b.add_argument("--size", default="1024x1024")
    b.add_argument("--quick", action="store_true", help="short run (fewer frames, smaller scenes)")
    b.add_argument("--full", action="store_true", help="also Algorithm 1's CPU and GPU paths at 100k parts")
    b.add_argument("--json", default=None, help="also write the figures as JSON")
    _projection(b)
    b = bsub.add_parser("composite", help="per-mode frame time against STD, and re-composite time")
    b.add_argument("--size", default="1024x1024")
    b.add_argument("--quick", action="store_true")
    _projection(b)
    b.add_argument(
        "--scene",
        nargs="+",
        default=None,
        metavar="NAME",
        help="demo, table1-N, random-N or a file (default: the demo and the Table 1 rows)",
    )
    b.add_argument("--json", default=None)
    b = bsub.add_parser("reliability", help="random extreme cameras against STD, and a soak (docs/reliability.md)")
    b.add_argument("--sweep", type=int, default=10000, help="random cameras per scene")
    b.add_argument("--soak", type=int, default=20000, help="soak frames per scene")
    b.add_argument("--quick", action="store_true", help="200 cameras, 500 soak frames, a 200-object scene")
    b.add_argument(
        "--scenes", default=None, metavar="NAME,...", help="only these of demo, random-2000, textured-64 (default: all)"
    )
    b.add_argument("--json", default=None)
    b = bsub.add_parser(
        "scale",
        help="generated 1k/10k/100k-part assemblies (and the engine): load vs "
        "trimesh.load, peak RSS, param+pack, STD, capture, ghosted, viewer fps",
    )
    b.add_argument("--size", default="1280x720")
    b.add_argument("--quick", action="store_true", help="the 1k assembly only, fewer rounds")
    b.add_argument("--parts", default=None, metavar="N,...", help="assembly sizes (default 1000,10000,100000)")
    b.add_argument("--no-viewer", action="store_true", help="skip the viewer's frames per second")
    b.add_argument("--normals", action="store_true", help="assemblies with a NORMAL attribute (no smoothing)")
    b.add_argument("--json", default=None)
    b = bsub.add_parser(
        "frame",
        help="per path of Algorithm 1 (cpu, gpu): a frame's Python ms outside GL calls, wall ms and GPU ms per stage",
    )
    b.add_argument("--size", default="1280x720")
    b.add_argument("--parts", default="1000,10000,100000", metavar="N,...", help="generated assembly sizes")
    b.add_argument("--scene", nargs="*", default=(), metavar="FILE", help="scene files besides (e.g. the engine)")
    b.add_argument(
        "--mode", nargs="+", default=["ghosted"], choices=("sprites", "transparent", "ghosted", "ghosted-ao")
    )
    b.add_argument("--frames", type=int, default=7, help="frames per figure")
    b.add_argument("--json", default=None)
    b = bsub.add_parser("packing", help="our packer against rectpack and rectangle-packer")
    b.add_argument("--quick", action="store_true")
    b.add_argument("--json", default=None)
    b = bsub.add_parser("ldi", help="the seed's LDI table, parity-test throughput against trimesh, error by resolution")
    b.add_argument("--quick", action="store_true", help="20,000 points, the generated shapes, two resolutions")
    b.add_argument("--points", type=int, default=1_000_000)
    b.add_argument("--json", default=None)
    b = bsub.add_parser(
        "material",
        help="textured objects without and with batching (material atlas, "
        "BVH chunks): draw calls, frame time, atlas memory",
    )
    b.add_argument("--objects", type=int, default=240, help="textured boxes in the generated scene")
    b.add_argument(
        "--max-vertices",
        type=int,
        default=480,
        help="BVH leaf size in vertices (the seed used 5000 for a city; the generated scene is smaller)",
    )
    b.add_argument("--quick", action="store_true", help="5 frames per figure, 16 textures")
    b.add_argument("--json", default=None)
    b = bsub.add_parser(
        "report",
        help="error against run time: regenerate docs/performance/report.md's report block and docs/bench/'s plots",
    )
    b.add_argument(
        "--quick",
        action="store_true",
        help="small scenes and grids, under two minutes (default output: out/report-quick/)",
    )
    b.add_argument(
        "--markdown",
        default=None,
        help="markdown file whose report block is replaced (default: docs/performance/report.md)",
    )
    b.add_argument("--plots", default=None, help="folder for the PNG plots (default: docs/bench)")
    b = bsub.add_parser("formats", help="load time of every scene file: the format's library against rtta")
    b.add_argument("files", nargs="*", help="scene files (default: every one in ../shared/data)")
    b.add_argument("--json", default=None)
    return bsub


def cmd_bench(args) -> int:
    from ..bench import render as bench
    from ..outputs import check_file

    if getattr(args, "json", None):  # a --json that cannot be written fails before the benchmark
        check_file(
            args.json, [*(getattr(args, "files", None) or []), *(getattr(args, "scene", None) or [])], what="--json"
        )

    if args.bench == "capture":
        return bench.run_capture(
            parse_size(args.size), quick=args.quick, json_path=args.json, projection=args.projection, full=args.full
        )
    if args.bench == "composite":
        return bench.run_composite(
            parse_size(args.size), quick=args.quick, json_path=args.json, scenes=args.scene, projection=args.projection
        )
    if args.bench == "reliability":
        from ..bench.reliability_table import run_reliability

        sweep, soak = (200, 500) if args.quick else (args.sweep, args.soak)
        if sweep < 1 or soak < 2:
            raise RttaError("--sweep must be at least 1 and --soak at least 2")
        only = args.scenes.split(",") if args.scenes else None
        return run_reliability(sweep, soak, quick=args.quick, json_path=args.json, only=only)
    if args.bench == "ldi":
        from ..bench.ldi import run_ldi

        if args.points < 1:
            raise RttaError("--points must be at least 1")
        return run_ldi(quick=args.quick, points=args.points, json_path=args.json)
    if args.bench == "material":
        from ..bench.material import run_material

        if args.objects < 1 or args.max_vertices < 3:
            raise RttaError("--objects must be at least 1 and --max-vertices at least 3")
        return run_material(args.objects, quick=args.quick, json_path=args.json, max_vertices=args.max_vertices)
    if args.bench == "formats":
        from ..bench.formats import run_formats

        return run_formats(args.files, json_path=args.json)
    if args.bench == "dataset":
        from .dataset import cmd_bench_dataset

        return cmd_bench_dataset(args)
    if args.bench == "scale":
        from ..bench.scale import run_scale

        return run_scale(
            parse_size(args.size),
            quick=args.quick,
            sizes=args.parts,
            json_path=args.json,
            viewer=not args.no_viewer,
            normals=args.normals,
        )
    if args.bench == "frame":
        from ..bench.frame_cost import run_frame

        if args.frames < 1:
            raise RttaError("--frames must be at least 1")
        parts = [int(p) for p in args.parts.split(",") if p.strip()] if args.parts else []
        return run_frame(parse_size(args.size), parts, args.scene, args.mode, args.frames, args.json)
    if args.bench == "report":
        from ..bench.report import run_report

        return run_report(quick=args.quick, markdown=args.markdown, plots=args.plots)
    return bench.run_packing(quick=args.quick, json_path=args.json)


def _projection(b) -> None:
    b.add_argument(
        "--projection",
        choices=("perspective", "ortho"),
        default="perspective",
        help="the benchmark camera's projection (default perspective, the paper's)",
    )
