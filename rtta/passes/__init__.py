"""Passes layer: one class per render pass, each with explicit inputs and outputs.

The capture into the atlas (RTTA, through the vertex- or geometry-shader path), the direct
render (STD) and an object rendered alone (RTT); post-processing on atlas texels (AO and
edges); compositing the atlas into sprites, transparency and ghosted views; the projector;
the unbatched and BVH-chunked STD passes for textured scenes; picking from atlas images.
Imports the gl, atlas and scene layers only.
"""

from .capture import CapturePass
from .composite import MODES, CompositePass, CompositeTarget, Style
from .direct import RttPass, StdPass
from .post import AtlasPostPass

__all__ = ["MODES", "AtlasPostPass", "CapturePass", "CompositePass", "CompositeTarget", "RttPass", "StdPass", "Style"]
