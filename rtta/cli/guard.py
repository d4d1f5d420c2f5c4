"""How every `rtta` command fails: one line on stderr, never a traceback or a usage block.

`OneLineParser` turns argparse's errors into an RttaError; `run_command` runs a handler with
the signal handlers of rtta.outputs installed and maps every failure to one line and an
exit status (2: bad input or a failure to write; 130: interrupted by SIGINT, SIGTERM or
SIGHUP before the command's output was in place; 1: a reader closed the pipe early). `RTTA_DEBUG=1` lets an unexpected
exception through with its traceback.
"""

from __future__ import annotations

import argparse
import os
import sys
import warnings
from collections.abc import Callable

from .. import outputs
from ..errors import RttaError, printable


class OneLineParser(argparse.ArgumentParser):
    """argparse, whose errors are one RttaError (`rtta: error: argument --fov: ...`) rather than
    a usage block and exit."""

    def error(self, message: str):
        raise RttaError(f"{message} (`{self.prog} --help` lists the options)")


class StdoutError(Exception):
    """Standard output cannot be written (a full disk, /dev/full, an I/O error)."""


class _GuardedStdout:
    """sys.stdout whose write errors (other than a closed pipe) are a StdoutError; with no
    stream (the process started with its standard output closed, `>&-`) every write is one."""

    def __init__(self, stream) -> None:
        self._stream = stream

    def write(self, text: str) -> int:
        if self._stream is None:
            raise StdoutError("it is closed")
        try:
            return self._stream.write(text)
        except BrokenPipeError:
            raise
        except OSError as exc:
            raise StdoutError(exc.strerror or "an input/output error") from None

    def flush(self) -> None:
        if self._stream is None:
            return
        try:
            self._stream.flush()
        except BrokenPipeError:
            raise
        except OSError as exc:
            raise StdoutError(exc.strerror or "an input/output error") from None

    def __getattr__(self, name):  # the rest as the stream has it (fileno, isatty, encoding...)
        if self._stream is None:
            raise AttributeError(name)
        return getattr(self._stream, name)


def hold_closed_streams() -> None:
    """A process started with standard input, output or error closed (`>&-`, `2>&-`): /dev/null
    takes the descriptor, so no file the run opens gets it (a native library printing to fd 1
    would write into it); sys.stdout stays None (writing to it is then a StdoutError, see
    _GuardedStdout) and sys.stderr writes to /dev/null (a failure is told by the exit status)."""
    for fd in (0, 1, 2):
        try:
            os.fstat(fd)
        except OSError:
            try:
                null = os.open(os.devnull, os.O_RDONLY if fd == 0 else os.O_WRONLY)
                if null != fd:
                    os.dup2(null, fd)
                    os.close(null)
            except OSError:
                pass
    if sys.stderr is None:
        sys.stderr = open(os.devnull, "w")  # noqa: SIM115 (for the rest of the process)


def say(kind: str, text: str, path: str | None = None) -> None:
    """`rtta: <kind>: [path: ]text` on stderr, escaped to one line; nothing where stderr is
    closed (print would fall back to stdout) or cannot be written."""
    where = f"{printable(path)}: " if path else ""
    if sys.stderr is None:
        return
    try:
        print(f"rtta: {kind}: {where}{printable(text)}", file=sys.stderr)
    except OSError:  # a full or broken stderr: the exit status still tells
        pass


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """A Python warning raised during a command, as one `rtta: warning: ...` line."""
    say("warning", str(message))


def _silence_stdout() -> None:
    """Point fd 1 at /dev/null so the interpreter's last flush cannot fail again."""
    try:
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
    except (OSError, ValueError, AttributeError):
        pass


def _subject(args: argparse.Namespace | None) -> str | None:
    for name in ("scene", "mesh"):
        value = getattr(args, name, None)
        if isinstance(value, str) and value:
            return value
    return None


def run_command(
    handler: Callable[[argparse.Namespace], int], args: argparse.Namespace, *, process: bool = False
) -> int:
    """Run `handler(args)` under the one-line failure contract (see the module docstring).
    `process`: this is the whole process (the `rtta` command), so once an output has been
    committed the signal handlers stay, and a late signal cannot kill the finished run."""
    old_handlers = outputs.install_signal_handlers()
    real_stdout = sys.stdout
    sys.stdout = _GuardedStdout(real_stdout)
    shown = warnings.showwarning
    warnings.showwarning = _show_warning  # what the library degraded: `rtta: warning: ...`
    try:
        with outputs.signals_held():  # the scene readers' native libraries: a signal must not cut their start
            _import_readers()
        code = handler(args)
        sys.stdout.flush()
        requested = outputs.interrupt_requested()
        if requested:  # a library swallowed it before the output was in place
            raise outputs.Interrupted(requested)
        return code
    except KeyboardInterrupt:  # Interrupted too: the run stops, its temporaries gone
        print("rtta: interrupted", file=sys.stderr)
        return 130
    except Exception as exc:
        if outputs.interrupt_requested() is None:
            return _failed(exc, args)
        print("rtta: interrupted", file=sys.stderr)  # what failed was the work the signal cut short
        return 130
    finally:
        warnings.showwarning = shown
        sys.stdout = real_stdout
        if not (process and outputs.finished()):
            outputs.restore_signal_handlers(old_handlers)


def _import_readers() -> None:
    """Import trimesh (and with it cascadio's OpenCASCADE) while signals are held."""
    try:
        import trimesh  # noqa: F401
    except ImportError:
        pass


def _failed(exc: Exception, args) -> int:
    """One line for an exception a command raised; its exit status."""
    try:
        raise exc
    except RttaError as exc:
        say("error", str(exc))
        return 2
    except BrokenPipeError:  # `rtta info | head`: the reader left; say nothing more
        _silence_stdout()
        return 1
    except StdoutError as exc:
        _silence_stdout()
        say("error", f"cannot write to standard output ({exc})")
        return 2
    except MemoryError:
        say("error", "out of memory (RTTA_MEMORY_LIMIT_MB sets how much a scene may need)", _subject(args))
        return 2
    except OSError as exc:
        say("error", exc.strerror or "the system refused to read or write it", exc.filename or _subject(args))
        return 2
    except Exception as exc:
        if os.environ.get("RTTA_DEBUG"):
            raise
        say("error", unexpected(exc), _subject(args))
        return 2


_PLAIN = {  # an unexpected exception's class (or a base's) -> what happened, in the user's terms
    "RecursionError": "its structure is nested too deeply",
    "OverflowError": "a number in it is too large to compute with",
    "ZeroDivisionError": "a computation on it divided by zero",
    "FloatingPointError": "a computation on it gave no finite number",
    "LinAlgError": "a matrix computation on it failed (a transform that cannot be inverted?)",
    "UnicodeError": "it holds text that is not valid in its encoding",
}


def unexpected(exc: BaseException) -> str:
    """The one line for a failure rtta did not foresee: what happened in the user's terms,
    never the exception's class or Python's own text, and how to see where."""
    names = [kind.__name__ for kind in type(exc).__mro__]
    what = next((_PLAIN[n] for n in names if n in _PLAIN), "rtta met a case it does not handle")
    return f"cannot process this input: {what}; this is a bug in rtta (RTTA_DEBUG=1 shows where)"
