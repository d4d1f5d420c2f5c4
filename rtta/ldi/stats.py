"""One row of the seed's LDI table (slide 18): complexity, timings and memory of an LDI
and its compressed form; printed by `rtta ldi --stats` and `rtta bench ldi`."""

from __future__ import annotations

import numpy as np

STATS_COLUMNS = (
    "mesh",
    "vertices",
    "d_min",
    "d_max",
    "d",
    "t_crop ms",
    "t_comp ms",
    "t_peel ms",
    "t_view ms",
    "M_crop B",
    "M_comp B",
    "ratio",
)


def stats_row(name: str, vertices: np.ndarray, ldi, packed) -> tuple:
    """One row of the seed's table; ratio = M_comp / M_crop (below 1: compression pays)."""
    t = ldi.timings
    return (
        name,
        len(vertices),
        ldi.complexity[0],
        ldi.complexity[1],
        ldi.depth,
        f"{t['crop']:.3f}",
        f"{packed.milliseconds:.3f}",
        f"{t['peel']:.3f}",
        f"{t['view']:.3f}",
        ldi.nbytes,
        packed.nbytes,
        f"{packed.nbytes / max(ldi.nbytes, 1):.2f}",
    )
