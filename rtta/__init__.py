"""rtta: render-to-texture-atlas for ghosted views of multi-part 3D models.

Every frame, each object's projected bounds are packed into a layered atlas (Algorithm 1)
and the whole batched scene is drawn in one pass, displaced into the atlas regions, so
every object is available unoccluded (colour, depth, normal, id).

Two ways in: `snapshot` (a mode rendered to an RGBA array) and `capture` (every object's
amodal images as arrays, a `Capture`) in one call each, with a headless context made once
and reused; or a `Renderer` on a moderngl context of your own, for control over frames.
"""

from .atlas.parameterize import Records, parameterize
from .errors import RttaError
from .gl.context import Capabilities, create_headless_context
from .passes.capture import CapturePass
from .passes.composite import Style
from .passes.direct import RttPass, StdPass
from .renderer.api import Capture, capture, snapshot
from .renderer.pick import Pick, pick
from .renderer.renderer import Renderer, Settings
from .scene.camera import Camera
from .scene.loader import load_scene
from .scene.model import Scene, from_meshes

__all__ = [
    # one call each (notebooks, scripts)
    "snapshot",
    "capture",
    "Capture",
    "pick",
    "Pick",
    # the renderer and what it takes and gives
    "Camera",
    "Capabilities",
    "CapturePass",
    "Records",
    "Renderer",
    "RttPass",
    "RttaError",
    "Scene",
    "Settings",
    "StdPass",
    "Style",
    "create_headless_context",
    "from_meshes",
    "load_scene",
    "parameterize",
]
__version__ = "0.1.0"
