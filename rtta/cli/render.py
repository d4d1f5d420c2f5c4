"""`rtta export` and `rtta snapshot`: their flags and their runs."""

from __future__ import annotations

from contextlib import suppress
from pathlib import Path

from ..errors import RttaError, printable
from ..outputs import check_file, check_folder, check_into_folder, os_error
from .common import camera_of, load, make_renderer, parse_size, scene_arg, settings_of, view_args
from .cutaway import cutaway_args, staging_of
from .views import saved_view_of, view_file_args


def add_parsers(sub) -> None:
    """The export and snapshot subcommands."""
    p = sub.add_parser("export", help="write per-object amodal images (atlas) and the direct render")
    scene_arg(p)
    view_args(p)
    cutaway_args(p)
    view_file_args(p)
    p.add_argument("-o", "--out", required=True, help="output folder (replaced atomically)")
    p = sub.add_parser("snapshot", help="render STD or a composite mode to PNG, headless")
    scene_arg(p)
    view_args(p)
    cutaway_args(p)
    view_file_args(p, save=True)
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
        help="ambient occlusion on the focus objects only or on all (ghosted-ao; default: see docs/modes.md)",
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
        "in transparent, by object in the ghosted context (see docs/modes.md)",
    )
    p.add_argument(
        "--edge-objects",
        choices=("focus", "all"),
        default=None,
        help="edges on the focus objects only or on all (ghosted-ao; default: see docs/modes.md)",
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
    out.add_argument("-o", "--out", help="image to write: .png, or .jpg, .webp, .tif by its suffix")
    out.add_argument("--all-modes", metavar="DIR", help="write <mode>.png for every mode into DIR")


def cmd_export(args) -> int:
    from ..gl.context import shared_context
    from ..renderer.export import export
    from ..renderer.placing import check_staging

    viewport = parse_size(args.size)
    settings = settings_of(args)
    args.saved_view = saved_view_of(args)  # --view-file's, or the flags'
    staging = staging_of(args)
    check_folder(args.out, [args.scene])  # before the work: a refused --out fails fast
    scene = load(args)
    camera, hidden = camera_of(args, check_staging(staging, scene), viewport)
    ctx = shared_context()
    renderer = make_renderer(ctx, scene, settings)
    renderer.staging = staging
    renderer.hidden = set(hidden)
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
    from ..renderer.options import make_style
    from ..renderer.placing import check_staging
    from ..renderer.snapshot import SNAPSHOT_MODES, parse_opacities, render_modes, resolve_names, write_pngs
    from ..renderer.view_file import view_writer

    args.saved_view = saved_view_of(args)  # --view-file's (its mode, focus... replace the flags), or the flags'
    if args.mode not in SNAPSHOT_MODES:
        raise RttaError(f"--mode must be one of {', '.join(SNAPSHOT_MODES)}, got '{args.mode}'")
    viewport = parse_size(args.size)
    if args.save_view:  # checked as a view file, before the work
        view_writer(args.saved_view, args.save_view, [args.scene, args.view_file])
    staging = staging_of(args)
    _snapshot_targets(args, [args.scene, *_projector_files(args)])  # refused outputs fail before the work
    scene = load(args)
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
    framed = check_staging(staging, scene, style.focus)  # the scene, or exploded its boxes moved
    camera, hidden = camera_of(args, framed, viewport)
    targets = _snapshot_targets(args, [*scene.inputs, *_projector_files(args)])
    renderer = make_renderer(shared_context(), scene, settings_of(args))
    renderer.staging = staging
    renderer.hidden = set(hidden)
    if args.projector is not None:
        renderer.projector = _projector(args, scene, camera)
    if args.lens is not None:
        renderer.lens = _lens(args, framed, style.focus)
    try:
        images = render_modes(renderer, camera, viewport, list(targets), style)
    except ValueError as exc:
        raise RttaError(str(exc)) from None
    finally:
        renderer.release()
    inputs = [*scene.inputs, *_projector_files(args)]
    also = [(args.save_view, view_writer(args.saved_view, args.save_view, inputs))] if args.save_view else []
    made = None
    if args.all_modes and not Path(args.all_modes).is_dir():
        try:
            Path(args.all_modes).mkdir()
            made = Path(args.all_modes)
        except OSError as exc:
            raise os_error(exc, args.all_modes) from None
    try:
        written = write_pngs(images, targets, also)
    except BaseException:
        if made is not None:  # the folder this run made, empty again
            with suppress(OSError):
                made.rmdir()
        raise
    for path in written:
        print(f"wrote {printable(path)}")
    return 0


def _snapshot_targets(args, inputs: list) -> dict:
    """{mode: image path} for --out or --all-modes, each allowed by rtta.outputs."""
    from ..renderer.snapshot import IMAGE_FORMATS, SNAPSHOT_MODES

    if args.out is not None:
        return {args.mode: check_file(args.out, inputs, suffix=tuple(IMAGE_FORMATS))}
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
