"""The shader loader: package files, includes, defines after #version, unknown defines rejected."""

import pytest

from rtta import glsl


def test_defines_are_injected_after_version():
    src = glsl.load("scene.vert", CAPTURE_VS=True)
    lines = src.splitlines()
    assert lines[0] == "#version 430" and lines[1] == "#define CAPTURE_VS 1"
    assert "struct Record" in src          # records.glsl was included
    assert "#include" not in src


def test_unknown_define_is_rejected():
    with pytest.raises(ValueError, match="unknown define"):
        glsl.load("scene.frag", NOT_A_DEFINE=1)


def test_every_shader_compiles(gl):
    for stages in ({"vertex_shader": glsl.load("scene.vert"), "fragment_shader": glsl.load("scene.frag")},
                   {"vertex_shader": glsl.load("scene.vert", CAPTURE_VS=True),
                    "fragment_shader": glsl.load("scene.frag")},
                   {"vertex_shader": glsl.load("scene.vert", CAPTURE_GS=True),
                    "geometry_shader": glsl.load("capture.geom"), "fragment_shader": glsl.load("scene.frag")}):
        gl.program(**stages).release()
