"""Renderer layer: one frame tied together, and what a frame gives back.

`Renderer` owns the GPU scene, the atlas and the passes for one context and runs them in
order (parameterize → capture → post-process → composite), re-running only what changed;
`snapshot` renders modes to RGBA arrays, `export` writes the per-object atlas images and
records, `api` is the one-call interface (`rtta.snapshot`, `rtta.capture`; its option
builders in `options`, shared with the CLI, and `Capture` in `captured`) with its own
headless context. Imports the ldi layer and below.
"""

from .renderer import Renderer, Settings

__all__ = ["Renderer", "Settings"]
