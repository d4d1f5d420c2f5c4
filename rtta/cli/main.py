"""The `rtta` command: export, snapshot, info, ldi, dataset, bench. Expected failures print one line and exit 2."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..errors import RttaError, printable
from ..outputs import check_file, check_folder, check_into_folder, os_error
from ..scene.preprocess import DEFAULT_SMOOTH_ANGLE
from .guard import OneLineParser, run_command, say


def parse_size(text: str, what: str = "--size") -> tuple[int, int]:
    from ..renderer.api import check_size

    return check_size(text, what)


def _scene_arg(p: argparse.ArgumentParser) -> None:
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


def _view_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--camera", default=None, help="AZ,EL,DIST orbit (degrees, degrees, scene radii)")
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
        "--context-scale",
        type=float,
        default=None,
        help="region scale of objects outside the focus, as a fraction of --region-scale "
        "(0.25 to 1; default: the library's, see README); upsampled depth-aware when composited",
    )


def build_parser() -> argparse.ArgumentParser:
    parser = OneLineParser(prog="rtta", description="Render-to-texture-atlas for ghosted views.")
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("export", help="write per-object amodal images (atlas) and the direct render")
    _scene_arg(p)
    _view_args(p)
    p.add_argument("--out", required=True, help="output folder (replaced atomically)")
    p = sub.add_parser("snapshot", help="render STD or a composite mode to PNG, headless")
    _scene_arg(p)
    _view_args(p)
    p.add_argument("--mode", default="ghosted-ao", help="std, sprites, transparent, ghosted or ghosted-ao")
    p.add_argument(
        "--focus",
        nargs="+",
        default=[],
        metavar="NAME",
        help="objects highlighted: opaque in ghosted modes, outlined in sprites/transparent",
    )
    p.add_argument("--opacity", nargs="+", default=[], metavar="NAME=A", help="per-object opacity in [0, 1]")
    p.add_argument("--context-opacity", type=float, default=None, help="opacity of non-focus objects (ghosted)")
    p.add_argument("--edge-width", type=int, default=1, help="edge detection distance in pixels (ghosted-ao)")
    p.add_argument("--ao-radius", type=float, default=6.0, help="ambient occlusion radius in pixels (ghosted-ao)")
    p.add_argument("--ao-strength", type=float, default=1.0, help="ambient occlusion strength (ghosted-ao)")
    p.add_argument(
        "--ao-objects",
        choices=("focus", "all"),
        default=None,
        help="ambient occlusion on the focus objects only or on all (ghosted-ao; default: see README)",
    )
    p.add_argument(
        "--halo",
        type=int,
        default=0,
        metavar="WIDTH",
        help="ghosted modes: a dark halo WIDTH pixels wide around focus objects where context lies behind",
    )
    p.add_argument(
        "--order",
        choices=("auto", "object", "pixel"),
        default=None,
        help="transparency order (transparent, ghosted context): by object (bounds centres) or per "
        "pixel (each object's surface depth; nested parts blend right); auto (default): per pixel "
        "in transparent, by object in the ghosted context (see README)",
    )
    p.add_argument(
        "--edge-objects",
        choices=("focus", "all"),
        default=None,
        help="edges on the focus objects only or on all (ghosted-ao; default: see README)",
    )
    p.add_argument(
        "--projector",
        default=None,
        metavar="IMAGE[,AZ,EL,DIST]",
        help="paint the scene with IMAGE ('default': the shipped grid) from an orbit position "
        "(as --camera); without one the projector sits at the camera",
    )
    p.add_argument("--projector-fov", type=float, default=30.0, help="projector field of view in degrees")
    p.add_argument("--no-projector-shadows", action="store_true", help="let the image pass through objects")
    p.add_argument(
        "--lens",
        default=None,
        metavar="SHAPE[,RADIUS]",
        help="cut the context away inside a lens (ghosted modes): sphere or box with a radius in "
        "world units (default: 0.6 x the focus bounds' diagonal), or the name of a closed object",
    )
    p.add_argument("--lens-at", default=None, metavar="X,Y,Z", help="lens centre in world units (default: the focus)")
    out = p.add_mutually_exclusive_group(required=True)
    out.add_argument("--out", help="PNG file to write")
    out.add_argument("--all-modes", metavar="DIR", help="write <mode>.png for every mode into DIR")
    p = sub.add_parser("info", help="list the objects of a scene (--tree: its part tree), its unit and up axis")
    _scene_arg(p)
    from .info import add_arguments

    add_arguments(p)
    p = sub.add_parser("bench", help="benchmarks that print tables")
    bsub = p.add_subparsers(dest="bench", required=True)
    b = bsub.add_parser("capture", help="STD / RTT / RTTA frame times on the paper's Table 1 sizes")
    b.add_argument("--size", default="1024x1024")
    b.add_argument("--quick", action="store_true", help="short run (fewer frames, smaller scenes)")
    b.add_argument("--json", default=None, help="also write the figures as JSON")
    b = bsub.add_parser("composite", help="per-mode frame time against STD, and re-composite time")
    b.add_argument("--size", default="1024x1024")
    b.add_argument("--quick", action="store_true")
    b.add_argument(
        "--scene",
        nargs="+",
        default=None,
        metavar="NAME",
        help="demo, table1-N, random-N or a file (default: the demo and the Table 1 rows)",
    )
    b.add_argument("--json", default=None)
    b = bsub.add_parser("reliability", help="random extreme cameras against STD, and a soak (RELIABILITY.md)")
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
        help="error against run time: regenerate the report block of BENCHMARKS.md and the plots in docs/bench/",
    )
    b.add_argument(
        "--quick",
        action="store_true",
        help="small scenes and grids, under two minutes (default output: out/report-quick/)",
    )
    b.add_argument(
        "--markdown", default=None, help="markdown file whose report block is replaced (default: BENCHMARKS.md)"
    )
    b.add_argument("--plots", default=None, help="folder for the PNG plots (default: docs/bench)")
    b = bsub.add_parser("formats", help="load time of every scene file: the format's library against rtta")
    b.add_argument("files", nargs="*", help="scene files (default: every one in ../shared/data)")
    b.add_argument("--json", default=None)
    from .dataset import add_parsers as add_dataset
    from .ldi import add_parser as add_ldi

    add_ldi(sub)
    add_dataset(sub, bsub, (add_load_options, load_options, parse_size))
    return parser


def load_options(args: argparse.Namespace) -> dict:
    """The loader's keyword arguments from add_load_options' flags (checked)."""
    if not 0.0 <= args.smooth_angle <= 180.0:
        raise RttaError(f"--smooth-angle must be between 0 and 180 degrees, got {args.smooth_angle:g}")
    return {"smooth_angle": args.smooth_angle, "smooth": args.smooth}


def _load(args):
    from ..scene.loader import load_scene_or_demo

    scene = load_scene_or_demo(args.scene, **load_options(args))
    for note in scene.warnings:
        say("warning", note, scene.source)
    return scene


def _settings(args):
    from ..renderer.api import make_settings

    return make_settings(
        args.border,
        args.atlas_max,
        args.max_layers,
        args.capture_path,
        args.region_scale,
        args.bounds,
        getattr(args, "context_scale", None),
    )


def _renderer(ctx, scene, settings):
    """A Renderer; what the driver lacks and the fallback used are said once on stderr."""
    from ..gl.context import Capabilities
    from ..renderer.renderer import Renderer

    caps = Capabilities.of(ctx)
    caps.capture_path(settings.capture_path)  # a path the driver lacks is an error, before any work
    for note in caps.notes if settings.capture_path == "auto" else []:
        say("note", note)
    return Renderer(ctx, scene, settings)


def cmd_export(args) -> int:
    from ..gl.context import shared_context
    from ..renderer.api import orbit_camera
    from ..renderer.export import export

    viewport = parse_size(args.size)
    settings = _settings(args)
    check_folder(args.out, [args.scene])  # before the work: a refused --out fails fast
    scene = _load(args)
    camera = orbit_camera(scene, args.camera, args.fov)
    ctx = shared_context()
    renderer = _renderer(ctx, scene, settings)
    try:
        out = export(renderer, camera, viewport, args.out)
    except ValueError as exc:
        raise RttaError(str(exc), args.out) from None
    finally:
        renderer.release()
    print(f"wrote {printable(out)} ({scene.count} objects, renderer: {renderer.caps.renderer})")
    return 0


def cmd_snapshot(args) -> int:
    from ..gl.context import shared_context
    from ..renderer.api import make_style, orbit_camera
    from ..renderer.snapshot import SNAPSHOT_MODES, parse_opacities, render_modes, resolve_names, write_pngs

    if args.mode not in SNAPSHOT_MODES:
        raise RttaError(f"--mode must be one of {', '.join(SNAPSHOT_MODES)}, got '{args.mode}'")
    viewport = parse_size(args.size)
    _snapshot_targets(args, [args.scene, *_projector_files(args)])  # refused outputs fail before the work
    scene = _load(args)
    camera = orbit_camera(scene, args.camera, args.fov)
    style = make_style(
        resolve_names(scene, args.focus, "--focus"),
        parse_opacities(scene, args.opacity),
        context_opacity=args.context_opacity,
        edge_width=args.edge_width,
        ao_radius=args.ao_radius,
        ao_strength=args.ao_strength,
        ao_objects=args.ao_objects,
        edge_objects=args.edge_objects,
        order=args.order,
        halo=args.halo,
    )
    targets = _snapshot_targets(args, [*scene.inputs, *_projector_files(args)])
    renderer = _renderer(shared_context(), scene, _settings(args))
    if args.projector is not None:
        renderer.projector = _projector(args, scene, camera)
    if args.lens is not None:
        renderer.lens = _lens(args, scene, style.focus)
    try:
        images = render_modes(renderer, camera, viewport, list(targets), style)
    except ValueError as exc:
        raise RttaError(str(exc)) from None
    finally:
        renderer.release()
    if args.all_modes:
        try:
            Path(args.all_modes).mkdir(exist_ok=True)
        except OSError as exc:
            raise os_error(exc, args.all_modes) from None
    for path in write_pngs(images, targets):
        print(f"wrote {printable(path)}")
    return 0


def _snapshot_targets(args, inputs: list) -> dict:
    """{mode: PNG path} for --out or --all-modes, each allowed by rtta.outputs."""
    from ..renderer.snapshot import SNAPSHOT_MODES

    if args.out is not None:
        return {args.mode: check_file(args.out, inputs, suffix=".png")}
    paths = check_into_folder(args.all_modes, [f"{m}.png" for m in SNAPSHOT_MODES], inputs, suffix=".png")
    return dict(zip(SNAPSHOT_MODES, paths, strict=True))


def _projector_files(args) -> list[str]:
    """The image file --projector may read (its text, or the text before AZ,EL,DIST)."""
    if not args.projector:
        return []
    return [n for n in {args.projector, args.projector.rsplit(",", 3)[0]} if n != "default"]


def _lens(args, scene, focus):
    """--lens SHAPE[,RADIUS] or --lens NAME, placed by --lens-at X,Y,Z (default: on the focus)."""
    from ..renderer.snapshot import make_lens

    return make_lens(scene, args.lens, args.lens_at, focus)


def _projector(args, scene, camera):
    """--projector IMAGE[,AZ,EL,DIST]: the image file (or 'default') and where it stands."""
    from ..renderer.snapshot import make_projector

    return make_projector(scene, camera, args.projector, args.projector_fov, not args.no_projector_shadows)


def cmd_info(args) -> int:
    from .info import run

    return run(_load(args), args.tree)


def cmd_bench(args) -> int:
    from ..bench import render as bench

    if args.bench == "capture":
        return bench.run_capture(parse_size(args.size), quick=args.quick, json_path=args.json)
    if args.bench == "composite":
        return bench.run_composite(parse_size(args.size), quick=args.quick, json_path=args.json, scenes=args.scene)
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
    if args.bench == "report":
        from ..bench.report import run_report

        return run_report(quick=args.quick, markdown=args.markdown, plots=args.plots)
    return bench.run_packing(quick=args.quick, json_path=args.json)


def main(argv: list[str] | None = None) -> int:
    from ..memory import steady_heap
    from .dataset import cmd_dataset
    from .ldi import cmd_ldi

    try:
        args = build_parser().parse_args(argv)
    except RttaError as exc:
        say("error", str(exc))
        return 2
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
