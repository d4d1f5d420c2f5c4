"""PNG writing: GL arrays (row 0 = bottom) to images (top row first), atomically."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import numpy as np
from PIL import Image


def to_image(rgba_gl: np.ndarray) -> Image.Image:
    return Image.fromarray(np.ascontiguousarray(rgba_gl[::-1]))


def save_png(path: str | Path, rgba_gl: np.ndarray, *, overwrite: bool = True) -> Path:
    """Write a GL-convention array as PNG, atomically. With overwrite=False an existing file
    is a FileExistsError, checked atomically (hard link), so a file that appears meanwhile
    is never replaced either."""
    path = Path(path)
    if not overwrite and path.exists():
        raise FileExistsError(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".png", dir=path.parent)
    os.close(fd)
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o666 & ~umask)          # mkstemp makes 0600; a saved image is the user's usual mode
    try:
        to_image(rgba_gl).save(tmp, format="PNG")
        if overwrite:
            os.replace(tmp, path)
        else:
            os.link(tmp, path)
    finally:
        Path(tmp).unlink(missing_ok=True)
    return path
