"""Missing GL features, forced for real through Mesa's overrides in a child process: a
context below GL 4.3 is refused with a message naming both versions; without the layer
extension the capture falls back to the geometry-shader path, says so, and draws the same."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from rtta.errors import RttaError
from rtta.gl.context import LAYER_EXTENSION, Capabilities

RTTA = str(Path(sys.executable).with_name("rtta"))


@pytest.fixture(scope="module")
def mesa(ctx):
    if "Mesa" not in ctx.info["GL_VERSION"] and "llvmpipe" not in ctx.info["GL_RENDERER"]:
        pytest.skip("the overrides are Mesa's (CI renders with Mesa llvmpipe)")
    return ctx


def _rtta(args: list[str], **env: str) -> subprocess.CompletedProcess:
    full = {k: v for k, v in os.environ.items() if not k.startswith("MESA_")} | env
    return subprocess.run([RTTA, *args], env=full, capture_output=True, text=True, timeout=300)


def test_gl_below_4_3_is_refused_naming_both_versions(mesa, tmp_path):
    out = tmp_path / "x.png"
    proc = _rtta(["snapshot", "--size", "64x48", "--out", str(out)], MESA_GL_VERSION_OVERRIDE="3.3")
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.count("\n") == 1 and "OpenGL 4.3 is required" in proc.stderr and "3.3" in proc.stderr
    assert "Traceback" not in proc.stderr and not out.exists()


def test_missing_layer_extension_falls_back_to_the_geometry_shader(mesa, tmp_path):
    args = ["snapshot", "--size", "200x150", "--mode", "sprites", "--camera", "40,20,2.2"]
    fallback = _rtta([*args, "--out", str(tmp_path / "gs.png")], MESA_EXTENSION_OVERRIDE=f"-{LAYER_EXTENSION}")
    assert fallback.returncode == 0, fallback.stderr
    assert f"note: {LAYER_EXTENSION} is missing" in fallback.stderr and "geometry-shader" in fallback.stderr
    normal = _rtta([*args, "--capture-path", "vs", "--out", str(tmp_path / "vs.png")])
    assert normal.returncode == 0 and "note:" not in normal.stderr, normal.stderr
    a = np.asarray(Image.open(tmp_path / "gs.png"), np.int16)
    b = np.asarray(Image.open(tmp_path / "vs.png"), np.int16)
    assert (np.abs(a - b).max(-1) <= 3).mean() >= 0.995
    assert (a[..., :3] != a[0, 0, :3]).any(-1).mean() > 0.1  # the assembly is drawn, not just background


def test_asking_for_the_missing_path_is_an_error(mesa, tmp_path):
    proc = _rtta(
        ["snapshot", "--size", "64x48", "--capture-path", "vs", "--out", str(tmp_path / "x.png")],
        MESA_EXTENSION_OVERRIDE=f"-{LAYER_EXTENSION}",
    )
    assert proc.returncode == 2 and LAYER_EXTENSION in proc.stderr and proc.stderr.count("\n") == 1


class _FakeContext:
    """What Capabilities.of reads from a context, for versions no real driver here offers."""

    def __init__(self, version: int, extensions: set[str]) -> None:
        self.version_code = version
        self.extensions = extensions
        self.info = {"GL_RENDERER": "fake", "GL_MAX_ARRAY_TEXTURE_LAYERS": 2048, "GL_MAX_TEXTURE_SIZE": 16384}


def test_capabilities_name_what_is_missing():
    with pytest.raises(RttaError, match=r"OpenGL 4\.3 is required, the context offers 4\.1"):
        Capabilities.of(_FakeContext(410, {LAYER_EXTENSION}))
    caps = Capabilities.of(_FakeContext(430, set()))
    assert caps.capture_path() == "gs" and LAYER_EXTENSION in caps.notes[0]
    full = Capabilities.of(_FakeContext(450, {LAYER_EXTENSION}))
    assert full.capture_path() == "vs" and full.notes == []
