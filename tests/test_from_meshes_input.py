"""`rtta.from_meshes` refuses a caller's mistakes with one RttaError naming the part, and
takes RGB colours (alpha 1) as well as RGBA."""

import numpy as np
import pytest

import rtta
from rtta.errors import RttaError

V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float)
F = np.array([[0, 1, 2]])


def test_rgb_colour_gets_alpha_one():
    scene = rtta.from_meshes([("a", V, F, None), ("b", V + 2, F, None)], colors=[(1.0, 0.0, 0.0), None])
    assert np.allclose(scene.colors[0], [1, 0, 0, 1])
    assert scene.colors[1][3] == 1.0


@pytest.mark.parametrize(
    "parts, colors, says",
    [
        ([("a", V, F, None)], [(255, 0, 0)], "values in [0, 1]"),
        ([("a", V, F, None)], [(1, 0)], "RGB or RGBA"),
        ([("a", V, F, None)], [(0.1, 0.2, 0.3), (0.1, 0.2, 0.3)], "2 colours for 1 parts"),
        ([("a", V, F, None)], [(np.nan, 0, 0)], "values in [0, 1]"),
        ([("a", V, [[0, 1, 3]], None)], None, "indexes a vertex"),
        ([("a", V, [[0, 1, -1]], None)], None, "indexes a vertex"),
        ([("a", [[0, 0]], F, None)], None, "shape [N, 3]"),
        ([("a", np.full_like(V, np.inf), F, None)], None, "not all finite"),
        ([("a", V, F, np.ones((2, 3)))], None, "2 normals for 3 vertices"),
        ([("a", V, F)], None, "expected (name, vertices, faces"),
        ([("a", "xyz", F, None)], None, "not numbers"),
        ([], None, "no objects"),
    ],
)
def test_mistakes_are_one_error(parts, colors, says):
    with pytest.raises(RttaError) as err:
        rtta.from_meshes(parts, colors=colors)
    assert says in str(err.value), str(err.value)
    assert "Error" not in str(err.value)
