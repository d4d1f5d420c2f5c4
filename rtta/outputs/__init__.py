"""Output files, and PNGs of GL arrays (row 0 = bottom) as images (top row first).

This is the one place that decides whether an output path may be written (the checks live
in rtta.outputs.paths, re-exported here), and how outputs are committed: every command
(export, snapshot, ldi) and the viewer's screenshots ask here. An output never replaces an
input of the same run (the scene file and the files it refers to, a projector image, a
points file), never replaces a folder that `rtta export` did not write (recognised by its
records.json and its file names), never a mount point, and never a file or folder the user
made read-only. Outputs are written beside their place and renamed into it; `committing()` marks that rename (signals
wait while it happens); once the output that ends a command is in place, SIGINT/SIGTERM/
SIGHUP no longer interrupt the run (it finishes and says so). Before that,
`install_signal_handlers()` turns those signals into `Interrupted`, so every `finally` that
removes a temporary runs.
"""

from __future__ import annotations

import os
import shutil
import signal
import tempfile
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np
from PIL import Image

from ..errors import RttaError
from .paths import EXPORT_FILE, NAME_MAX, PATH_MAX, check_file, check_folder, check_into_folder, os_error  # noqa: F401 (re-exported: every caller asks rtta.outputs)

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


# ---- writing ------------------------------------------------------------------------------
def staging_dir(target: Path) -> Path:
    """A new hidden folder beside `target` to write into before it is renamed into place."""
    with quiet_signals():
        try:
            folder = Path(tempfile.mkdtemp(prefix=f".{target.name[:64]}.", dir=target.parent))
        except OSError as exc:
            raise os_error(exc, target) from None
        os.chmod(folder, 0o777 & ~_umask())  # mkdtemp makes 0700; an output gets the user's usual mode
        return folder


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


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


# ---- PNGs -----------------------------------------------------------------------------------
def to_image(rgba_gl: np.ndarray) -> Image.Image:
    return Image.fromarray(np.ascontiguousarray(rgba_gl[::-1]))


def atomic_write(
    path: str | Path, write: Callable[[str], object], *, overwrite: bool = True, final: bool = False
) -> Path:
    """Let `write(tmp)` fill a temporary file beside `path`, then move it into place: an old
    file stays whole until the new one is complete. With overwrite=False an existing file is
    a FileExistsError, checked atomically (hard link), so a file that appears meanwhile is
    never replaced either. A file the user made read-only is not replaced, and other OS
    errors (read-only or full file system, permissions) are an RttaError naming `path`; the
    temporary is removed in every case, signals included (see rtta.outputs)."""
    path = Path(path)
    if not overwrite and path.exists():
        raise FileExistsError(path)
    staged: list[str] = []
    try:
        _stage(path, write, staged)
        with committing(final):
            try:
                if overwrite:
                    os.replace(staged[0], path)
                else:
                    os.link(staged[0], path)
            except FileExistsError:
                raise
            except OSError as exc:
                raise os_error(exc, path) from None
    finally:
        _unlink(staged)
    return path


def atomic_write_all(outputs: list[tuple[str | Path, Callable[[str], object]]], *, final: bool = False) -> list[Path]:
    """atomic_write for files that belong together (snapshot's PNGs and its --save-view):
    every temporary is filled first, then all are renamed into place while signals wait, so a
    failure (a full disk) leaves no new file and every old one whole."""
    paths = [Path(path) for path, _ in outputs]
    staged: list[str] = []
    try:
        for path, (_, write) in zip(paths, outputs, strict=True):
            _stage(path, write, staged)
        with committing(final):
            for path, tmp in zip(paths, staged, strict=True):
                try:
                    os.replace(tmp, path)
                except OSError as exc:
                    raise os_error(exc, path) from None
    finally:
        _unlink(staged)
    return paths


def _stage(path: Path, write: Callable[[str], object], staged: list[str]) -> None:
    """A temporary file beside `path` (added to `staged`, which the caller removes) that
    `write(tmp)` fills."""
    if path.is_file() and not os.access(path, os.W_OK):
        raise RttaError("is read-only; it will not be replaced", path)
    with quiet_signals():
        try:
            fd, tmp = tempfile.mkstemp(prefix=f".{path.name[:64]}.", suffix=path.suffix[:16], dir=path.parent)
        except OSError as exc:
            raise os_error(exc, path) from None
        os.close(fd)
        staged.append(tmp)
    try:
        os.chmod(tmp, 0o666 & ~_umask())  # mkstemp makes 0600; a saved file gets the user's usual mode
        write(tmp)
    except OSError as exc:
        raise os_error(exc, path) from None


def _unlink(temporaries: list[str]) -> None:
    with quiet_signals():
        for tmp in temporaries:
            Path(tmp).unlink(missing_ok=True)


def write_text(path: str | Path, text: str) -> Path:
    """`text` into `path` (UTF-8), atomically (see atomic_write)."""
    return atomic_write(path, lambda tmp: Path(tmp).write_text(text, encoding="utf-8"))


def save_png(path: str | Path, rgba_gl: np.ndarray, *, overwrite: bool = True, final: bool = False) -> Path:
    """Write a GL-convention array as PNG, atomically (see atomic_write)."""
    return atomic_write(path, lambda tmp: to_image(rgba_gl).save(tmp, format="PNG"), overwrite=overwrite, final=final)
