"""Exploded views: a world offset per object that pulls the parts apart along the part tree.

Every group of the file's tree (Scene.paths; a flat file is one group) with two children or
more separates them: each child moves away from the group's centre by its own distance from
it, so the layout grows about the centre; children that share the centre (within 5% of the
group's radius) are spread along the group's main axis (PCA of its children's centres, or of
its parts' box corners when those coincide) instead. Groups nearer the root separate first:
over F in [0, 1] each depth of the tree has its own window of F (overlapping its neighbours'),
so sub-assemblies move apart before their parts do; beyond 1 every offset grows linearly, up to
EXPLODE_MAX. The offsets are scaled so that no part moves more than 0.9 scene radii per unit
of F: the motion is continuous and never jumps.
"""

from __future__ import annotations

from typing import Literal, get_args

import numpy as np

from ..errors import RttaError

ExplodeScope = Literal["all", "focus"]
EXPLODE_SCOPES: tuple[ExplodeScope, ...] = get_args(ExplodeScope)
EXPLODE_MAX = 4.0
CENTRAL = 0.05  # a child this close to its group's centre (times the group's radius) shares it
MAX_SPEED = 0.9  # scene radii per unit of F
STAGGER = 0.5  # the deepest level starts ramping at F = STAGGER * (levels - 1) / levels


def check_explode(factor: float | str, scope: str = "all") -> float:
    """The explode factor as a float in [0, EXPLODE_MAX], or RttaError naming the flag."""
    try:
        f = float(factor)
    except (TypeError, ValueError):
        f = float("nan")
    if not 0.0 <= f <= EXPLODE_MAX:  # NaN fails too
        raise RttaError(f"--explode must be a number in [0, {EXPLODE_MAX:g}], got '{factor}'")
    if scope not in EXPLODE_SCOPES:
        raise RttaError(f"--explode-scope must be one of {', '.join(EXPLODE_SCOPES)}, got '{scope}'")
    return f


def _main_axis(points: np.ndarray) -> np.ndarray | None:
    """Unit principal axis of points [k, 3] (None when they coincide)."""
    q = points - points.mean(axis=0)
    if len(points) < 2 or not np.abs(q).max() > 0:
        return None
    _, s, vt = np.linalg.svd(q, full_matrices=False)
    return vt[0] if s[0] > 0 else None


def _separations(scene) -> list[tuple[int, np.ndarray]]:
    """Per group with two children or more: (its depth, float64 [n, 3] full-explosion
    offset each object gets from this group's separation; zero outside the group)."""
    n = scene.count
    lo, hi = np.asarray(scene.aabb_min, np.float64), np.asarray(scene.aabb_max, np.float64)
    paths = [scene.path_of(o) for o in range(n)]
    groups: dict[tuple, dict[object, list[int]]] = {}
    for o, path in enumerate(paths):
        for depth in range(len(path) + 1):
            child = path[depth] if depth < len(path) else ("object", o)  # a subgroup, or the object itself
            groups.setdefault(path[:depth], {}).setdefault(child, []).append(o)
    out = []
    for key, children in groups.items():
        if len(children) < 2:
            continue
        members = [np.asarray(m) for m in children.values()]
        box = [(lo[m].min(axis=0), hi[m].max(axis=0)) for m in members]
        centres = np.array([(a + b) / 2 for a, b in box])
        glo, ghi = np.min([a for a, _ in box], axis=0), np.max([b for _, b in box], axis=0)
        centre, radius = (glo + ghi) / 2, max(float(np.linalg.norm(ghi - glo)) / 2, 1e-30)
        move = centres - centre
        central = np.linalg.norm(move, axis=1) < CENTRAL * radius
        if central.sum() >= 2:
            axis = _main_axis(centres)
            if axis is None:
                everything = np.concatenate(members)
                corners = np.concatenate([lo[everything], hi[everything], (lo[everything] + hi[everything]) / 2])
                axis = _main_axis(corners)
            axis = np.array([1.0, 0.0, 0.0]) if axis is None else axis
            ids = np.flatnonzero(central)
            extent = max(float(np.abs((box[i][1] - box[i][0]) @ axis).max()) for i in ids)
            spread = (np.arange(len(ids)) - (len(ids) - 1) / 2) * max(extent, 0.1 * radius)
            move[ids] = spread[:, None] * axis
        offsets = np.zeros((n, 3))
        for m, v in zip(members, move, strict=True):
            offsets[m] = v
        out.append((len(key), offsets))
    return out


def windows(levels: int, factor: float) -> np.ndarray:
    """Activation of each tree depth (rank 0 at the root) at F: depth k ramps from 0 at
    F = k * STAGGER / levels to 1 at F = 1 (the root first, all done together), then is F."""
    if factor >= 1.0:
        return np.full(levels, factor)
    start = np.arange(levels) * STAGGER / levels
    return np.clip((factor - start) / (1.0 - start), 0.0, 1.0)


def _fastest(per_level: np.ndarray) -> float:
    """Largest speed (world units per unit F) of any object: between the ramps' starts the
    active depths move at their slopes; beyond 1 all at 1."""
    levels = len(per_level)
    start = np.arange(levels) * STAGGER / levels
    speeds = [np.linalg.norm(per_level.sum(axis=0), axis=1).max()]
    for a in range(levels):  # F in [start[a], start[a + 1]): depths 0..a ramp
        slopes = np.where(np.arange(levels) <= a, 1.0 / (1.0 - start), 0.0)
        speeds.append(np.linalg.norm(np.einsum("l,lnk->nk", slopes, per_level), axis=1).max())
    return float(max(speeds))


def explode_offsets(scene, factor: float, movable: np.ndarray | None = None) -> np.ndarray:
    """World offset float64 [n, 3] of every object at explode factor `factor` (0: none).

    Parameters
    ----------
    scene : Scene
        Its B_world boxes and part tree (paths) decide the motion.
    factor : float
        0 assembled, 1 fully exploded, up to EXPLODE_MAX (checked by check_explode).
    movable : bool array [n], optional
        Only these objects move (--explode-scope focus); None: all.
    """
    n = scene.count
    if factor <= 0 or n == 0:
        return np.zeros((n, 3))
    seps = _separations(scene)
    if not seps:
        return np.zeros((n, 3))
    depths = sorted({d for d, _ in seps})
    rank = {d: i for i, d in enumerate(depths)}
    per_level = np.zeros((len(depths), n, 3))
    for d, offs in seps:
        per_level[rank[d]] += offs
    fastest = _fastest(per_level)
    scale = min(1.0, MAX_SPEED * scene.radius / fastest) if fastest > 0 else 0.0
    out = np.einsum("l,lnk->nk", windows(len(depths), factor), per_level) * scale
    if movable is not None:
        out[~np.asarray(movable, bool)] = 0.0
    return out
