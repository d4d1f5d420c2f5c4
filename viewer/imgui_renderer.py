"""moderngl-window's imgui renderer with vertex and index buffers that grow to fit.

moderngl-window 3.1 allocates both buffers once, for 65,536 vertices and indices, and
writes each draw list into them whole: a panel or an overlay with more (a long object list,
outlines of thousands of atlas regions) makes `Buffer.write` raise "out of range". Here each
buffer is reallocated (to the next power of two) before a draw list that does not fit, and
the vertex array is rebuilt on the new buffers. imgui-bundle < 1.92 (pinned) uses 32-bit
indices, so one draw list never needs a vertex offset.

Mouse events go through imgui's input queue (`add_mouse_*_event`) instead of setting
`io.mouse_down` directly: a press and its release that arrive before the same frame (a tap,
`xdotool click`) were one state overwritten by the next, so the panel never saw the click;
queued, imgui trickles them over two frames and the widget gets its click.
"""

from __future__ import annotations

from imgui_bundle import imgui
from moderngl_window.integrations.imgui_bundle import ModernglWindowRenderer

INITIAL_ELEMENTS = 65536


def _capacity(needed: int) -> int:
    """The next power of two at or above `needed` (at least INITIAL_ELEMENTS)."""
    return max(INITIAL_ELEMENTS, 1 << max(0, int(needed) - 1).bit_length())


class GrowingImguiRenderer(ModernglWindowRenderer):
    """ModernglWindowRenderer whose buffers grow to the largest draw list seen."""

    def _create_device_objects(self) -> None:
        super()._create_device_objects()
        self.vertex_capacity = self.index_capacity = INITIAL_ELEMENTS

    def reserve(self, vertices: int, indices: int) -> None:
        """Make room for a draw list of `vertices` vertices and `indices` indices."""
        if vertices <= self.vertex_capacity and indices <= self.index_capacity:
            return
        self.vertex_capacity = max(self.vertex_capacity, _capacity(vertices))
        self.index_capacity = max(self.index_capacity, _capacity(indices))
        for old in (self._vao, self._vertex_buffer, self._index_buffer):
            old.release()
        self._vertex_buffer = self.ctx.buffer(reserve=imgui.VERTEX_SIZE * self.vertex_capacity)
        self._index_buffer = self.ctx.buffer(reserve=imgui.INDEX_SIZE * self.index_capacity)
        self._vao = self.ctx.vertex_array(
            self._prog,
            [(self._vertex_buffer, "2f 2f 4f1", "Position", "UV", "Color")],
            index_buffer=self._index_buffer,
            index_element_size=imgui.INDEX_SIZE,
        )

    def _buttons(self, button) -> list[int]:
        m = self.wnd.mouse
        return [k for k, b in enumerate((m.left, m.right, m.middle)) if button == b]

    def mouse_position_event(self, x, y, dx, dy) -> None:
        self.io.add_mouse_pos_event(*self._mouse_pos_viewport(x, y))

    def mouse_drag_event(self, x, y, dx, dy) -> None:
        self.io.add_mouse_pos_event(*self._mouse_pos_viewport(x, y))

    def mouse_press_event(self, x, y, button) -> None:
        self.io.add_mouse_pos_event(*self._mouse_pos_viewport(x, y))
        for k in self._buttons(button):
            self.io.add_mouse_button_event(k, True)

    def mouse_release_event(self, x, y, button) -> None:
        self.io.add_mouse_pos_event(*self._mouse_pos_viewport(x, y))
        for k in self._buttons(button):
            self.io.add_mouse_button_event(k, False)

    def mouse_scroll_event(self, x_offset, y_offset) -> None:
        self.io.add_mouse_wheel_event(float(x_offset), float(y_offset))

    def render(self, draw_data: imgui.ImDrawData) -> None:
        io = self.io
        fb_w = int(io.display_size[0] * io.display_framebuffer_scale[0])
        fb_h = int(io.display_size[1] * io.display_framebuffer_scale[1])
        if fb_w == 0 or fb_h == 0:
            return
        for commands in draw_data.cmd_lists:
            self.reserve(commands.vtx_buffer.size(), commands.idx_buffer.size())
        super().render(draw_data)
