"""USD time samples (rtta.scene.readers.usd_stage.read_time): the stage is read at one time
code, its start time code where it authors a time code range, else the earliest (an
attribute's first sample, or its default where it has no samples); time-sampled points,
xformOps and PointInstancer data are drawn there, and samples win over a default value."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rtta.scene.loader import load_scene

pytest.importorskip("pxr")

TRI = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float64)
TOPOLOGY = """        int[] faceVertexCounts = [3]
        int[] faceVertexIndices = [0, 1, 2]
"""


def _points(p: np.ndarray) -> str:
    return "[" + ", ".join(f"({x:g}, {y:g}, {z:g})" for x, y, z in p) + "]"


def _write(path: Path, body: str, header: str = "") -> Path:
    path.write_text(f'#usda 1.0\n(\n    upAxis = "Z"\n{header})\n\n{body}')
    return path


def _read(path: Path):
    from rtta.scene.readers import usd

    return usd.read(path)


def _mover(xform: str, points: str) -> str:
    """/root, whose translate is `xform` (its attribute lines), holding the triangle mesh `m`
    whose points are `points` (its attribute lines)."""
    return f"""def Xform "root"
{{
{xform}
    uniform token[] xformOpOrder = ["xformOp:translate"]

    def Mesh "m"
    {{
{points}
{TOPOLOGY}    }}
}}
"""


def test_time_sampled_points_and_transform_are_drawn_at_the_start_time_code(tmp_path):
    """What an animation export writes: points and the translate only as time samples, a
    range from 4 to 10. The mesh is drawn (it was empty at the default time), moved by the
    translate interpolated at frame 4, its points interpolated there too."""
    path = _write(
        tmp_path / "anim.usda",
        _mover(
            "    double3 xformOp:translate.timeSamples = { 0: (0, 0, 0), 10: (10, 0, 0) }",
            f"        point3f[] points.timeSamples = {{ 0: {_points(TRI)}, 10: {_points(TRI * 11)} }}",
        ),
        "    startTimeCode = 4\n    endTimeCode = 10\n",
    )
    a = _read(path)
    assert a.names == ["m"], a.names
    np.testing.assert_allclose(a.vertices[0], TRI * 5 + (4, 0, 0))  # points at 4: TRI * (1 + 10 * 0.4)
    s = load_scene(path, cache=False)  # the whole way, through the reader's child process
    assert s.names == ["m"]
    np.testing.assert_allclose(s.aabb_min[0], [4, 0, 0], atol=1e-6)
    np.testing.assert_allclose(s.aabb_max[0], [9, 5, 0], atol=1e-6)


def test_without_a_range_the_first_sample_is_drawn(tmp_path):
    """No startTimeCode and endTimeCode: Usd.TimeCode.EarliestTime, the first sample of each
    attribute (frame -4 of the translate, frame 0 of the points), not frame 0 (the start time
    code usd-core reports when none is authored) nor the default time (no points at all)."""
    path = _write(
        tmp_path / "norange.usda",
        _mover(
            "    double3 xformOp:translate.timeSamples = { -4: (2, 0, 0), 10: (16, 0, 0) }",
            f"        point3f[] points.timeSamples = {{ 0: {_points(TRI)}, 10: {_points(TRI * 3)} }}",
        ),
    )
    a = _read(path)
    assert a.names == ["m"], a.names
    np.testing.assert_allclose(a.vertices[0], TRI + (2, 0, 0))


def test_samples_win_over_a_default_value(tmp_path):
    """An attribute with both a default and samples gives the samples' value (as usdview shows
    at its start frame), with a range or without; a default alone is still read."""
    both = _mover(
        "    double3 xformOp:translate = (100, 0, 0)\n"
        "    double3 xformOp:translate.timeSamples = { 1: (1, 0, 0), 9: (9, 0, 0) }",
        f"        point3f[] points = {_points(TRI * 7)}\n"
        f"        point3f[] points.timeSamples = {{ 1: {_points(TRI * 2)} }}",
    )
    a = _read(_write(tmp_path / "both.usda", both))
    np.testing.assert_allclose(a.vertices[0], TRI * 2 + (1, 0, 0))
    a = _read(_write(tmp_path / "both_range.usda", both, "    startTimeCode = 5\n    endTimeCode = 9\n"))
    np.testing.assert_allclose(a.vertices[0], TRI * 2 + (5, 0, 0))
    plain = _mover("    double3 xformOp:translate = (100, 0, 0)", f"        point3f[] points = {_points(TRI)}")
    a = _read(_write(tmp_path / "plain.usda", plain, "    startTimeCode = 5\n    endTimeCode = 9\n"))
    np.testing.assert_allclose(a.vertices[0], TRI + (100, 0, 0))


def test_a_point_instancer_with_time_sampled_data(tmp_path):
    """positions, protoIndices and invisibleIds only as samples, and a prototype whose points
    are samples too: the instances at the start frame (3), instance 1 invisible there."""
    body = f"""def PointInstancer "scatter"
{{
    int[] protoIndices.timeSamples = {{ 1: [0, 0, 0], 5: [0, 0] }}
    point3f[] positions.timeSamples = {{
        1: [(0, 0, 0), (10, 0, 0), (20, 0, 0)],
        5: [(0, 40, 0), (10, 40, 0), (20, 40, 0)],
    }}
    int64[] invisibleIds.timeSamples = {{ 1: [1] }}
    rel prototypes = </scatter/P/tri>

    def Scope "P"
    {{
        def Mesh "tri"
        {{
            point3f[] points.timeSamples = {{ 0: {_points(TRI)} }}
{TOPOLOGY}        }}
    }}
}}
"""
    path = _write(tmp_path / "scatter.usda", body, "    startTimeCode = 3\n    endTimeCode = 5\n")
    a = _read(path)
    assert a.names == ["tri_0", "tri_2"], a.names
    np.testing.assert_allclose(a.vertices[0], TRI + (0, 20, 0))  # positions at 3: halfway to y = 40
    np.testing.assert_allclose(a.vertices[1], TRI + (20, 20, 0))
    assert not a.warnings, a.warnings


@pytest.mark.parametrize("start", ["nan", "inf", "-inf"])
def test_a_start_time_code_that_is_not_finite_reads_the_first_samples(tmp_path, start):
    """startTimeCode = nan read every value as none ('no parts'); a start that is not a finite
    number reads as no range does: each attribute's first sample."""
    path = _write(
        tmp_path / "start.usda",
        _mover(
            "    double3 xformOp:translate.timeSamples = { 1: (1, 0, 0), 10: (10, 0, 0) }",
            f"        point3f[] points.timeSamples = {{ 1: {_points(TRI)} }}",
        ),
        f"    startTimeCode = {start}\n    endTimeCode = 10\n",
    )
    a = _read(path)
    assert a.names == ["m"], a.names
    np.testing.assert_allclose(a.vertices[0], TRI + (1, 0, 0))
