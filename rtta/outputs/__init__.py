"""Output files, and PNGs of GL arrays (row 0 = bottom) as images (top row first).

This is the one place that decides whether an output path may be written, and how outputs
are committed: every command (export, snapshot, ldi) and the viewer's screenshots ask here.
An output never replaces an input of the same run (the scene file and the files it refers
to, a projector image, a points file), never replaces a folder that `rtta export` did not
write (recognised by its records.json and its file names), and never a mount point. Outputs
are written beside their place and renamed into it; `committing()` marks that rename (signals
wait while it happens); once the output that ends a command is in place, SIGINT/SIGTERM/
SIGHUP no longer interrupt the run (it finishes and says so). Before that,
`install_signal_handlers()` turns those signals into `Interrupted`, so every `finally` that
removes a temporary runs.
"""

from __future__ import annotations

import os
import re
import shutil
import signal
import stat
import tempfile
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np
from PIL import Image

from ..errors import RttaError, reason

NAME_MAX = 255  # bytes in one path component (Linux, macOS)
PATH_MAX = 4096
EXPORT_FILE = re.compile(
    r"^(records\.json|atlas_color_\d+\.png|atlas_(depth|id)\.npy|std_color\.png|"
    r"std_(depth|id)\.npy)$"
)
SIGNALS = tuple(s for s in (getattr(signal, n, None) for n in ("SIGINT", "SIGTERM", "SIGHUP")) if s is not None)


class Interrupted(KeyboardInterrupt):
    """A signal (SIGINT, SIGTERM, SIGHUP) arrived before the command's output was in place."""

    def __init__(self, signum: int) -> None:
        super().__init__(signum)
        self.signum = signum


class _State:
    depth = 0  # inside committing() or quiet_signals(): a signal waits
    finished = False  # the output that ends the command is in place: signals are not raised any more
    raised = False  # Interrupted has been raised once: later signals only wait (cleanup runs)
    requested: int | None = None  # the first signal while not finished


def _handler(signum, frame) -> None:
    if _State.finished:
        return  # the run's output is in place: finish and say so
    if _State.requested is None:
        _State.requested = signum
    if _State.depth or _State.raised:
        return  # raised at the next commit, or already unwinding
    _State.raised = True
    raise Interrupted(signum)


def install_signal_handlers() -> dict:
    """Make SIGINT/SIGTERM/SIGHUP raise Interrupted (main thread only); returns the previous
    handlers for restore_signal_handlers. Signals ignored on purpose (nohup) stay ignored."""
    _State.depth, _State.finished, _State.raised, _State.requested = 0, False, False, None
    old = {}
    for sig in SIGNALS:
        try:
            if signal.getsignal(sig) is signal.SIG_IGN:
                continue
            old[sig] = signal.signal(sig, _handler)
        except (ValueError, OSError):  # not the main thread, or not allowed: leave it
            pass
    return old


def _ignore_signals() -> None:
    """Once the final output is in place, rtta's own handlers become SIG_IGN: Python puts
    SIG_DFL back for handlers written in Python while the interpreter shuts down, so a signal
    in the last milliseconds of the process would kill it (exit -2) after its work was done."""
    for sig in SIGNALS:
        try:
            if signal.getsignal(sig) is _handler:
                signal.signal(sig, signal.SIG_IGN)
        except (ValueError, OSError):  # not the main thread: the handler stays and returns
            pass


def restore_signal_handlers(old: dict) -> None:
    for sig, handler in old.items():
        signal.signal(sig, handler)


def finished() -> bool:
    """Whether the output that ends this run has replaced its old version."""
    return _State.finished


def interrupt_requested() -> int | None:
    """The signal that asked this run to stop before its final output was in place (even if
    a library swallowed the Interrupted it raised)."""
    return None if _State.finished else _State.requested


@contextmanager
def committing(final: bool = False) -> Iterator[None]:
    """Signals wait while the block renames an output into place. A signal that came earlier
    (and was swallowed or waited) is raised here, before anything is replaced. `final`: this
    output ends the command (an export, a snapshot, an LDI result); once it is in place the
    run finishes and signals are not raised any more. After other outputs (a dataset's
    views) signals stop the run again as before."""
    if _State.requested is not None and not _State.finished:
        raise Interrupted(_State.requested)
    _State.depth += 1
    try:
        yield
    finally:
        _State.depth -= 1
    if final:
        _State.finished = True
        _ignore_signals()
    elif _State.requested is not None and not _State.raised:
        _State.raised = True
        raise Interrupted(_State.requested)  # it came during the rename: stop now, the file is whole


@contextmanager
def quiet_signals() -> Iterator[None]:
    """Signals wait during the block (used while cleaning up temporaries)."""
    _State.depth += 1
    try:
        yield
    finally:
        _State.depth -= 1


@contextmanager
def signals_held() -> Iterator[None]:
    """Signals wait during the block and stop the run when it ends. For imports of native
    libraries: an exception raised by a signal handler while OpenCASCADE's module (imported
    with trimesh) initialises kills the process (SIGSEGV or std::terminate), measured at
    about 1 in 15 interrupted `rtta export` runs. (Blocking the signals in the main thread
    is not enough: numpy's worker threads receive them.)"""
    _State.depth += 1
    try:
        yield
    finally:
        _State.depth -= 1
    if _State.requested is not None and not (_State.finished or _State.raised or _State.depth):
        _State.raised = True
        raise Interrupted(_State.requested)


# ---- paths ----------------------------------------------------------------------------
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
    if not parent.is_dir():
        raise RttaError("parent directory does not exist", path.parent)
    return parent


def check_file(
    path: str | Path, inputs: Iterable[str | Path] | None = (), *, suffix: str | None = None, what: str = "--out"
) -> Path:
    """RttaError unless `path` may be (re)written as a file: a name the file system takes,
    the wanted suffix, an existing folder as parent, not a folder, FIFO, device or mount
    point itself, and not any input of this run (also through links)."""
    path = Path(path)
    _check_name(path, what)
    if suffix and path.suffix.lower() != suffix:
        raise RttaError(f"{what} must name a {suffix} file", path)
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
    return path


def check_folder(path: str | Path, inputs: Iterable[str | Path] | None = (), *, what: str = "--out") -> Path:
    """RttaError unless folder `path` may be replaced by an export: it does not exist, or it is
    empty, or it holds only what `rtta export` writes (records.json and the images); it is
    not a mount point, not the current folder or one above it, and holds no input."""
    path = Path(path)
    _check_name(path, what)
    _parent_dir(path)
    real = _resolved(path)
    for source in _inputs(inputs):
        if source == real or real in source.parents:
            raise RttaError(f"holds an input of this run ({source.name}); {what} must not replace it", path)
    if not path.exists() and not path.is_symlink():
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
        for n in names:  # a folder still to be made holds no input
            _check_name(folder / n, what)
        return [folder / n for n in names]
    return [check_file(folder / n, inputs, suffix=suffix, what=what) for n in names]


# ---- writing ------------------------------------------------------------------------------
def staging_dir(target: Path) -> Path:
    """A new hidden folder beside `target` to write into before it is renamed into place."""
    with quiet_signals():
        try:
            return Path(tempfile.mkdtemp(prefix=f".{target.name[:64]}.", dir=target.parent))
        except OSError as exc:
            raise os_error(exc, target) from None


def remove_tree(path: Path) -> None:
    with quiet_signals():
        shutil.rmtree(path, ignore_errors=True)


def replace_dir(new: Path, target: Path, *, final: bool = False) -> None:
    """Swap folder `new` into `target`: the old folder is moved aside first and removed last;
    signals wait until the swap is done (`final`: see committing)."""
    with committing(final):
        try:
            if not target.exists():
                os.replace(new, target)
                return
            old = Path(tempfile.mkdtemp(prefix=f".{target.name[:64]}.old.", dir=target.parent))
            os.rmdir(old)
            os.replace(target, old)
            try:
                os.replace(new, target)
            except BaseException:
                os.replace(old, target)
                raise
        except OSError as exc:
            raise os_error(exc, target) from None
    remove_tree(old)


# ---- PNGs -----------------------------------------------------------------------------------
def to_image(rgba_gl: np.ndarray) -> Image.Image:
    return Image.fromarray(np.ascontiguousarray(rgba_gl[::-1]))


def atomic_write(
    path: str | Path, write: Callable[[str], object], *, overwrite: bool = True, final: bool = False
) -> Path:
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
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes 0600; a saved file gets the user's usual mode
        write(tmp)
        with committing(final):
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


def save_png(path: str | Path, rgba_gl: np.ndarray, *, overwrite: bool = True, final: bool = False) -> Path:
    """Write a GL-convention array as PNG, atomically (see atomic_write)."""
    return atomic_write(path, lambda tmp: to_image(rgba_gl).save(tmp, format="PNG"), overwrite=overwrite, final=final)
