"""The few raw OpenGL calls moderngl does not expose: depth texture arrays,
per-attachment clears and clip-distance enables.

moderngl can attach 2D texture arrays to a framebuffer but cannot create a depth
texture array, which layered rendering needs (every attachment must be layered).
"""

from __future__ import annotations

import ctypes
import ctypes.util
from functools import lru_cache

import numpy as np

GL_FRAMEBUFFER = 0x8D40
GL_DEPTH_ATTACHMENT = 0x8D00
GL_TEXTURE_2D_ARRAY = 0x8C1A
GL_DEPTH_COMPONENT = 0x1902
GL_DEPTH_COMPONENT32F = 0x8CAC
GL_FLOAT = 0x1406
GL_COLOR = 0x1800
GL_DEPTH = 0x1801
GL_TEXTURE_MIN_FILTER = 0x2801
GL_TEXTURE_MAG_FILTER = 0x2800
GL_NEAREST = 0x2600
GL_CLIP_DISTANCE0 = 0x3000
GL_PACK_ALIGNMENT = 0x0D05


@lru_cache(maxsize=1)
def _lib() -> ctypes.CDLL:
    """libOpenGL (GLVND) dispatches core entry points to the current context (EGL or GLX)."""
    for name in ("libOpenGL.so.0", "libGL.so.1", ctypes.util.find_library("GL") or ""):
        if not name:
            continue
        try:
            lib = ctypes.CDLL(name)
            lib.glGetError.restype = ctypes.c_uint
            return lib
        except OSError:
            continue
    raise OSError("no OpenGL library (libOpenGL.so.0 or libGL.so.1) found")


class DepthArray:
    """A GL_DEPTH_COMPONENT32F 2D texture array (immutable storage); with `stencil`
    GL_DEPTH32F_STENCIL8 (section caps mark their texels in the stencil)."""

    def __init__(self, width: int, height: int, layers: int, stencil: bool = False) -> None:
        self.stencil = stencil
        gl = _lib()
        tex = ctypes.c_uint(0)
        gl.glGenTextures(1, ctypes.byref(tex))
        self.glo = tex.value
        self.size = (width, height, layers)
        gl.glBindTexture(GL_TEXTURE_2D_ARRAY, self.glo)
        gl.glTexStorage3D(GL_TEXTURE_2D_ARRAY, 1, 0x8CAD if stencil else GL_DEPTH_COMPONENT32F, width, height, layers)
        gl.glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MIN_FILTER, GL_NEAREST)
        gl.glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAG_FILTER, GL_NEAREST)
        gl.glBindTexture(GL_TEXTURE_2D_ARRAY, 0)

    def attach_to_bound_framebuffer(self) -> None:
        """Attach as the layered depth attachment of the currently bound framebuffer."""
        point = 0x821A if self.stencil else GL_DEPTH_ATTACHMENT  # GL_DEPTH_STENCIL_ATTACHMENT
        _lib().glFramebufferTexture(GL_FRAMEBUFFER, point, self.glo, 0)

    def read(self) -> np.ndarray:
        """All layers as float32 [layers, height, width]; row 0 is the bottom row."""
        w, h, n = self.size
        out = np.empty((n, h, w), np.float32)
        gl = _lib()
        gl.glPixelStorei(GL_PACK_ALIGNMENT, 4)
        gl.glBindTexture(GL_TEXTURE_2D_ARRAY, self.glo)
        gl.glGetTexImage(GL_TEXTURE_2D_ARRAY, 0, GL_DEPTH_COMPONENT, GL_FLOAT, out.ctypes.data_as(ctypes.c_void_p))
        gl.glBindTexture(GL_TEXTURE_2D_ARRAY, 0)
        return out

    def release(self) -> None:
        if self.glo:
            tex = ctypes.c_uint(self.glo)
            _lib().glDeleteTextures(1, ctypes.byref(tex))
            self.glo = 0


GL_RED_INTEGER = 0x8D94
GL_INT = 0x1404


def read_texels(glo: int, points: np.ndarray, depth: bool) -> np.ndarray:
    """The texels of a 2D texture array at `points` [k, 3] (x, y, layer), one
    glGetTextureSubImage (GL 4.5) each: float32 depths, or int32 values of a one-channel
    integer texture. Picking reads a few texels instead of every layer of the atlas."""
    gl = _lib()
    out = np.empty(len(points), np.float32 if depth else np.int32)
    fmt, kind = (GL_DEPTH_COMPONENT, GL_FLOAT) if depth else (GL_RED_INTEGER, GL_INT)
    base = out.ctypes.data
    gl.glPixelStorei(GL_PACK_ALIGNMENT, 4)
    for k, (x, y, layer) in enumerate(np.asarray(points, np.int64).tolist()):
        gl.glGetTextureSubImage(glo, 0, x, y, layer, 1, 1, 1, fmt, kind, 4, ctypes.c_void_p(base + 4 * k))
    return out


def flush_commands() -> None:
    """glFlush: the commands queued so far handed to the GPU (sync.kick)."""
    _lib().glFlush()


def clear_depth(value: float = 1.0) -> None:
    """Clear the depth attachment of the bound framebuffer (all layers)."""
    _lib().glClearBufferfv(GL_DEPTH, 0, (ctypes.c_float * 1)(value))


def clear_color_float(draw_buffer: int, rgba: tuple[float, float, float, float]) -> None:
    _lib().glClearBufferfv(GL_COLOR, draw_buffer, (ctypes.c_float * 4)(*rgba))


def clear_color_int(draw_buffer: int, value: int) -> None:
    _lib().glClearBufferiv(GL_COLOR, draw_buffer, (ctypes.c_int * 4)(value, value, value, value))


def set_clip_distances(count: int, enabled: bool) -> None:
    gl = _lib()
    for i in range(count):
        (gl.glEnable if enabled else gl.glDisable)(GL_CLIP_DISTANCE0 + i)


GL_TEXTURE0 = 0x84C0


def bind_texture_array(unit: int, glo: int) -> None:
    """Bind a raw 2D texture array (e.g. a DepthArray) to a texture unit for sampling."""
    gl = _lib()
    gl.glActiveTexture(GL_TEXTURE0 + unit)
    gl.glBindTexture(GL_TEXTURE_2D_ARRAY, glo)
    gl.glActiveTexture(GL_TEXTURE0)


GL_BACK = 0x0405
GL_RGBA = 0x1908
GL_UNSIGNED_BYTE = 0x1401
GL_READ_FRAMEBUFFER = 0x8CA8


GL_SYNC_GPU_COMMANDS_COMPLETE = 0x9117
GL_SYNC_FLUSH_COMMANDS_BIT = 0x1
GL_TIMEOUT_EXPIRED = 0x911B
WAIT_STEP_NS = 100_000_000


class Throttle:
    """Flush, keeping at most one flushed batch of commands in flight: before a batch is
    handed over, the one before it must be done. llvmpipe gives every batch in flight a
    "scene" of its own, allocates scenes on demand and keeps them; a scene keeps the
    framebuffer it drew last (and so its textures, after they were deleted) until it is
    used again. A loop that never waits (headless, no swap) piled up many scenes, and the
    memory of as many old atlases (docs/reliability.md, Soak). Waiting for the batch before
    costs nothing on a GPU that keeps up, and on llvmpipe keeps Python one batch ahead."""

    def __init__(self) -> None:
        self._fence = None

    def flush(self) -> None:
        gl = _lib()
        self.wait()
        gl.glFenceSync.restype = ctypes.c_void_p
        self._fence = gl.glFenceSync(ctypes.c_uint(GL_SYNC_GPU_COMMANDS_COMPLETE), ctypes.c_uint(0))
        gl.glFlush()

    def wait(self) -> None:
        """Until the last flushed batch is done (anything but a timeout, a failed wait too,
        ends it: it gives up rather than hangs)."""
        if not self._fence:
            return
        gl = _lib()
        gl.glClientWaitSync.restype = ctypes.c_uint
        fence = ctypes.c_void_p(self._fence)
        while (
            gl.glClientWaitSync(fence, ctypes.c_uint(GL_SYNC_FLUSH_COMMANDS_BIT), ctypes.c_uint64(WAIT_STEP_NS))
            == GL_TIMEOUT_EXPIRED
        ):
            pass
        self.release()

    def release(self) -> None:
        if self._fence:
            _lib().glDeleteSync(ctypes.c_void_p(self._fence))
            self._fence = None


def read_window(width: int, height: int) -> np.ndarray:
    """The default framebuffer's back buffer as RGBA8 [H, W, 4], row 0 at the bottom.
    moderngl reads the default framebuffer through GL_COLOR_ATTACHMENT0, an error there."""
    gl = _lib()
    out = np.empty((height, width, 4), np.uint8)
    gl.glBindFramebuffer(GL_READ_FRAMEBUFFER, 0)
    gl.glReadBuffer(GL_BACK)
    gl.glPixelStorei(GL_PACK_ALIGNMENT, 1)
    gl.glReadPixels(0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE, out.ctypes.data_as(ctypes.c_void_p))
    return out


GL_ANY_SAMPLES_PASSED = 0x8C2F
GL_QUERY_RESULT = 0x8866


class SamplesQuery:
    """An occlusion query (GL_ANY_SAMPLES_PASSED) that can be released (moderngl's cannot)."""

    def __init__(self) -> None:
        q = ctypes.c_uint(0)
        _lib().glGenQueries(1, ctypes.byref(q))
        self.glo = q.value

    def __enter__(self) -> SamplesQuery:
        _lib().glBeginQuery(GL_ANY_SAMPLES_PASSED, self.glo)
        return self

    def __exit__(self, *exc) -> None:
        _lib().glEndQuery(GL_ANY_SAMPLES_PASSED)

    @property
    def any_samples(self) -> bool:
        result = ctypes.c_uint(0)
        _lib().glGetQueryObjectuiv(self.glo, GL_QUERY_RESULT, ctypes.byref(result))
        return result.value != 0

    def release(self) -> None:
        if self.glo:
            _lib().glDeleteQueries(1, ctypes.byref(ctypes.c_uint(self.glo)))
            self.glo = 0


GL_TEXTURE_BUFFER = 0x8C2A
GL_RGB32F = 0x8815
GL_MAP_WRITE_BIT = 0x0002
GL_MAP_INVALIDATE_BUFFER_BIT = 0x0008


class BufferTexture:
    """An RGB32F buffer texture (samplerBuffer) over a buffer, and writing that buffer in
    place through a mapping: numpy casts straight into the driver's memory, one copy fewer
    than a texture upload (moderngl has neither)."""

    def __init__(self, buffer_glo: int) -> None:
        gl = _lib()
        tex = ctypes.c_uint(0)
        gl.glGenTextures(1, ctypes.byref(tex))
        self.glo = tex.value
        self.buffer_glo = buffer_glo
        gl.glBindTexture(GL_TEXTURE_BUFFER, self.glo)
        gl.glTexBuffer(GL_TEXTURE_BUFFER, GL_RGB32F, buffer_glo)
        gl.glBindTexture(GL_TEXTURE_BUFFER, 0)

    def write_points(self, points: np.ndarray, count: int) -> None:
        """Points [n, 3] (any float type) as float32 into the first `count` texels, zeros after."""
        gl = _lib()
        gl.glMapNamedBufferRange.restype = ctypes.c_void_p
        nbytes = count * 12
        ptr = gl.glMapNamedBufferRange(
            ctypes.c_uint(self.buffer_glo),
            ctypes.c_ssize_t(0),
            ctypes.c_ssize_t(nbytes),
            ctypes.c_uint(GL_MAP_WRITE_BIT | GL_MAP_INVALIDATE_BUFFER_BIT),
        )
        if not ptr:
            raise RuntimeError("glMapNamedBufferRange failed")
        try:
            view = np.ctypeslib.as_array((ctypes.c_float * (count * 3)).from_address(ptr)).reshape(count, 3)
            n = len(points)
            view[:n] = points
            view[n:] = 0.0
        finally:
            gl.glUnmapNamedBuffer(ctypes.c_uint(self.buffer_glo))

    def use(self, unit: int) -> None:
        gl = _lib()
        gl.glActiveTexture(GL_TEXTURE0 + unit)
        gl.glBindTexture(GL_TEXTURE_BUFFER, self.glo)
        gl.glActiveTexture(GL_TEXTURE0)

    def release(self) -> None:
        if self.glo:
            _lib().glDeleteTextures(1, ctypes.byref(ctypes.c_uint(self.glo)))
            self.glo = 0


GL_RENDERBUFFER = 0x8D41
GL_DEPTH32F_STENCIL8 = 0x8CAD
GL_DEPTH_STENCIL_ATTACHMENT = 0x821A
GL_DEPTH_STENCIL = 0x84F9
GL_STENCIL_TEST = 0x0B90
GL_ALWAYS = 0x0207
GL_LESS = 0x0201
GL_KEEP = 0x1E00
GL_REPLACE = 0x1E01
GL_INCR = 0x1E02


GL_STENCIL_INDEX8 = 0x8D48
GL_STENCIL_ATTACHMENT = 0x8D20
GL_STENCIL = 0x1802


class DepthStencil:
    """A GL_DEPTH32F_STENCIL8 renderbuffer, or with `stencil_only` a GL_STENCIL_INDEX8 one:
    moderngl makes no attachment with a stencil."""

    def __init__(self, width: int, height: int, stencil_only: bool = False) -> None:
        gl = _lib()
        rb = ctypes.c_uint(0)
        gl.glGenRenderbuffers(1, ctypes.byref(rb))
        self.glo, self.size = rb.value, (width, height)
        self.stencil_only = stencil_only
        gl.glBindRenderbuffer(GL_RENDERBUFFER, self.glo)
        gl.glRenderbufferStorage(
            GL_RENDERBUFFER, GL_STENCIL_INDEX8 if stencil_only else GL_DEPTH32F_STENCIL8, width, height
        )
        gl.glBindRenderbuffer(GL_RENDERBUFFER, 0)

    @property
    def nbytes(self) -> int:
        return (1 if self.stencil_only else 8) * self.size[0] * self.size[1]

    def attach_to_bound_framebuffer(self) -> None:
        point = GL_STENCIL_ATTACHMENT if self.stencil_only else GL_DEPTH_STENCIL_ATTACHMENT
        _lib().glFramebufferRenderbuffer(GL_FRAMEBUFFER, point, GL_RENDERBUFFER, self.glo)

    def release(self) -> None:
        if self.glo:
            _lib().glDeleteRenderbuffers(1, ctypes.byref(ctypes.c_uint(self.glo)))
            self.glo = 0


def clear_depth_stencil(depth: float = 1.0, stencil: int = 0) -> None:
    """Clear depth and stencil of the bound framebuffer."""
    _lib().glClearBufferfi(GL_DEPTH_STENCIL, 0, ctypes.c_float(depth), ctypes.c_int(stencil))


def clear_stencil(value: int = 0) -> None:
    """Clear the stencil of the bound framebuffer."""
    _lib().glClearBufferiv(GL_STENCIL, 0, (ctypes.c_int * 1)(value))


def stencil_count_surfaces() -> None:
    """Stencil test on, always passing: each fragment that passes the depth test adds 1 to its
    pixel's stencil (saturating at 255), one that fails sets it to 255."""
    gl = _lib()
    gl.glEnable(GL_STENCIL_TEST)
    gl.glStencilMask(0xFF)
    gl.glStencilFunc(GL_ALWAYS, 255, 0xFF)
    gl.glStencilOp(GL_KEEP, GL_REPLACE, GL_INCR)


def stencil_above(value: int) -> None:
    """Stencil test on: only where the stencil holds more than `value`, which stays."""
    gl = _lib()
    gl.glEnable(GL_STENCIL_TEST)
    gl.glStencilFunc(GL_LESS, value, 0xFF)
    gl.glStencilOp(GL_KEEP, GL_KEEP, GL_KEEP)


def stencil_from_shader() -> None:
    """Stencil test on, always passing: each fragment writes the stencil its shader exports
    (gl_FragStencilRefARB)."""
    gl = _lib()
    gl.glEnable(GL_STENCIL_TEST)
    gl.glStencilMask(0xFF)
    gl.glStencilFunc(GL_ALWAYS, 0, 0xFF)
    gl.glStencilOp(GL_KEEP, GL_KEEP, GL_REPLACE)


def stencil_off() -> None:
    _lib().glDisable(GL_STENCIL_TEST)
