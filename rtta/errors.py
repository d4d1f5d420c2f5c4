"""User-facing errors: one line, naming the file and the problem; and text made safe to print."""

from __future__ import annotations

import unicodedata
from pathlib import Path

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
