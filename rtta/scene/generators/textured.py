"""A generated textured scene for the material atlas's tests and benchmark: boxes in a grid,
each face carrying its object's texture tiled `repeat` times (coordinates beyond [0, 1]),
over a set of textures of awkward kinds (non-power-of-two, odd, 1x1, grey, RGBA), several
objects sharing each texture, and some objects with no texture at all."""

from __future__ import annotations

import numpy as np

from ..model import Scene, from_meshes

# (name, width, height, kind): what the acceptance asks the atlas to handle
TEXTURE_KINDS = (
    ("checker", 64, 64, "rgb"),
    ("stripes_npot", 48, 80, "rgb"),
    ("odd_npot", 37, 21, "rgb"),
    ("one_texel", 1, 1, "rgb"),
    ("grey", 32, 32, "grey"),
    ("rgba", 128, 64, "rgba"),
    ("rings", 256, 256, "rgb"),
    ("wide", 96, 16, "rgb"),
)


REPEATS = (1.0, 2.5, 3.0)  # tilings per face, object i takes REPEATS[i % 3] by default


def make_texture(width: int, height: int, kind: str, seed: int) -> np.ndarray:
    """uint8 [h, w, 4] (row 0 = v 0): smooth colour waves with a few sharp lines, so both
    bilinear filtering and mip levels are exercised."""
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:height, 0:width].astype(np.float64)
    u, v = (x + 0.5) / width, (y + 0.5) / height
    channels = []
    for _ in range(3):
        fu, fv, phase = rng.integers(1, 4), rng.integers(1, 4), rng.uniform(0, 2 * np.pi)
        wave = 0.5 + 0.45 * np.sin(2 * np.pi * (fu * u + fv * v) + phase)  # periodic: wraps cleanly
        channels.append(wave)
    rgb = np.stack(channels, -1)
    lines = ((x % max(2, width // 4)) < 1) | ((y % max(2, height // 4)) < 1)
    rgb[lines] *= 0.35
    if kind == "grey":
        rgb[:] = rgb.mean(axis=-1, keepdims=True)
    alpha = np.where(kind == "rgba", 0.3 + 0.7 * u, 1.0)[..., None]
    rgba = np.concatenate([rgb, np.broadcast_to(alpha, rgb.shape[:2] + (1,))], -1)
    return np.clip(np.round(rgba * 255), 0, 255).astype(np.uint8)


def textured_box(repeat: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A unit box (side 1, centred) with 4 vertices per face and uv in [0, repeat]^2."""
    verts, uvs, faces = [], [], []
    for axis in range(3):
        for sign in (-1.0, 1.0):
            a, b = (axis + 1) % 3, (axis + 2) % 3
            corners = np.zeros((4, 3))
            corners[:, axis] = 0.5 * sign
            corners[:, a] = [-0.5, 0.5, 0.5, -0.5]
            corners[:, b] = [-0.5, -0.5, 0.5, 0.5]
            base = len(verts) * 4
            verts.append(corners)
            uvs.append(np.array([[0, 0], [repeat, 0], [repeat, repeat], [0, repeat]], np.float64))
            tri = [[0, 1, 2], [0, 2, 3]] if sign > 0 else [[0, 2, 1], [0, 3, 2]]
            faces.append(np.array(tri) + base)
    return np.concatenate(verts), np.concatenate(faces), np.concatenate(uvs)


def textured_scene(
    n: int = 24,
    seed: int = 0,
    untextured_every: int = 7,
    repeat_choices=REPEATS,
    textures: int | None = None,
    spacing: float = 1.6,
) -> Scene:
    """n textured boxes on a square grid in the x-y plane (facing +z), turned a little so
    three faces show; every `untextured_every`-th object keeps only its material colour."""
    rng = np.random.default_rng(seed)
    count = len(TEXTURE_KINDS) if textures is None else textures
    images = [make_texture(*TEXTURE_KINDS[i % len(TEXTURE_KINDS)][1:], seed=seed * 1000 + i) for i in range(count)]
    side = int(np.ceil(np.sqrt(n)))
    parts, uvs, ids, colors = [], [], [], []
    for i in range(n):
        repeat = float(repeat_choices[i % len(repeat_choices)])
        v, f, uv = textured_box(repeat)
        angle = np.radians(rng.uniform(15, 35)), np.radians(rng.uniform(15, 35))
        rx = np.array([[1, 0, 0], [0, np.cos(angle[0]), -np.sin(angle[0])], [0, np.sin(angle[0]), np.cos(angle[0])]])
        ry = np.array([[np.cos(angle[1]), 0, np.sin(angle[1])], [0, 1, 0], [-np.sin(angle[1]), 0, np.cos(angle[1])]])
        centre = np.array([(i % side) - (side - 1) / 2, (side - 1) / 2 - (i // side), 0.0]) * spacing
        parts.append((f"box{i:04d}", v @ (ry @ rx).T + centre, f, None))
        textured = untextured_every <= 0 or (i + 1) % untextured_every != 0
        uvs.append(uv if textured else None)
        ids.append(i % count if textured else -1)
        colors.append([1.0, 1.0, 1.0, 1.0] if textured else [0.8, 0.4, 0.3, 1.0])
    return from_meshes(parts, colors, source=f"<textured {n} seed {seed}>", uvs=uvs, texture_ids=ids, textures=images)
