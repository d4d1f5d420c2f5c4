"""Context creation and capability checks (the library only ever takes a moderngl.Context)."""

from __future__ import annotations

from dataclasses import dataclass

import moderngl

from .errors import RttaError

LAYER_EXTENSION = "GL_ARB_shader_viewport_layer_array"


def create_headless_context() -> moderngl.Context:
    """A standalone OpenGL 4.3+ core context through EGL (works without a display)."""
    try:
        ctx = moderngl.create_standalone_context(backend="egl", require=430)
    except Exception as exc:
        raise RttaError(f"cannot create an OpenGL 4.3 context through EGL ({exc}); "
                        "install Mesa (libegl1 libgl1-mesa-dri) or a GPU driver") from None
    return ctx


@dataclass(frozen=True)
class Capabilities:
    version: int
    renderer: str
    geometry_shader: bool
    vertex_layer: bool
    max_layers: int
    max_texture: int

    @classmethod
    def of(cls, ctx: moderngl.Context) -> Capabilities:
        if ctx.version_code < 430:
            raise RttaError(f"OpenGL 4.3 is required, the context offers {ctx.version_code // 100}."
                            f"{ctx.version_code // 10 % 10} ({ctx.info['GL_RENDERER']})")
        return cls(version=ctx.version_code, renderer=str(ctx.info["GL_RENDERER"]),
                   geometry_shader=True, vertex_layer=LAYER_EXTENSION in ctx.extensions,
                   max_layers=int(ctx.info["GL_MAX_ARRAY_TEXTURE_LAYERS"]),
                   max_texture=int(ctx.info["GL_MAX_TEXTURE_SIZE"]))

    def capture_path(self, requested: str = "auto") -> str:
        """'vs' where the layer extension exists, else the paper's 'gs' path."""
        if requested == "vs" and not self.vertex_layer:
            raise RttaError(f"capture path 'vs' needs {LAYER_EXTENSION}, which {self.renderer} lacks")
        if requested in ("vs", "gs"):
            return requested
        return "vs" if self.vertex_layer else "gs"
