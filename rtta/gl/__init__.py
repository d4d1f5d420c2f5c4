"""GL layer: OpenGL plumbing, knowing nothing of passes or compositing.

The headless context and its capabilities, raw GL calls moderngl does not wrap (`glraw`),
the one shader loader (`glsl`, over the files in `rtta.shaders`), layered render targets,
the scene's and records' GPU buffers (`GpuScene`) and reading images back into viewport
space. Imports the atlas and scene layers only.
"""

from .context import Capabilities, create_headless_context
from .gpu import GpuScene
from .targets import LayeredTarget

__all__ = ["Capabilities", "GpuScene", "LayeredTarget", "create_headless_context"]
