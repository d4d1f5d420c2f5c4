"""CLI layer: `rtta` (info, snapshot, export, ldi, dataset, bench) — argument parsing, one-line
errors and exit codes over the layers below. The top layer: nothing in rtta imports it
(the viewer reuses its load options).
"""

from .main import main

__all__ = ["main"]
