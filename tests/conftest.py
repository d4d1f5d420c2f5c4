"""One EGL context per test session; every GL test checks ctx.error before and after."""

from __future__ import annotations

import atexit
import os
import shutil
import signal
import tempfile

import pytest

from rtta.gl.context import shared_context

# the scene cache (rtta.scene.cache) in a folder of this session's own, never the user's;
# the commands the tests run in subprocesses inherit it; removed when the session ends
os.environ["RTTA_CACHE_DIR"] = tempfile.mkdtemp(prefix="rtta-test-cache-")
atexit.register(shutil.rmtree, os.environ["RTTA_CACHE_DIR"], True)

# Ctrl+C as a terminal sends it, whatever started the suite: a shell runs a background job with
# SIGINT ignored, which rtta keeps (nohup's choice), and the processes the tests start inherit
# it; the tests of interrupts (test_interrupts.py, the viewer's Ctrl+C) would then wait in vain
if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)


def pytest_addoption(parser):
    parser.addoption(
        "--regenerate-references",
        action="store_true",
        default=False,
        help="rewrite tests/references/*.png from this run instead of comparing",
    )


GL_FIXTURES = {"ctx", "gl", "make_renderer"}
VIEWER_FILES = {"test_viewer.py", "test_tree_viewer.py"}  # the real window under Xvfb (tests/viewer_*driver.py)
SLOW_FIXTURES = {"driven", "driven_large", "tree_driven"}  # one driven viewer session each: 30-75 s


def pytest_collection_modifyitems(items):
    """Markers by what a test uses (registered in pyproject.toml, `--strict-markers`): `gl` for
    a GL context, `viewer` for the viewer's window tests, `slow` for the driven viewer sessions;
    other tests over ~10 s carry `@pytest.mark.slow` by hand."""
    for item in items:
        uses = set(getattr(item, "fixturenames", ()))
        if uses & GL_FIXTURES:
            item.add_marker(pytest.mark.gl)
        if item.path.name in VIEWER_FILES or "display" in uses:
            item.add_marker(pytest.mark.viewer)
        if uses & SLOW_FIXTURES:
            item.add_marker(pytest.mark.slow)


@pytest.fixture(scope="session")
def ctx():
    """The process's one headless context (the CLI called in-process uses it too)."""
    from rtta.memory import steady_heap

    steady_heap()  # as the CLI and the viewer do
    return shared_context()


@pytest.fixture
def gl(ctx):
    """The session context, asserted error-free around the test."""
    assert ctx.error == "GL_NO_ERROR"
    yield ctx
    assert ctx.error == "GL_NO_ERROR"


@pytest.fixture
def make_renderer(gl):
    """Renderers created in a test are released at its end (no GPU objects leak)."""
    from rtta.renderer.renderer import Renderer

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
    from rtta.scene.generators.demo import demo_path
    from rtta.scene.loader import load_scene

    return load_scene(demo_path())
