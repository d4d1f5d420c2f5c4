"""One EGL context per test session; every GL test checks ctx.error before and after."""

from __future__ import annotations

import numpy as np
import pytest

from rtta.context import create_headless_context


def pytest_addoption(parser):
    parser.addoption("--regenerate-references", action="store_true", default=False,
                     help="rewrite tests/references/*.png from this run instead of comparing")


@pytest.fixture(scope="session")
def ctx():
    context = create_headless_context()
    yield context
    context.release()


@pytest.fixture
def gl(ctx):
    """The session context, asserted error-free around the test."""
    assert ctx.error == "GL_NO_ERROR"
    yield ctx
    assert ctx.error == "GL_NO_ERROR"


@pytest.fixture
def make_renderer(gl):
    """Renderers created in a test are released at its end (no GPU objects leak)."""
    from rtta.renderer import Renderer

    made = []

    def make(scene, settings=None):
        r = Renderer(gl, scene, settings)
        made.append(r)
        return r

    yield make
    for r in made:
        r.release()


@pytest.fixture(scope="session")
def demo_scene():
    from rtta.demo import demo_path
    from rtta.loader import load_scene

    return load_scene(demo_path())


def near_edges(ids: np.ndarray) -> np.ndarray:
    """Pixels within one pixel (8-neighbourhood) of a change of id: silhouettes."""
    pad = np.pad(ids, 1, mode="edge")
    h, w = ids.shape
    edge = np.zeros(ids.shape, bool)
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            edge |= pad[1 + dy:1 + dy + h, 1 + dx:1 + dx + w] != ids
    return edge


CREASE = 2e-4   # window depth is affine over a planar triangle: larger 2nd differences are contours


def near_silhouettes(ids: np.ndarray, *depths: np.ndarray) -> np.ndarray:
    """Pixels within one pixel of an id change or of a depth crease/discontinuity in any image."""
    crease = np.zeros(ids.shape, bool)
    for d in depths:
        d = d.astype(np.float64)
        pad = np.pad(d, 1, mode="edge")
        second_x = np.abs(pad[1:-1, 2:] + pad[1:-1, :-2] - 2 * d)
        second_y = np.abs(pad[2:, 1:-1] + pad[:-2, 1:-1] - 2 * d)
        crease |= (second_x > CREASE) | (second_y > CREASE)
    return near_edges(ids) | near_edges(crease.astype(np.int8))
