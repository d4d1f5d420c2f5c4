"""The viewer's cutaways and exploded views (issue 41): a plane placed on a picked surface, its
handle dragged, flipped, the one-button reset, the explode slider, and picking on a moved
part. The real window under Xvfb is driven by tests/viewer_cutaway_driver.py."""

from __future__ import annotations

import numpy as np
import pytest
from test_viewer import _region, display, run_driver  # noqa: F401  (the Xvfb fixture)

from viewer.cutaway import CutawayState

pytestmark = pytest.mark.viewer


@pytest.fixture(scope="module")
def cut(display, tmp_path_factory):  # noqa: F811
    out, cwd = tmp_path_factory.mktemp("cutaway"), tmp_path_factory.mktemp("cwd")
    result, shots = run_driver(display, out, "viewer_cutaway_driver.py", cwd=cwd)
    return result, shots


def _changed(a: np.ndarray, b: np.ndarray) -> float:
    """The share of pixels that changed by more than 10/255 in some channel."""
    return float((np.abs(a.astype(int) - b.astype(int)).max(-1) > 10).mean())


def _parts(result, shots, a: str, b: str) -> tuple[float, float]:
    rects = result["layout"]
    return tuple(_changed(_region(shots[a], rects[k]), _region(shots[b], rects[k])) for k in ("composite", "atlas"))


def test_plane_on_a_picked_surface_changes_composite_and_atlas(cut):
    r, shots = cut
    p = r["plane"]
    assert p["normal"] is not None and abs(np.linalg.norm(p["normal"]) - 1) < 1e-9 and not p["picking"]
    assert p["focus"] == []  # the click placed the plane, it selected nothing
    composite, atlas = _parts(r, shots, "first", "plane")
    assert composite > 0.01 and atlas > 0.01, (composite, atlas)
    composite, atlas = _parts(r, shots, "plane", "plane_quad")
    assert composite > 0.01 and atlas == 0.0  # the translucent quad shows, over the composite alone
    assert r["gl_errors"] == []


def test_dragging_the_handle_moves_the_plane_along_its_normal(cut):
    r, shots = cut
    d = r["drag"]
    assert r["grabbed"] and not d["dragging"]
    assert d["after"] > d["before"]  # along the normal (away from the camera here: less is removed)
    composite, atlas = _parts(r, shots, "plane", "dragged")
    assert composite > 0.005 and atlas > 0.005, (composite, atlas)


def test_flip_keeps_the_other_side(cut):
    r, shots = cut
    assert np.allclose(r["flipped_normal"], -np.asarray(r["plane"]["normal"]))
    before, after = set(r["removed_before_flip"]), set(r["removed_after_flip"])
    assert after and not before & after  # the parts beyond the plane now are those kept before
    composite, atlas = _parts(r, shots, "dragged", "flipped")
    assert composite > 0.05 and atlas > 0.05, (composite, atlas)


def test_toggle_off_and_on(cut):
    _, shots = cut
    assert np.array_equal(shots["toggled_off"], shots["first"])
    assert np.array_equal(shots["toggled_on"], shots["flipped"])


def test_reset_clears_everything_active(cut):
    r, shots = cut
    assert r["active_before_reset"] == ["section", "explode 0.50", "lens", "1 hidden"]
    assert r["active_after_reset"] == []
    assert np.array_equal(shots["reset"], shots["first"])


def test_explode_slider_at_one_then_zero_gives_the_first_image_back(cut):
    r, shots = cut
    assert _parts(r, shots, "reset", "exploded")[0] > 0.05
    assert np.array_equal(shots["unexploded"], shots["reset"])


def test_key_e_animates_the_explode_open_and_closed(cut):
    r, shots = cut
    a = r["animated"]
    assert a["end"] == 0.0 and 1.0 in a["seen"]
    assert any(0.0 < v < 1.0 for v in a["seen"])  # frames between: animated, not jumped
    assert _parts(r, shots, "reset", "animated_open")[0] > 0.05
    assert np.array_equal(shots["animated_closed"], shots["reset"])


def test_a_click_on_a_capped_part_selects_it(cut):
    m = cut[0]["capped"]
    assert m is not None and m["focus"] == [m["part"]]


def test_a_click_on_a_part_moved_by_explode_selects_it(cut):
    m = cut[0]["moved"]
    assert m is not None and m["offset"] > 0.05 * m["radius"]
    assert m["focus"] == [m["part"]]


def test_flip_and_toggle_of_the_state(demo_scene):
    c = CutawayState(axis="x", at=0.25)
    spec = c.spec(demo_scene)
    c.flip()
    assert c.spec(demo_scene) == "-" + spec
    c.enabled = False
    assert c.spec(demo_scene) is None and c.staging(demo_scene).cutaway.planes == ()
    c.set_plane((0.0, 0.0, 0.01), (0.0, 0.0, 2.0))
    assert c.spec(demo_scene) == "0,0,1,0.01"
    c.flip()
    assert c.staging(demo_scene).cutaway.planes[0].normal == (-0.0, -0.0, -1.0)


def test_saved_view_keeps_a_plane_along_a_normal(demo_scene, tmp_path):
    from viewer import saved
    from viewer.orbit import Orbit
    from viewer.state import ViewerState

    state = ViewerState(demo_scene.names, paths=demo_scene.paths)
    state.cutaway.set_plane((0.1, 0.2, 0.3), (1.0, 1.0, 0.0))
    state.cutaway.flip()
    o = Orbit.default(demo_scene.center, demo_scene.radius)
    views = saved.Views(tmp_path, demo_scene)
    views.save("n", saved.capture(demo_scene, state, o))
    other = ViewerState(demo_scene.names, paths=demo_scene.paths)
    saved.apply(views.load("n"), demo_scene, other, o)
    assert other.cutaway.normal == pytest.approx(state.cutaway.normal) and other.cutaway.axis == "off"
    assert other.cutaway.offset == pytest.approx(state.cutaway.offset)
    assert other.cutaway.spec(demo_scene) == state.cutaway.spec(demo_scene)


@pytest.mark.parametrize("spec, axis, at", [("-x", "-x", 0.5), ("z=25%", "z", 0.25), ("y=150%", "y", 1.0)])
def test_a_saved_view_may_place_its_plane_at_a_fraction(demo_scene, spec, axis, at):
    """A view file's `x`, `-x` or `x=P%` (as `rtta snapshot --save-view` writes them) opens with
    the viewer's slider there (it refused them: only x=V was read)."""
    from viewer import saved
    from viewer.orbit import Orbit
    from viewer.state import ViewerState

    o = Orbit.default(demo_scene.center, demo_scene.radius)
    view = saved.capture(demo_scene, ViewerState(demo_scene.names, paths=demo_scene.paths), o)
    view.sections = {"planes": [spec], "caps": "hatch", "scope": "all"}
    state = ViewerState(demo_scene.names, paths=demo_scene.paths)
    saved.apply(view, demo_scene, state, o)
    assert (state.cutaway.axis, state.cutaway.caps, state.cutaway.normal) == (axis, "hatch", None)
    assert state.cutaway.at == pytest.approx(at)
