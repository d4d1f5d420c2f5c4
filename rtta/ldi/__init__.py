"""Layered depth images: depth peeling of closed meshes, viewpoint selection and cropping,
compression, the GPU point-in-mesh parity test, and the lens built on them (a sphere or box
that cuts the context away in the ghosted modes). Imports the passes layer and below.
"""

from .lens import Lens, LensPass
from .peel import LayeredDepthImage, build

__all__ = ["LayeredDepthImage", "Lens", "LensPass", "build"]
