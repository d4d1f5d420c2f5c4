"""`Settings`: the atlas settings of a `Renderer`, what a user can choose per frame."""

from __future__ import annotations

import functools
import os
import re
from dataclasses import dataclass
from enum import StrEnum
from typing import Literal

from ..gl.context import CapturePath, CapturePathName
from ..scene.bounds import Bounds, BoundsName


class ParameterizeOn(StrEnum):
    """Where Algorithm 1 runs (Settings.parameterize)."""

    AUTO = "auto"  # the GPU where its compute shaders build, else the CPU (said once)
    CPU = "cpu"  # rtta.atlas.parameterize, numpy: the reference and the fallback
    GPU = "gpu"  # rtta.passes.atlas_gpu, compute shaders: records, draw lists and order on the GPU


ParameterizeName = Literal["auto", "cpu", "gpu"]
PARAMETERIZE_ON: tuple[str, ...] = tuple(p.value for p in ParameterizeOn)
BlendName = Literal["auto", "raster", "compute"]
BLEND_ON: tuple[str, ...] = ("auto", "raster", "compute")
# GPUs with little raster hardware for their compute (NVIDIA's data-centre parts: the H100 has 8
# ROPs), where blending sprites through the raster pipeline is the frame's bottleneck
FEW_ROPS = ("A100", "A800", "H100", "H200", "H800", "H20", "GH200", "B100", "B200", "GB200")
_FEW_ROPS = re.compile(rf"\b({'|'.join(FEW_ROPS)})\b")  # asked every frame (Renderer.composite)


@dataclass
class Settings:
    """The atlas settings of a `Renderer`: what a user can choose per frame.

    Parameters
    ----------
    border : int, default 1
        Empty texels around each region (the `ghosted-ao` filters read neighbours).
    atlas_max : tuple of int, optional
        The largest atlas layer (W, H); None: the viewport plus twice the border.
    max_layers : int, optional
        The most atlas layers; None: the driver's GL_MAX_ARRAY_TEXTURE_LAYERS. Regions are
        scaled down (the scale recorded) rather than dropped when they do not fit.
    capture_path : {"auto", "vs", "gs"}, default "auto"
        "vs" (vertex shader with GL_ARB_shader_viewport_layer_array), "gs" (the paper's
        geometry shader) or "auto" (vs where the driver has it).
    region_scale : float, default 1
        Atlas texels per viewport pixel (below 1 saves fill, above 1 supersamples).
    context_scale : float, default 1
        Of `region_scale`, for objects outside the focus (0.25-1); the focus stays exact.
    bounds : {"aabb", "obb"}, default "aabb"
        B_world: "aabb" (the paper's) or "obb" (the projections of the AABB and of the
        principal-axes box intersected: tighter for long, rotated parts).
    cull_closed : bool, default True
        Cull the back faces of closed parts (`rtta.scene.closure`); the images are the same,
        False draws every object double-sided.
    parameterize : {"auto", "cpu", "gpu"}, default "auto"
        Where Algorithm 1 runs: compute shaders ("gpu": the records, the capture's draw lists
        and compositing's order made on the GPU, so a frame's CPU cost does not grow with the
        number of parts), numpy ("cpu": the reference) or "auto" (the GPU where its shaders
        build; RTTA_PARAMETERIZE=cpu in the environment makes it the CPU). The GPU's shelf
        packing differs from the CPU's, and so does fast navigation's thinning (by classes of
        area, `rtta.atlas.thinning.KeepShare`).
    blend : {"auto", "raster", "compute"}, default "auto"
        How a GPU-driven frame blends in object order (the ghosted context, `transparent` in
        object order): as sprites through the raster pipeline, or in a compute pass
        (`rtta.passes.blend_tiles`; the same pixels within 3/255). "auto": compute on GPUs with
        little raster hardware (NVIDIA's data-centre parts, `FEW_ROPS`), else raster.

    Examples
    --------
    >>> import rtta
    >>> settings = rtta.Settings(border=2, bounds="obb")
    """

    border: int = 1
    atlas_max: tuple[int, int] | None = None
    max_layers: int | None = None
    capture_path: CapturePathName | CapturePath = "auto"
    region_scale: float = 1.0
    context_scale: float = 1.0
    bounds: BoundsName | Bounds = "aabb"
    cull_closed: bool = True
    parameterize: ParameterizeName | ParameterizeOn = "auto"
    blend: BlendName = "auto"


def parameterize_on(parameterize: ParameterizeName | ParameterizeOn) -> str:
    """`Settings.parameterize` as a renderer takes it: "auto" is "cpu" where the environment
    says RTTA_PARAMETERIZE=cpu (a whole program on the reference path: a driver's bug worked
    around, or the test suite run on both paths)."""
    if parameterize == "auto" and os.environ.get("RTTA_PARAMETERIZE", "").strip().lower() == "cpu":
        return "cpu"
    return str(parameterize)


@functools.lru_cache(maxsize=16)
def blend_on(blend: BlendName, renderer: str) -> Literal["raster", "compute"]:
    """`Settings.blend` resolved for the GL_RENDERER string `renderer` (asked every frame:
    cached, a C call where it is known)."""
    if blend == "auto":
        return "compute" if _FEW_ROPS.search(renderer) else "raster"
    return blend
