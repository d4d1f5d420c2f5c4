"""Which scene sizes and distances from the origin a driver draws: a unit box scaled by S and
moved by D along every axis, snapshots in STD and sprites, printed as the share of pixels
drawn (python scripts/probe_tiny.py; run on each new driver, see rtta.scene.model.TINY_SCENE)."""

from __future__ import annotations

import warnings

import numpy as np
import trimesh

import rtta
from rtta.scene.model import from_meshes

CASES = [(s, 0.0) for s in (1e-5, 1e-10, 1e-15, 1e-20, 1e-25, 1e-28, 1e-30, 1e-33, 1e-36, 1e-38)] + [
    (1e-3, 1e7),
    (1e-5, 1e7),
    (1e-7, 1e7),
    (1.0, 1e12),
]


def drawn(img: np.ndarray) -> float:
    return float((np.abs(img[..., :3].astype(int) - img[0, 0, :3].astype(int)).max(-1) > 10).mean())


def main() -> None:
    box = trimesh.creation.box()
    for scale, shift in CASES:
        v = np.asarray(box.vertices) * scale + shift
        scene = from_meshes([("box", v, np.asarray(box.faces), None)], [(0.8, 0.3, 0.2, 1.0)])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            shares = [
                drawn(rtta.snapshot(scene, mode, size=(96, 72), camera=(0, 0, 2.5)))
                for mode in ("std", "sprites", "ghosted-ao")
            ]
        print(
            f"scale {scale:8.0e} shift {shift:8.0e}: drawn std {shares[0]:.3f} sprites {shares[1]:.3f} "
            f"ghosted-ao {shares[2]:.3f}  warnings: {'; '.join(w[:60] for w in scene.warnings) or '-'}"
        )


if __name__ == "__main__":
    main()
