"""The object panel as the part tree: open/close groups, a group's checkbox highlights its
whole subtree (mixed when part of it is), the name filter, all / none / invert, opacity per
object and group in `transparent`, and per row (right-click) hide, isolate, show all.

Only the rows on screen are emitted (imgui's list clipper over the flattened visible rows),
so a scene of 100,000 objects costs what its visible rows cost, and imgui's fixed-size
vertex buffers never overflow.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from imgui_bundle import imgui

if TYPE_CHECKING:
    from .commands import PanelsHost

LIST_MIN = 160  # the tree's least height; it takes what the panel leaves it above that
SLIDER_W = 64
INDENT = 12.0
MIXED = imgui.internal.ItemFlagsPrivate_.mixed_value.value
SELECTED = imgui.IM_COL32(255, 200, 80, 255)
HIDDEN_TEXT = imgui.ImVec4(0.55, 0.55, 0.58, 1.0)


def button_width(label: str) -> float:
    """The width of a small button and the spacing before it."""
    st = imgui.get_style()
    return imgui.calc_text_size(label).x + 2 * st.frame_padding.x + st.item_spacing.x


def same_line_if(width: float) -> None:
    """Keep on this line when `width` pixels are left on it; else start the next one."""
    imgui.same_line()
    if imgui.get_content_region_avail().x < width - imgui.get_style().item_spacing.x:
        imgui.new_line()


def draw(app: PanelsHost, reserve: float = 0.0) -> None:
    """The tree section; its list takes the panel's height but `reserve` pixels (what the
    sections below it took the last frame), LIST_MIN at least."""
    s = app.state
    if not imgui.collapsing_header("Objects", imgui.TreeNodeFlags_.default_open.value):
        return
    hows = ("all", "none", "invert")
    imgui.set_next_item_width(max(80.0, imgui.get_content_region_avail().x - sum(button_width(h) for h in hows)))
    _, s.filter = imgui.input_text_with_hint("##filter", "filter by name", s.filter)
    controls = {-1: (*imgui.get_item_rect_min(), *imgui.get_item_rect_max())}
    for k, how in enumerate(hows):
        same_line_if(button_width(how))
        if imgui.small_button(how):
            s.select(how)
        controls[-2 - k] = (*imgui.get_item_rect_min(), *imgui.get_item_rect_max())
    _toolbar(app)
    tree = s.tree
    rows = tree.rows(s.filter)
    list_height = max(LIST_MIN, imgui.get_content_region_avail().y - reserve)
    imgui.begin_child("objects", imgui.ImVec2(0, list_height), imgui.ChildFlags_.borders.value)
    app.item_rects.clear()
    app.item_rects.update(controls)  # -1: filter box, -2..-4: all/none/invert (tests click them)
    tree.rects = {}  # rows on screen: node -> checkbox rect (tests click them)
    tree.sliders = {}
    focus, hidden = tree.counts(s.highlighted), tree.counts(s.hidden)
    sizes = tree.last - tree.first
    height = imgui.get_frame_height_with_spacing()
    if s.scroll_to is not None:
        where = np.flatnonzero(rows == s.scroll_to)
        if where.size:
            imgui.set_scroll_y(max(0.0, float(where[0]) * height - list_height / 2))
        s.scroll_to = None
    s.hover = None
    clipper = imgui.ListClipper()
    clipper.begin(len(rows), height)
    while clipper.step():
        for k in range(clipper.display_start, clipper.display_end):
            _row(app, int(rows[k]), focus, hidden, sizes)
    clipper.end()
    imgui.end_child()


def _toolbar(app: PanelsHost) -> None:
    s = app.state
    s.tree.buttons = {}
    for k, (label, act) in enumerate(
        (
            ("hide highlighted", lambda: s.hide(s.highlighted)),
            ("isolate", lambda: s.isolate(s.highlighted)),
            ("show all", s.show_all),
        )
    ):
        if k:
            same_line_if(button_width(label))
        if imgui.small_button(label):
            act()
        s.tree.buttons[label] = (*imgui.get_item_rect_min(), *imgui.get_item_rect_max())  # tests click them
    if s.hidden:
        text = f"{len(s.hidden)} hidden"
        same_line_if(imgui.calc_text_size(text).x + imgui.get_style().item_spacing.x)
        imgui.text_disabled(text)


def _row(app: PanelsHost, node: int, focus: np.ndarray, hidden: np.ndarray, sizes: np.ndarray) -> None:
    s, tree = app.state, app.state.tree
    oid = int(tree.obj[node])
    imgui.push_id(node)
    imgui.set_cursor_pos_x(imgui.get_cursor_pos_x() + INDENT * float(tree.depth[node]))
    if oid < 0:
        is_open = node in tree.open
        if imgui.arrow_button("##open", imgui.Dir.down if is_open else imgui.Dir.right):
            tree.open ^= {node}
        imgui.same_line()
    n, on, off = int(sizes[node]), int(focus[node]), int(hidden[node])
    mixed = 0 < on < n
    if mixed:
        imgui.push_item_flag(MIXED, True)
    label = tree.labels[node] if oid >= 0 else f"{tree.labels[node]}  ({n})"
    if s.mode == "transparent":  # room for the opacity slider on the right
        label = fit_text(label, imgui.get_window_width() - SLIDER_W - 40 - imgui.get_cursor_pos_x())
    if off == n:
        imgui.push_style_color(imgui.Col_.text.value, HIDDEN_TEXT)
    changed, _ = imgui.checkbox(label, n > 0 and on == n)
    if off == n:
        imgui.pop_style_color()
    if mixed:
        imgui.pop_item_flag()
    rect = (*imgui.get_item_rect_min(), *imgui.get_item_rect_max())
    tree.rects[node] = rect
    if oid >= 0:
        app.item_rects[oid] = rect
    if imgui.is_item_hovered():
        s.hover = node
    if oid >= 0 and oid == s.selected:
        lo, hi = imgui.ImVec2(rect[0] - 2, rect[1] - 1), imgui.ImVec2(rect[2] + 2, rect[3] + 1)
        imgui.get_window_draw_list().add_rect(lo, hi, SELECTED)
    if changed:
        s.toggle(oid) if oid >= 0 else s.toggle_group(tree.members(node))
    _menu(app, node, off == n)
    if s.mode == "transparent":
        _opacity(app, node)
    imgui.pop_id()


def _menu(app: PanelsHost, node: int, all_hidden: bool) -> None:
    """Right-click on a row: hide or show it, isolate it, show everything."""
    s = app.state
    if imgui.begin_popup_context_item("row"):
        ids = s.tree.members(node)
        if imgui.menu_item_simple("show" if all_hidden else "hide"):
            s.hide(ids, on=not all_hidden)
        if imgui.menu_item_simple("isolate"):
            s.isolate(ids)
        if imgui.menu_item_simple("show all"):
            s.show_all()
        if imgui.menu_item_simple("frame"):
            app.frame_objects(ids)
        imgui.end_popup()


def _opacity(app: PanelsHost, node: int) -> None:
    s = app.state
    ids = s.tree.members(node)
    imgui.same_line(max(imgui.get_cursor_pos_x(), imgui.get_window_width() - SLIDER_W - 14))
    imgui.set_next_item_width(SLIDER_W)
    current = s.opacity(int(ids[0])) if len(ids) else s.style.default_opacity
    changed, a = imgui.slider_float("##a", current, 0.0, 1.0, "%.2f")
    s.tree.sliders[node] = (*imgui.get_item_rect_min(), *imgui.get_item_rect_max())  # tests drag them
    if changed:
        for oid in ids:
            s.style.opacity[int(oid)] = a


def fit_text(label: str, width: float) -> str:
    """The label, shortened with '...' to fit `width` pixels (the text, not its checkbox)."""
    if imgui.calc_text_size(label).x <= width:
        return label
    text = label
    while len(text) > 1 and imgui.calc_text_size(text + "...").x > width:
        text = text[:-1]
    return text + "..."
