"""rtta: render-to-texture-atlas for ghosted views of multi-part 3D models.

Every frame, each object's projected bounds are packed into a layered atlas (Algorithm 1)
and the whole batched scene is drawn in one pass, displaced into the atlas regions, so
every object is available unoccluded (colour, depth, normal, id).
"""

from .atlas.parameterize import Records, parameterize
from .errors import RttaError
from .gl.context import Capabilities, create_headless_context
from .passes.capture import CapturePass, RttPass, StdPass
from .renderer.renderer import Renderer, Settings
from .scene.camera import Camera
from .scene.loader import load_scene
from .scene.model import Scene, from_meshes

__all__ = [
    "Camera", "Capabilities", "CapturePass", "Records", "Renderer", "RttPass", "RttaError", "Scene",
    "Settings", "StdPass", "create_headless_context", "from_meshes", "load_scene", "parameterize",
]
__version__ = "0.1.0"
