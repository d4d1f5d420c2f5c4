"""The shader loader: package files, includes, defines after #version, unknown defines rejected."""

import pytest

from rtta.gl import glsl


def test_defines_are_injected_after_version():
    src = glsl.load("scene.vert", CAPTURE_VS=True)
    lines = src.splitlines()
    assert lines[0] == "#version 430" and lines[1] == "#define CAPTURE_VS 1"
    assert "struct Record" in src  # records.glsl was included
    assert "#include" not in src


def test_unknown_define_is_rejected():
    with pytest.raises(ValueError, match="unknown define"):
        glsl.load("scene.frag", NOT_A_DEFINE=1)


def test_every_shader_compiles(gl):
    for stages in (
        {"vertex_shader": glsl.load("scene.vert"), "fragment_shader": glsl.load("scene.frag")},
        {"vertex_shader": glsl.load("scene.vert", CAPTURE_VS=True), "fragment_shader": glsl.load("scene.frag")},
        {
            "vertex_shader": glsl.load("scene.vert", CAPTURE_GS=True),
            "geometry_shader": glsl.load("capture.geom"),
            "fragment_shader": glsl.load("scene.frag"),
        },
    ):
        gl.program(**stages).release()


def test_capture_path_falls_back_without_the_layer_extension(gl):
    """Forcing a context 'without' GL_ARB_shader_viewport_layer_array: auto picks the GS path,
    an explicit 'vs' request is a clear error naming the extension."""
    import dataclasses

    from rtta.errors import RttaError
    from rtta.gl.context import LAYER_EXTENSION, Capabilities

    caps = dataclasses.replace(Capabilities.of(gl), vertex_layer=False)
    assert caps.capture_path("auto") == "gs"
    with pytest.raises(RttaError, match=LAYER_EXTENSION):
        caps.capture_path("vs")
    assert Capabilities.of(gl).capture_path("auto") == ("vs" if LAYER_EXTENSION in gl.extensions else "gs")


def test_scene_pass_routes_defines_by_declaration_and_rejects_unknown(gl):
    from rtta.passes.capture import ScenePass

    with pytest.raises(ValueError, match="BOGUS"):
        ScenePass(gl, BOGUS=True)
    p = ScenePass(gl, SEPARATE=True)  # declared by scene.frag only: scene.vert must not get it
    try:
        assert "u_textured" not in p.program  # untextured variant: SEPARATE's uniforms are #ifdef TEXTURED
        assert "u_textured" in p.program_for(True)
    finally:
        p.release()


def test_matrices_past_float32_saturate_instead_of_inf():
    """The inverse of a nearly singular view-projection at an extreme camera can hold entries
    past float32's range: they saturate (a finite uniform), with no overflow warning."""
    import warnings

    import numpy as np

    from rtta.gl.glsl import mat_bytes

    m = np.diag([1e300, -1e300, 1.0, 2.0])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        out = np.frombuffer(mat_bytes(m), np.float32).reshape(4, 4)
    assert np.isfinite(out).all() and out[0, 0] > 3e38 and out[1, 1] < -3e38 and out[3, 3] == 2.0
