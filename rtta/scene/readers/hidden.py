"""Transforms that flatten space: a zero scale on an axis (glTF's way to hide a node, and
any format's) or a rank-deficient matrix. Every conforming viewer draws nothing there, so
the readers leave such nodes out, and everything below them, with one warning naming the
nodes, rather than refusing a legal file (the normals' inverse transform does not exist)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...errors import RttaError

SINGULAR = 1e-12  # volume of a transform's columns scaled to a largest component of 1: at most this, it flattens


def singular(m: np.ndarray) -> np.ndarray:
    """Whether the 3x3 part of each transform flattens space.

    Parameters
    ----------
    m : numpy.ndarray
        Transforms [..., 4, 4] or [..., 3, 3], column vectors (p' = m @ p).

    Returns
    -------
    numpy.ndarray
        bool [...]: a column of zeros, or columns that, each scaled to a largest component of
        1, span a volume of at most SINGULAR (float64's precision). Scale-free: a tiny uniform scale is not
        singular. A non-finite transform is not called singular (the loader refuses it).
    """
    r = np.asarray(m, np.float64)[..., :3, :3]
    length = np.abs(r).max(axis=-2)  # each column's largest component [..., 3] (a norm underflows below 1e-154)
    with np.errstate(all="ignore"):
        unit = r / np.where(length > 0, length, 1.0)[..., None, :]
        volume = np.abs(np.linalg.det(unit))
    return (length.min(axis=-1) == 0) | (volume <= SINGULAR)


def note_hidden(hiders: list[str], drawn: int, path: Path, warnings: list[str]) -> None:
    """One warning naming the nodes whose singular transform hid geometry; an RttaError when
    they hid all of it (`drawn` objects are left), as an empty file would be.

    Parameters
    ----------
    hiders : list of str
        Names of the nodes whose transform is singular and that hid at least one object, in
        file order, each once.
    drawn : int
        How many objects are drawn.
    path : pathlib.Path
        The file, for the message.
    warnings : list of str
        The reader's warnings; the note is appended.
    """
    if not hiders:
        return
    if not drawn:
        raise RttaError(
            "every object lies under a singular transform (a zero scale, which hides a node): nothing to draw", path
        )
    more = " ..." if len(hiders) > 5 else ""
    warnings.append(
        f"{len(hiders)} node(s) with a singular transform (a zero scale, which hides a node) are not drawn, "
        "nor anything below them: " + ", ".join(hiders[:5]) + more
    )
