"""Context creation and capability checks (the library only ever takes a moderngl.Context)."""

from __future__ import annotations

import os
from dataclasses import dataclass
from enum import StrEnum
from pathlib import Path
from typing import Literal

import moderngl

from ..errors import RttaError, member

LAYER_EXTENSION = "GL_ARB_shader_viewport_layer_array"
_MESA_CACHE_VARIABLES = ("MESA_SHADER_CACHE_DIR", "MESA_GLSL_CACHE_DIR", "XDG_CACHE_HOME")


class CapturePath(StrEnum):
    """How the capture routes each object to its atlas layer (Settings.capture_path)."""

    AUTO = "auto"  # VS where the driver has LAYER_EXTENSION, else GS
    VS = "vs"  # gl_Layer from the vertex shader (LAYER_EXTENSION)
    GS = "gs"  # the paper's geometry shader


CapturePathName = Literal["auto", "vs", "gs"]
CAPTURE_PATHS: tuple[str, ...] = tuple(p.value for p in CapturePath)


def create_headless_context() -> moderngl.Context:
    """Make a standalone OpenGL 4.3+ core context through EGL; no display is needed.

    Mesa's llvmpipe gives one on any machine; a GPU driver's EGL is used where there is one.

    Returns
    -------
    moderngl.Context
        A new context; `Renderer` takes it.

    Raises
    ------
    RttaError
        The driver offers no OpenGL 4.3 (the message names the version it offers), or EGL is
        missing.

    Examples
    --------
    >>> import rtta
    >>> ctx = rtta.create_headless_context()
    >>> ctx.version_code >= 430
    True
    """
    _quiet_shader_cache()
    try:
        # (moderngl's stubs type every keyword setting as a dict; backend is a string)
        ctx = moderngl.create_standalone_context(backend="egl", require=430)  # pyright: ignore[reportArgumentType]
    except Exception as exc:
        offered = _offered_version()
        if offered:
            raise RttaError(
                f"OpenGL 4.3 is required (storage buffers, layered rendering); this driver offers only {offered}"
            ) from None
        raise RttaError(
            f"cannot create an OpenGL 4.3 context through EGL ({exc}); "
            "install Mesa (libegl1 libgl1-mesa-dri) or a GPU driver"
        ) from None
    return ctx


def _quiet_shader_cache() -> None:
    """Mesa keeps compiled shaders in $MESA_SHADER_CACHE_DIR, else $XDG_CACHE_HOME, else
    ~/.cache (the passwd entry's home), making that folder and its mesa_shader_cache; where it
    cannot, it prints a line of its own on stderr at every start. Its cache is then turned off
    instead, silently, as rtta's scene cache is: a cache is no reason for a message."""
    if any(os.environ.get(k) for k in ("MESA_SHADER_CACHE_DISABLE", "MESA_GLSL_CACHE_DISABLE")):
        return
    base = next((os.environ[k] for k in _MESA_CACHE_VARIABLES if os.environ.get(k)), None)
    if base is None:
        try:
            import pwd

            base = os.path.join(pwd.getpwuid(os.getuid()).pw_dir, ".cache")
        except (ImportError, KeyError, OSError):
            base = os.path.join(os.path.expanduser("~"), ".cache")
    folder = Path(base) / "mesa_shader_cache"
    for _ in range(2):  # Mesa makes the cache folder and the one it lies in, no more
        if folder.exists():
            break
        folder = folder.parent
    if not (folder.is_dir() and os.access(folder, os.W_OK | os.X_OK)):
        os.environ["MESA_SHADER_CACHE_DISABLE"] = "true"


def _offered_version() -> str | None:
    """'3.3 (llvmpipe ...)' for the best context EGL gives without a version demand, or None."""
    try:
        probe = moderngl.create_standalone_context(backend="egl")  # pyright: ignore[reportArgumentType]  (as above)
    except Exception:
        return None
    try:
        code = probe.version_code
        return f"{code // 100}.{code // 10 % 10} ({probe.info['GL_RENDERER']})"
    finally:
        probe.release()


_shared: moderngl.Context | None = None


def shared_context() -> moderngl.Context:
    """One headless context per process, made on first use (contexts are costly and
    creating many leaks driver memory): the CLI and the tests share it."""
    global _shared
    if _shared is None:
        _shared = create_headless_context()
    return _shared


@dataclass(frozen=True)
class Capabilities:
    """What a context's driver offers that rtta needs; `Capabilities.of(ctx)` checks it.

    Attributes
    ----------
    version : int
        The GL version code (430 for 4.3).
    renderer : str
        GL_RENDERER, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)".
    geometry_shader : bool
        Whether the geometry-shader capture path (the paper's) is available.
    vertex_layer : bool
        Whether GL_ARB_shader_viewport_layer_array allows the vertex-shader capture path.
    max_layers : int
        GL_MAX_ARRAY_TEXTURE_LAYERS: the most atlas layers.
    max_texture : int
        GL_MAX_TEXTURE_SIZE: the largest atlas layer side.
    """

    version: int
    renderer: str
    geometry_shader: bool
    vertex_layer: bool
    max_layers: int
    max_texture: int

    @classmethod
    def of(cls, ctx: moderngl.Context) -> Capabilities:
        if ctx.version_code < 430:
            raise RttaError(
                f"OpenGL 4.3 is required, the context offers {ctx.version_code // 100}."
                f"{ctx.version_code // 10 % 10} ({ctx.info['GL_RENDERER']})"
            )
        return cls(
            version=ctx.version_code,
            renderer=str(ctx.info["GL_RENDERER"]),
            geometry_shader=True,
            vertex_layer=LAYER_EXTENSION in ctx.extensions,
            max_layers=int(ctx.info["GL_MAX_ARRAY_TEXTURE_LAYERS"]),
            max_texture=int(ctx.info["GL_MAX_TEXTURE_SIZE"]),
        )

    @property
    def notes(self) -> list[str]:
        """What is missing and which fallback is used instead (empty on a full GL 4.5 driver)."""
        if self.vertex_layer:
            return []
        return [
            f"{LAYER_EXTENSION} is missing on {self.renderer}: capturing through the "
            "geometry-shader path (the paper's) instead"
        ]

    def capture_path(self, requested: CapturePathName | CapturePath = "auto") -> CapturePath:
        """The path `requested`, or for 'auto' 'vs' where the layer extension exists, else the paper's 'gs'."""
        path = member(CapturePath, requested)
        if path is None:
            raise RttaError(f"capture path must be one of {', '.join(CAPTURE_PATHS)}, got {requested!r}")
        if path is CapturePath.VS and not self.vertex_layer:
            raise RttaError(f"capture path 'vs' needs {LAYER_EXTENSION}, which {self.renderer} lacks")
        if path is not CapturePath.AUTO:
            return path
        return CapturePath.VS if self.vertex_layer else CapturePath.GS
