"""`rtta ldi MESH`: volumetric parity tests of points against a closed mesh, and the seed's
table of LDI figures (`--stats`). MESH is a scene file (all its objects together) or
`shape:NAME` for a generated shape (sphere, box, torus, torus-knot, vase)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from ..errors import RttaError, printable
from ..ldi.stats import STATS_COLUMNS, stats_row
from ..outputs import check_file
from .guard import say


def add_parser(sub) -> None:
    p = sub.add_parser("ldi", help="classify points inside/outside a closed mesh with a layered depth image")
    p.add_argument("mesh", help="closed mesh: a scene file, or shape:NAME (sphere, box, torus, torus-knot, vase)")
    p.add_argument("--points", help="float array [N, 3] (.npy) of world points")
    p.add_argument("-o", "--out", help="bool array [N] (.npy) written atomically: True = inside")
    p.add_argument("--resolution", type=int, default=512, help="LDI resolution N (N x N texels)")
    p.add_argument("--compressed", action="store_true", help="test against the compressed depth ranges")
    p.add_argument("--stats", action="store_true", help="print the seed's table row for this mesh")
    p.add_argument("--no-cache", action="store_true", help="read the scene file itself, not the scene cache")


def load_mesh(spec: str, cache: bool = True) -> tuple[str, np.ndarray, np.ndarray, list[str]]:
    """(name, vertices, faces, files read) of a closed mesh; RttaError naming the file otherwise."""
    from ..ldi.peel import closed_mesh

    if spec.startswith("shape:"):
        from ..scene.generators.shapes import SHAPES

        kind = spec.removeprefix("shape:")
        if kind not in SHAPES:
            raise RttaError(f"unknown shape; shapes: {', '.join(SHAPES)}", spec)
        mesh = SHAPES[kind]()
        return spec, *closed_mesh(mesh.vertices, mesh.faces, spec), []
    from ..scene.loader import load_scene

    scene = load_scene(spec, cache=cache)
    for note in scene.warnings:
        say("warning", note, scene.source)
    vertices = scene.positions.astype(np.float64) + scene.origin
    v, f = closed_mesh(vertices, scene.indices.reshape(-1, 3), spec)
    return spec, v, f, scene.inputs


def read_points(path: str) -> np.ndarray:
    """A float [N, 3] array from a .npy file; its header is checked against the file's size
    and the memory limit before any array is allocated."""
    from ..scene.files import memory_limit, regular_file

    size = regular_file(Path(path), "points file")
    try:
        with open(path, "rb") as fh:
            if fh.read(6) != b"\x93NUMPY":
                raise RttaError("not a .npy file (numpy's format: np.save)", path)
            fh.seek(0)
            version = np.lib.format.read_magic(fh)
            if version not in ((1, 0), (2, 0)):
                raise ValueError(f".npy format version {version} is not supported")
            read = np.lib.format.read_array_header_1_0 if version == (1, 0) else np.lib.format.read_array_header_2_0
            shape, _, dtype = read(fh)
            body = fh.tell()
    except (ValueError, OSError, EOFError, SyntaxError, TypeError) as exc:
        raise RttaError(f"not a .npy array ({str(exc).splitlines()[0][:80]})", path) from None
    if len(shape) != 2 or shape[1] != 3 or dtype.kind not in "fiu":
        raise RttaError(f"expected a numeric array of shape [N, 3], got {dtype} {list(shape)}", path)
    need = shape[0] * 3 * dtype.itemsize
    if need != size - body:
        raise RttaError(
            f"the header says {shape[0]:,} points ({need:,} bytes) but the file holds {size - body:,} bytes of data",
            path,
        )
    if shape[0] * 3 * 8 * 2 > memory_limit():  # the float64 copy and the GPU buffer
        raise RttaError(f"{shape[0]:,} points are over the memory limit (RTTA_MEMORY_LIMIT_MB)", path)
    try:
        points = np.load(path, allow_pickle=False)
    except (ValueError, OSError, EOFError) as exc:
        raise RttaError(f"not a .npy array ({str(exc).splitlines()[0][:80]})", path) from None
    if not np.isfinite(points).all():
        raise RttaError(f"{int((~np.isfinite(points)).any(axis=1).sum())} points are NaN or infinite", path)
    return points.astype(np.float64)


def write_npy(path: str, array: np.ndarray) -> None:
    """Write atomically: the old file stays until the new one is complete."""
    from ..outputs import atomic_write

    def save(tmp: str) -> None:
        with open(tmp, "wb") as fh:  # a file object: np.save would add ".npy" to a bare name
            np.save(fh, array)

    atomic_write(path, save, final=True)


def cmd_ldi(args: argparse.Namespace) -> int:
    from ..gl.context import shared_context
    from ..ldi.gpu import ParityTest
    from ..ldi.pack import compress
    from ..ldi.peel import build

    if not args.stats and not (args.points and args.out):
        raise RttaError("rtta ldi needs --points and --out, or --stats")
    if not 16 <= args.resolution <= 4096:
        raise RttaError(f"--resolution must be between 16 and 4096, got {args.resolution}")
    inputs = [args.mesh, args.points]
    if args.out:
        check_file(args.out, inputs, suffix=".npy")
    points = read_points(args.points) if args.points else None
    name, vertices, faces, files = load_mesh(args.mesh, cache=not args.no_cache)
    if args.out:
        check_file(args.out, [*inputs, *files], suffix=".npy")
    center, extent = (vertices.min(axis=0) + vertices.max(axis=0)) / 2, float(np.ptp(vertices, axis=0).max())
    if points is not None:  # parity is unchanged by moving and scaling both: test at unit size,
        points = (points - center) / extent  # so float32 depths work for meshes at 1e-30 or 1e12 units
        points = np.clip(points, -4.0, 4.0)  # the mesh lies within ±0.5: points beyond stay outside, in float32
    ctx = shared_context()
    ldi = build(ctx, (vertices - center) / extent, faces, args.resolution)
    packed = compress(ldi)
    if args.stats:
        from ..bench.tables import print_table

        print_table(STATS_COLUMNS, [stats_row(name, vertices, ldi, packed)])
    if points is not None:
        test = ParityTest(ctx, ldi, packed)
        try:
            inside = test.classify(points, compressed=args.compressed)
        finally:
            test.release()
        write_npy(args.out, inside)
        print(
            f"{printable(args.out)}: {int(inside.sum())} of {len(inside)} points inside {printable(name)} "
            f"(LDI {ldi.size[0]}x{ldi.size[1]}, {ldi.depth} layers)",
            file=sys.stderr,
        )
    return 0
