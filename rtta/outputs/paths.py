"""Whether an output path may be written (rtta.outputs re-exports these; every command and
the viewer's screenshots ask there): a name the file system takes, an existing folder as
parent that this user may write into, never an input of the same run (the scene file and
the files it refers to, a projector image, a points file), never a folder that `rtta
export` did not write (recognised by its records.json and its file names), never a mount
point, and never a file or folder the user made read-only.
"""

from __future__ import annotations

import os
import re
import stat
from collections.abc import Iterable
from pathlib import Path

from ..errors import RttaError, reason

NAME_MAX = 255  # bytes in one path component (Linux, macOS)
PATH_MAX = 4096
EXPORT_FILE = re.compile(
    r"^(records\.json|atlas_color_\d+\.png|atlas_(depth|id)\.npy|std_color\.png|"
    r"std_(depth|id)\.npy)$"
)


def os_error(exc: OSError, path: str | Path, doing: str = "cannot write") -> RttaError:
    """An OSError as one line naming the path (read-only or full file system, permissions ...)."""
    return RttaError(f"{doing} ({reason(exc)})", path)


def _check_name(path: Path, what: str) -> None:
    text = str(path)
    if "\0" in text:
        raise RttaError(f"{what} contains a NUL byte", text.replace("\0", "\\0"))
    raw = os.fsencode(text)
    if len(raw) >= PATH_MAX:
        raise RttaError(f"{what} is longer than {PATH_MAX} bytes", text[:80] + "...")
    for part in path.parts:
        if len(os.fsencode(part)) > NAME_MAX:
            raise RttaError(f"{what}: a name in the path is longer than {NAME_MAX} bytes", path)


def _resolved(path: Path) -> Path:
    try:
        return path.resolve()
    except (OSError, RuntimeError) as exc:  # a symlink loop
        raise RttaError(f"cannot resolve the path ({exc})", path) from None


def _same(a: Path, b: Path) -> bool:
    try:
        return a == b or (a.exists() and b.exists() and os.path.samefile(a, b))
    except OSError:
        return False


def _inputs(inputs: Iterable[str | Path] | None) -> list[Path]:
    out = []
    for p in inputs or ():
        if p is None:
            continue
        try:
            out.append(Path(p).resolve())
        except (OSError, RuntimeError, ValueError):
            continue
    return out


def _parent_dir(path: Path) -> Path:
    parent = _resolved(path).parent
    if parent.is_dir():
        return parent
    try:
        os.stat(parent)
        problem = "is not a folder"
    except (FileNotFoundError, NotADirectoryError):
        problem = "parent directory does not exist"
    except OSError as exc:  # a folder above it that this user may not enter
        problem = f"cannot reach the folder ({reason(exc)})"
    raise RttaError(problem, path.parent)


def _writable(path: Path, what: str, *, replace: bool = False) -> None:
    """RttaError unless this user may write into `path`'s folder and, with `replace`, change
    `path` itself (a file or folder the user made read-only is never replaced: as `cp` or a
    shell's `>` would not; root may, as it may there)."""
    folder = _resolved(path).parent
    for target, check in ((folder, True), (path, replace)):
        if check and not os.access(target, os.W_OK | (os.X_OK if target.is_dir() else 0)):
            try:
                read_only = bool(os.statvfs(target).f_flag & os.ST_RDONLY)
            except OSError:
                read_only = False
            if read_only:
                raise RttaError("cannot write (Read-only file system)", path)
            if target is folder:
                raise RttaError("cannot write (Permission denied)", path)
            raise RttaError(f"is read-only; {what} will not replace it", path)


def check_file(
    path: str | Path,
    inputs: Iterable[str | Path] | None = (),
    *,
    suffix: str | tuple[str, ...] | None = None,
    what: str = "--out",
) -> Path:
    """RttaError unless `path` may be (re)written as a file: a name the file system takes,
    the wanted suffix, an existing folder as parent that this user may write into, not a
    folder, FIFO, device or mount point itself, not a file the user made read-only, and not
    any input of this run (also through links)."""
    path = Path(path)
    _check_name(path, what)
    wanted = (suffix,) if isinstance(suffix, str) else suffix
    if wanted and path.suffix.lower() not in wanted:
        kinds = wanted[0] if len(wanted) == 1 else f"{', '.join(wanted[:-1])} or {wanted[-1]}"
        raise RttaError(f"{what} must name a {kinds} file", path)
    _parent_dir(path)
    real = _resolved(path)
    try:
        st = os.stat(path)
    except FileNotFoundError:
        st = None
    except OSError as exc:
        raise os_error(exc, path, "cannot inspect the output") from None
    if st is not None:
        if stat.S_ISDIR(st.st_mode):
            raise RttaError(f"is a folder; {what} takes a {suffix or ''} file".replace("  ", " "), path)
        if not stat.S_ISREG(st.st_mode):
            raise RttaError(f"is not a regular file (a device, FIFO or socket); {what} will not replace it", path)
        if os.path.ismount(path):
            raise RttaError("is a mount point; it cannot be replaced", path)
    for source in _inputs(inputs):
        if _same(real, source):
            raise RttaError(f"is an input of this run; {what} must not replace it", path)
    _writable(path, what, replace=st is not None)
    return path


def check_folder(path: str | Path, inputs: Iterable[str | Path] | None = (), *, what: str = "--out") -> Path:
    """RttaError unless folder `path` may be replaced by an export: it does not exist, or it is
    empty, or it holds only what `rtta export` writes (records.json and the images), none of
    it read-only; it is not a mount point, not the current folder or one above it, holds no
    input, and this user may write into its parent."""
    path = Path(path)
    _check_name(path, what)
    _parent_dir(path)
    real = _resolved(path)
    for source in _inputs(inputs):
        if source == real or real in source.parents:
            raise RttaError(f"holds an input of this run ({source.name}); {what} must not replace it", path)
    if not path.exists() and not path.is_symlink():
        _writable(path, what)
        return path
    if not path.is_dir() or path.is_symlink():
        raise RttaError(f"exists and is not a folder; {what} takes a folder", path)
    if os.path.ismount(path):
        raise RttaError("is a mount point; it cannot be replaced", path)
    cwd = Path.cwd().resolve()
    if real == cwd or real in cwd.parents:
        raise RttaError(f"is the current folder or holds it; {what} must name a folder of its own", path)
    try:
        names = sorted(os.listdir(path))
    except OSError as exc:
        raise os_error(exc, path, "cannot list the folder") from None
    _writable(path, what, replace=True)
    if not names:
        return path
    if "records.json" not in names:
        raise RttaError(
            f"is a folder that rtta export did not write (no records.json); {what} will not replace it", path
        )
    foreign = [n for n in names if not EXPORT_FILE.match(n) or not (path / n).is_file()]
    if foreign:
        listed = ", ".join(foreign[:3]) + (" ..." if len(foreign) > 3 else "")
        raise RttaError(f"holds files rtta export does not write ({listed}); {what} will not replace it", path)
    locked = [n for n in names if not os.access(path / n, os.W_OK)]
    if locked:
        raise RttaError(f"holds read-only files ({', '.join(locked[:3])}); {what} will not replace it", path)
    return path


def check_into_folder(
    folder: str | Path,
    names: Iterable[str],
    inputs: Iterable[str | Path] | None = (),
    *,
    suffix: str | None = None,
    what: str = "--all-modes",
) -> list[Path]:
    """The files `names` inside `folder` (made if missing), each checked like check_file."""
    folder = Path(folder)
    _check_name(folder, what)
    if folder.exists() and not folder.is_dir():
        raise RttaError(f"exists and is not a folder; {what} takes a folder", folder)
    if not folder.exists():
        _parent_dir(folder)
        _writable(folder, what)
        for n in names:  # a folder still to be made holds no input
            _check_name(folder / n, what)
        return [folder / n for n in names]
    return [check_file(folder / n, inputs, suffix=suffix, what=what) for n in names]
