"""Atomic file writing, and PNGs of GL arrays (row 0 = bottom) as images (top row first)."""

from __future__ import annotations

import os
import tempfile
from collections.abc import Callable
from pathlib import Path

import numpy as np
from PIL import Image

from .outputs import committing, os_error, quiet_signals


def to_image(rgba_gl: np.ndarray) -> Image.Image:
    return Image.fromarray(np.ascontiguousarray(rgba_gl[::-1]))


def atomic_write(path: str | Path, write: Callable[[str], None], *, overwrite: bool = True) -> Path:
    """Let `write(tmp)` fill a temporary file beside `path`, then move it into place: an old
    file stays whole until the new one is complete. With overwrite=False an existing file is
    a FileExistsError, checked atomically (hard link), so a file that appears meanwhile is
    never replaced either. Other OS errors (read-only or full file system, permissions) are
    an RttaError naming `path`; the temporary is removed in every case, signals included
    (see rtta.outputs)."""
    path = Path(path)
    if not overwrite and path.exists():
        raise FileExistsError(path)
    with quiet_signals():
        try:
            fd, tmp = tempfile.mkstemp(prefix=f".{path.name[:64]}.", suffix=path.suffix[:16], dir=path.parent)
        except OSError as exc:
            raise os_error(exc, path) from None
        os.close(fd)
    try:
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)          # mkstemp makes 0600; a saved file gets the user's usual mode
        write(tmp)
        with committing():
            if overwrite:
                os.replace(tmp, path)
            else:
                os.link(tmp, path)
    except FileExistsError:
        raise
    except OSError as exc:
        raise os_error(exc, path) from None
    finally:
        with quiet_signals():
            Path(tmp).unlink(missing_ok=True)
    return path


def save_png(path: str | Path, rgba_gl: np.ndarray, *, overwrite: bool = True) -> Path:
    """Write a GL-convention array as PNG, atomically (see atomic_write)."""
    return atomic_write(path, lambda tmp: to_image(rgba_gl).save(tmp, format="PNG"), overwrite=overwrite)
