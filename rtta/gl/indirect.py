"""Indirect draws whose command count the GPU writes (GL_ARB_indirect_parameters, core in
GL 4.6): the capture's draw lists (rtta.passes.draw_lists) drawn without the CPU reading them.
moderngl has no such call; the entry point is looked up through EGL or GLX."""

from __future__ import annotations

import ctypes

from .glraw import _lib

GL_TRIANGLES = 0x0004
GL_UNSIGNED_INT = 0x1405
GL_DRAW_INDIRECT_BUFFER = 0x8F3F
GL_PARAMETER_BUFFER = 0x80EE  # GL 4.6, ARB_indirect_parameters
COMMAND_BYTES = 20  # DrawElementsIndirectCommand: count, instances, first index, base vertex, base instance
_COUNT_DRAW = ctypes.CFUNCTYPE(
    None, ctypes.c_uint, ctypes.c_uint, ctypes.c_void_p, ctypes.c_ssize_t, ctypes.c_int, ctypes.c_int
)


def proc_address(name: str) -> int | None:
    """The address of a GL entry point for the current context, through EGL where an EGL
    context is current (the headless one), else GLX (a window's); None where neither has it."""
    for library, getter, current in (
        ("libEGL.so.1", "eglGetProcAddress", "eglGetCurrentContext"),
        ("libGLX.so.0", "glXGetProcAddressARB", "glXGetCurrentContext"),
    ):
        try:
            lib = ctypes.CDLL(library)
        except OSError:
            continue
        getattr(lib, current).restype = ctypes.c_void_p
        if not getattr(lib, current)():
            continue
        get = getattr(lib, getter)
        get.restype, get.argtypes = ctypes.c_void_p, [ctypes.c_char_p]
        return get(name.encode()) or None
    return None


class IndirectCountDraw:
    """glMultiDrawElementsIndirectCount (GL 4.6; glMultiDrawElementsIndirectCountARB of
    GL_ARB_indirect_parameters): indexed triangles from a command buffer, as many commands as a
    count the GPU wrote into a parameter buffer, so the CPU never reads how many there are.

    Parameters
    ----------
    version_code : int
        The context's GL version (moderngl's `ctx.version_code`).
    extensions : set of str
        The context's extensions (`ctx.extensions`).
    """

    def __init__(self, version_code: int, extensions: set[str]) -> None:
        names = (["glMultiDrawElementsIndirectCount"] if version_code >= 460 else []) + (
            ["glMultiDrawElementsIndirectCountARB"] if "GL_ARB_indirect_parameters" in extensions else []
        )
        address = next((a for a in map(proc_address, names) if a), None)
        self._draw = _COUNT_DRAW(address) if address else None

    @property
    def available(self) -> bool:
        return self._draw is not None

    def draw(
        self, program: int, vertex_array: int, commands: int, counts: int, first: int, count_at: int, most: int
    ) -> None:
        """Draw with `program` and `vertex_array` (GL names) the commands from index `first` of
        buffer `commands`, as many as the uint at byte `count_at` of buffer `counts` says (at most
        `most`). Leaves no program, vertex array or indirect buffer bound (moderngl binds its own
        before each of its draws)."""
        assert self._draw is not None, "available() first"
        gl = _lib()
        gl.glUseProgram(program)
        gl.glBindVertexArray(vertex_array)
        gl.glBindBuffer(GL_DRAW_INDIRECT_BUFFER, commands)
        gl.glBindBuffer(GL_PARAMETER_BUFFER, counts)
        try:
            self._draw(GL_TRIANGLES, GL_UNSIGNED_INT, first * COMMAND_BYTES, count_at, most, COMMAND_BYTES)
        finally:
            gl.glBindBuffer(GL_PARAMETER_BUFFER, 0)
            gl.glBindBuffer(GL_DRAW_INDIRECT_BUFFER, 0)
            gl.glBindVertexArray(0)
            gl.glUseProgram(0)
