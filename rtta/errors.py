"""User-facing errors: one line, naming the file and the problem; and text made safe to print."""

from __future__ import annotations

import re
import unicodedata
from enum import StrEnum
from pathlib import Path
from typing import TypeVar

E = TypeVar("E", bound=StrEnum)

_ESCAPED = {"\n": "\\n", "\r": "\\r", "\t": "\\t"}


class RttaError(Exception):
    """An expected failure: bad input, an unwritable output, an unsupported context.

    The CLI prints it as one line, ``rtta: error: <file>: <reason>``, and exits with code 2;
    the library raises it with the same message.

    Parameters
    ----------
    message : str
        What is wrong, as one line.
    path : str or Path, optional
        The file it is about; it leads the message.

    Examples
    --------
    >>> import rtta
    >>> str(rtta.RttaError("truncated", "part.glb"))
    'part.glb: truncated'
    """

    def __init__(self, message: str, path: str | Path | None = None) -> None:
        self.path = None if path is None else str(path)
        self.message = message
        super().__init__(f"{self.path}: {message}" if self.path else message)


def member(kind: type[E], value: object) -> E | None:
    """The member of the option enum `kind` that `value` (a member or its string) names, else
    None, for the caller's own error: a dict lookup, where `kind(value)` takes three Python calls
    and raises (options are looked up every frame; issue 43 counts a frame's calls)."""
    return kind._value2member_map_.get(value) if isinstance(value, str) else None  # type: ignore[return-value]


def printable(text: object) -> str:
    """`text` as one line that cannot act on a terminal: control and format characters,
    line and paragraph separators (and bytes that were not UTF-8 in a file name) are
    written as escapes (ESC -> \\x1b, newline -> \\n); everything else is kept."""
    text = str(text)
    if text.isprintable():
        return text
    out = []
    for ch in text:
        o = ord(ch)
        if ch in _ESCAPED:
            out.append(_ESCAPED[ch])
        elif 0xDC80 <= o <= 0xDCFF:  # os.fsdecode's stand-in for a non-UTF-8 byte
            out.append(f"\\x{o - 0xDC00:02x}")
        elif unicodedata.category(ch) in ("Cc", "Cf", "Cs", "Co", "Zl", "Zp"):
            out.append(f"\\x{o:02x}" if o < 0x100 else f"\\u{o:04x}" if o < 0x10000 else f"\\U{o:08x}")
        else:
            out.append(ch)
    return "".join(out)


_PLAIN = (  # an exception's kind (or a base's) -> what happened, in the user's terms
    ("MemoryError", "out of memory"),
    ("RecursionError", "nested too deeply"),
    ("UnicodeError", "text that is not valid in its encoding"),
    ("EOFError", "it ends too early"),
    ("ArithmeticError", "a number out of range"),
    ("LinAlgError", "a transform that cannot be inverted"),
)
_INTERNAL = ("AttributeError", "TypeError", "NameError", "LookupError", "AssertionError", "StopIteration")


def reason(exc: BaseException, limit: int = 160) -> str:
    """Why a library failed, for a message in parentheses: the first line of its own text
    where that speaks of the input, else what its kind of failure means in the user's terms;
    never the exception's class, nor Python's own wording (`'NoneType' object has no attribute
    'x'`, `list index out of range`) from a library's bug.

    Parameters
    ----------
    exc : BaseException
        What the library raised.
    limit : int
        Characters kept of its text.

    Returns
    -------
    str
        One line.
    """
    kinds = [kind.__name__ for kind in type(exc).__mro__]
    if isinstance(exc, OSError) and exc.strerror:
        return exc.strerror
    if type(exc).__module__ == "zlib":  # zlib.error: 'Error -3 while decompressing data: ...'
        return "compressed data that is damaged"
    plain = next((text for name, text in _PLAIN if name in kinds), None)
    if plain is not None:
        return plain
    if isinstance(exc, KeyError) and exc.args and isinstance(exc.args[0], str) and " " in exc.args[0].strip():
        return exc.args[0].strip().splitlines()[0][:limit]  # KeyError('no such entity #42'): a message, not a key
    if any(name in kinds for name in _INTERNAL):
        return "data of a form the reader does not expect"
    try:
        lines = str(exc).strip().splitlines()
    except Exception:  # a __str__ that fails (usd-core's, on bytes that are not UTF-8)
        lines = []
    line = re.sub(r"\s*<[^<>]* at 0x[0-9a-fA-F]+>", "", lines[0]).strip() if lines else ""  # an object's repr
    return line[:limit] or ("a system error" if isinstance(exc, OSError) else "a failure the library does not describe")
