"""The bytes the live GL objects hold, asked of the driver (issue 42's monkey and soaks).

`reliability.gl_census` counts live objects per kind; a resource that grows (a buffer
orphaned to a larger size, a texture of a larger window) or one the driver keeps after it was
deleted leaves that count as it was. `gl_bytes` sums the storage of every live buffer,
texture (all its levels, layers and samples) and renderbuffer, from the driver's own answers
(GL 4.5 direct-state queries). Beside the process's RSS it tells memory that rtta holds
through GL from memory that the driver or another library holds.
"""

from __future__ import annotations

import ctypes

import moderngl

from ..gl.glraw import _lib
from .reliability import live_names

GL_BUFFER_SIZE = 0x8764
GL_TEXTURE_WIDTH, GL_TEXTURE_HEIGHT, GL_TEXTURE_DEPTH, GL_TEXTURE_SAMPLES = 0x1000, 0x1001, 0x8071, 0x9106
# bits per channel of a texture level (GL_TEXTURE_RED_SIZE ... GL_TEXTURE_STENCIL_SIZE)
TEXTURE_BITS = (0x805C, 0x805D, 0x805E, 0x805F, 0x884A, 0x88F1)
GL_RENDERBUFFER_WIDTH, GL_RENDERBUFFER_HEIGHT, GL_RENDERBUFFER_SAMPLES = 0x8D42, 0x8D43, 0x8CAB
RENDERBUFFER_BITS = (0x8D50, 0x8D51, 0x8D52, 0x8D53, 0x8D54, 0x8D55)  # red, green, blue, alpha, depth, stencil
GL_TEXTURE_TARGET = 0x1006
GL_TEXTURE_CUBE_MAP, GL_TEXTURE_BUFFER = 0x8513, 0x8C2A
MULTISAMPLE = (0x9100, 0x9102)  # GL_TEXTURE_2D_MULTISAMPLE(_ARRAY): one level
MAX_LEVELS = 15  # of a texture of up to 16384 texels a side


def _ints(fn, name: int, pnames, level: int | None = None) -> list[int]:
    out = []
    for pname in pnames:
        value = ctypes.c_int(0)
        args = (ctypes.c_uint(name),) + (() if level is None else (ctypes.c_int(level),))
        fn(*args, ctypes.c_uint(pname), ctypes.byref(value))
        out.append(value.value)
    return out


def _texture_bytes(name: int) -> int:
    """Bytes of a texture's levels (a buffer texture's storage is its buffer's: 0)."""
    gl = _lib()
    target = ctypes.c_int(0)
    gl.glGetTextureParameteriv(ctypes.c_uint(name), ctypes.c_uint(GL_TEXTURE_TARGET), ctypes.byref(target))
    if target.value == GL_TEXTURE_BUFFER:
        return 0
    faces = 6 if target.value == GL_TEXTURE_CUBE_MAP else 1
    total = 0
    for level in range(1 if target.value in MULTISAMPLE else MAX_LEVELS):
        w, h, d, samples = _ints(gl.glGetTextureLevelParameteriv, name, (GL_TEXTURE_WIDTH, GL_TEXTURE_HEIGHT,
                                 GL_TEXTURE_DEPTH, GL_TEXTURE_SAMPLES), level)  # fmt: skip
        if w <= 0:
            break
        bits = sum(_ints(gl.glGetTextureLevelParameteriv, name, TEXTURE_BITS, level))
        total += w * max(h, 1) * max(d, 1) * max(samples, 1) * faces * bits // 8
    return total


def gl_bytes(ctx: moderngl.Context) -> dict[str, int]:
    """Bytes of storage per kind of live GL object in the current context: "buffers",
    "textures" (every level, layer and sample, at the bits per texel the driver reports) and
    "renderbuffers". The queries raise no GL error (the error-checking fixture's state stays).

    Parameters
    ----------
    ctx : moderngl.Context
        The current context (an OpenGL 4.5 one: direct-state queries).

    Returns
    -------
    dict of str to int
        Bytes per kind.

    Examples
    --------
    >>> sum(gl_bytes(ctx).values()) / 2**20  # doctest: +SKIP
    """
    gl = _lib()
    out = {"buffers": 0, "textures": 0, "renderbuffers": 0}
    for name in live_names("buffers"):
        size = ctypes.c_int64(0)
        gl.glGetNamedBufferParameteri64v(ctypes.c_uint(name), ctypes.c_uint(GL_BUFFER_SIZE), ctypes.byref(size))
        out["buffers"] += size.value
    for name in live_names("textures"):
        out["textures"] += _texture_bytes(name)
    for name in live_names("renderbuffers"):
        pnames = (GL_RENDERBUFFER_WIDTH, GL_RENDERBUFFER_HEIGHT, GL_RENDERBUFFER_SAMPLES)
        w, h, samples = _ints(gl.glGetNamedRenderbufferParameteriv, name, pnames)
        bits = sum(_ints(gl.glGetNamedRenderbufferParameteriv, name, RENDERBUFFER_BITS))
        out["renderbuffers"] += w * h * max(samples, 1) * bits // 8
    return out
