"""`rtta ldi MESH`: volumetric parity tests of points against a closed mesh, and the seed's
table of LDI figures (`--stats`). MESH is a scene file (all its objects together) or
`shape:NAME` for a generated shape (sphere, box, torus, torus-knot, vase)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from ..errors import RttaError
from ..ldi.stats import STATS_COLUMNS, stats_row


def add_parser(sub) -> None:
    p = sub.add_parser("ldi", help="classify points inside/outside a closed mesh with a layered depth image")
    p.add_argument("mesh", help="closed mesh: a scene file, or shape:NAME (sphere, box, torus, torus-knot, vase)")
    p.add_argument("--points", help="float array [N, 3] (.npy) of world points")
    p.add_argument("--out", help="bool array [N] (.npy) written atomically: True = inside")
    p.add_argument("--resolution", type=int, default=512, help="LDI resolution N (N x N texels)")
    p.add_argument("--compressed", action="store_true", help="test against the compressed depth ranges")
    p.add_argument("--stats", action="store_true", help="print the seed's table row for this mesh")


def load_mesh(spec: str) -> tuple[str, np.ndarray, np.ndarray]:
    """(name, vertices, faces) of a closed mesh; RttaError naming the file otherwise."""
    from ..ldi.peel import closed_mesh

    if spec.startswith("shape:"):
        from ..scene.shapes import SHAPES

        kind = spec.removeprefix("shape:")
        if kind not in SHAPES:
            raise RttaError(f"unknown shape; shapes: {', '.join(SHAPES)}", spec)
        mesh = SHAPES[kind]()
        return spec, *closed_mesh(mesh.vertices, mesh.faces, spec)
    from ..scene.loader import load_scene

    scene = load_scene(spec)
    vertices = scene.positions.astype(np.float64) + scene.origin
    v, f = closed_mesh(vertices, scene.indices.reshape(-1, 3), spec)
    return spec, v, f


def read_points(path: str) -> np.ndarray:
    if not Path(path).is_file():
        raise RttaError("no such file", path)
    with open(path, "rb") as fh:
        if fh.read(6) != b"\x93NUMPY":
            raise RttaError("not a .npy file (numpy's format: np.save)", path)
    try:
        points = np.load(path, allow_pickle=False)
    except (ValueError, OSError, EOFError) as exc:
        raise RttaError(f"not a .npy array ({str(exc).splitlines()[0][:80]})", path) from None
    if points.ndim != 2 or points.shape[1] != 3 or points.dtype.kind not in "fiu":
        raise RttaError(f"expected a numeric array of shape [N, 3], got {points.dtype} {list(points.shape)}", path)
    if not np.isfinite(points).all():
        raise RttaError(f"{int((~np.isfinite(points)).any(axis=1).sum())} points are NaN or infinite", path)
    return points.astype(np.float64)


def write_npy(path: str, array: np.ndarray) -> None:
    """Write atomically: the old file stays until the new one is complete."""
    from ..imageio import atomic_write

    if not Path(path).parent.is_dir():
        raise RttaError("the output folder does not exist", path)
    def save(tmp: str) -> None:
        with open(tmp, "wb") as fh:          # a file object: np.save would add ".npy" to a bare name
            np.save(fh, array)

    atomic_write(path, save)


def cmd_ldi(args: argparse.Namespace) -> int:
    from ..gl.context import shared_context
    from ..ldi.gpu import ParityTest
    from ..ldi.pack import compress
    from ..ldi.peel import build

    if not args.stats and not (args.points and args.out):
        raise RttaError("rtta ldi needs --points and --out, or --stats")
    points = read_points(args.points) if args.points else None
    if args.out and Path(args.out).is_dir():
        raise RttaError("is a folder; --out takes a .npy file", args.out)
    name, vertices, faces = load_mesh(args.mesh)
    ctx = shared_context()
    ldi = build(ctx, vertices, faces, args.resolution)
    packed = compress(ldi)
    if args.stats:
        from ..tools.tables import print_table

        print_table(STATS_COLUMNS, [stats_row(name, vertices, ldi, packed)])
    if points is not None:
        test = ParityTest(ctx, ldi, packed)
        try:
            inside = test.classify(points, compressed=args.compressed)
        finally:
            test.release()
        write_npy(args.out, inside)
        print(f"{args.out}: {int(inside.sum())} of {len(inside)} points inside {name} "
              f"(LDI {ldi.size[0]}x{ldi.size[1]}, {ldi.depth} layers)", file=sys.stderr)
    return 0
