"""The viewer's tree panel in the real window under Xvfb (tests/viewer_tree_driver.py):
a group's checkbox highlights its subtree, hide / isolate change the atlas and the
composite, hovering a row outlines its object, a click reveals its row, and framing leaves
a margin on all four sides at composite aspects 0.5, 1 and 2."""

from __future__ import annotations

import os

import numpy as np
import pytest
from test_viewer import _region, display, run_driver  # noqa: F401  (the Xvfb fixture)

BACKGROUND = np.array([0.93, 0.93, 0.95]) * 255


@pytest.fixture(scope="module")
def tree_driven(display, tmp_path_factory):  # noqa: F811
    return run_driver(display, tmp_path_factory.mktemp("tree_viewer"), "viewer_tree_driver.py")


def test_group_checkbox_highlights_its_subtree(tree_driven):
    result, shots = tree_driven
    assert result["rows"][:4] == ["Demo project", "Site", "House", "Storey 1"]
    assert result["group_focus"] == result["storey2"] and len(result["storey2"]) == 3
    assert result["gl_errors"] == []


def test_hide_and_isolate_change_atlas_and_composite(tree_driven):
    result, shots = tree_driven
    assert result["hidden"] == [0] and not result["hidden_has_region"] and 0 not in result["atlas_ids_hidden"]
    assert result["isolated_visible"] == [0] and result["shown_visible"] == 7
    start, hidden, isolated = (shots[k] for k in ("start", "hidden", "isolated"))
    lay = result["layout_hover"]
    assert (np.abs(_region(start, lay) - _region(hidden, lay)).max(-1) > 10).sum() > 200
    assert (np.abs(_region(hidden, lay) - _region(isolated, lay)).max(-1) > 10).sum() > 200


def test_hover_outlines_and_click_reveals(tree_driven):
    result, shots = tree_driven
    assert result["hover"] == result["hover_node"]
    x, y, w, h = result["layout_hover"]
    comp = _region(shots["hover"], (x, y, w, h))
    outline = np.abs(comp - [255, 200, 80]).max(-1) < 40
    assert outline.sum() > 20  # the hover colour around the door's bounds
    assert result["picked_expected"] is not None and result["picked_selected"] == result["picked_expected"]
    assert result["picked_row"] not in result["rows_before_reveal"] and result["picked_row_shown"]


def test_framing_leaves_a_margin_on_all_sides(tree_driven):
    if os.environ.get("RTTA_TEST_HEADLESS"):
        pytest.skip("pyglet's headless window keeps its size: the driver's resizes do nothing there")
    result, shots = tree_driven
    for key, f in result["framing"].items():
        img = _region(shots[f["png"][:-4]], f["rect"])
        h, w = img.shape[:2]
        assert abs(w / h - float(key.split()[1])) < 0.02, key
        mask = np.abs(img - BACKGROUND).max(-1) > 10
        ys, xs = np.nonzero(mask)
        margins = xs.min() / w, (w - 1 - xs.max()) / w, ys.min() / h, (h - 1 - ys.max()) / h
        assert min(margins) >= 0.02, (key, margins)  # no object pixel within 2% of any edge
        assert min(margins[0] + margins[1], margins[2] + margins[3]) < 0.5, (key, margins)  # and it fills


def test_a_100000_object_tree_emits_only_the_rows_on_screen(tree_driven):
    result, _ = tree_driven
    assert result["many_rows"] == 100_000 + 1 + 20 + 1000
    assert 5 <= result["many_emitted"] <= 40  # the list clipper: what fits in the list, no more
    assert result["gl_errors"] == []  # imgui's buffers did not overflow


def test_double_click_fits_the_object(tree_driven):
    result, _ = tree_driven
    assert result["double_click_target"] == pytest.approx(result["window_center"])
    x0, y0, x1, y1 = result["window_rect"]
    w, h = result["window_viewport"]
    margins = x0 / w, (w - x1) / w, y0 / h, (h - y1) / h
    assert min(margins) >= 0.02 and min(margins[0] + margins[1], margins[2] + margins[3]) < 0.5, margins


def test_group_opacity_sets_its_subtree(tree_driven):
    result, _ = tree_driven
    assert sorted(int(k) for k in result["opacities"]) == result["storey1"]
    assert all(v < 0.05 for v in result["opacities"].values())
