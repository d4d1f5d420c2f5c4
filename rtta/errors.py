"""User-facing errors: one line, naming the file and the problem."""

from __future__ import annotations

from pathlib import Path


class RttaError(Exception):
    """An expected failure (bad input, unsupported context); the CLI prints it and exits 2."""

    def __init__(self, message: str, path: str | Path | None = None) -> None:
        self.path = None if path is None else str(path)
        self.message = message
        super().__init__(f"{self.path}: {message}" if self.path else message)
