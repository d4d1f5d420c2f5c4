"""Names of meshes reached through native USD instances (rtta.scene.readers.usd_names): each is
named after the innermost instance prim above it where that instance's prototype draws one
part, else '<instance>_<mesh name>' in a group named after the instance, as a PointInstancer's
instances are; a prototype's parts are counted as the reader draws them (no guides, no
invisible or empty meshes, proxies only where it has no render mesh)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rtta.scene.loader import load_scene

pytest.importorskip("pxr")

WHEELS = ("wheel_FL", "wheel_FR", "wheel_RL", "wheel_RR")


def _mesh(name: str, x: float = 0, indent: int = 4, extra: str = "", empty: bool = False) -> str:
    """A triangle mesh prim at x (no faces where `empty`); `extra` holds attribute lines."""
    pad = " " * indent
    faces = "" if empty else f"{pad}    int[] faceVertexCounts = [3]\n{pad}    int[] faceVertexIndices = [0, 1, 2]\n"
    return (
        f'{pad}def Mesh "{name}"\n{pad}{{\n{extra}'
        f"{pad}    point3f[] points = [({x}, 0, 0), ({x + 1}, 0, 0), ({x}, 1, 0)]\n{faces}{pad}}}\n"
    )


def _instance(name: str, prototype: str, at: tuple = (0, 0, 0), indent: int = 4) -> str:
    """An Xform at `at` that instances the class `prototype`."""
    pad = " " * indent
    return (
        f'{pad}def Xform "{name}" (\n{pad}    instanceable = true\n{pad}    references = </{prototype}>\n{pad})\n'
        f"{pad}{{\n{pad}    double3 xformOp:translate = {at}\n"
        f'{pad}    uniform token[] xformOpOrder = ["xformOp:translate"]\n{pad}}}\n'
    )


def _prim(kind: str, name: str, *children: str, indent: int = 0) -> str:
    pad = " " * indent
    return f'{pad}{kind} "{name}"\n{pad}{{\n' + "".join(children) + f"{pad}}}\n"


def _read(path: Path, body: str):
    from rtta.scene.readers import usd

    path.write_text("#usda 1.0\n\n" + body)
    return usd.read(path)


def _car() -> str:
    """/car holds four instances of the class /Wheel (the mesh `tire` and five instances of
    the class /Bolt, whose mesh is `geom`), wheel k at x = 100 k, bolt j at z = 10 j."""
    bolt = _prim("class", "Bolt", _mesh("geom"))
    wheel = _prim(
        "class", "Wheel", _mesh("tire"), *(_instance(f"bolt_{j}", "Bolt", (0, 0, 10 * j)) for j in range(1, 6))
    )
    car = _prim("def Xform", "car", *(_instance(w, "Wheel", (100 * k, 0, 0)) for k, w in enumerate(WHEELS)))
    return car + bolt + wheel


def test_nested_instances_are_named_after_the_innermost_instance(tmp_path):
    """Each bolt's mesh is named after its bolt instance, in the group of its wheel; the wheel's
    prototype draws six parts (its tire and its bolts), so its tire is '<wheel>_tire' in the
    group of the wheel. Each part lies where its instances place it."""
    a = _read(tmp_path / "car.usda", _car())
    expected = []
    for w in WHEELS:
        expected += [(f"{w}_tire", ("car", w))] + [(f"bolt_{j}", ("car", w)) for j in range(1, 6)]
    assert list(zip(a.names, a.paths, strict=True)) == expected
    for i, (_name, groups) in enumerate(expected):
        wheel, bolt = WHEELS.index(groups[1]), i % 6
        np.testing.assert_allclose(a.vertices[i][0], [100 * wheel, 0, 10 * bolt])


def test_a_prototype_of_several_meshes_is_a_group_of_its_meshes(tmp_path):
    """The wheel's prototype draws a tire and a rim below the Xform `hub` (and a guide mesh,
    an invisible one and an empty one, which are not drawn and not counted): each instance is a
    group of '<instance>_tire' and '<instance>_rim'. The cap's prototype draws one part (its
    render mesh; its proxy mesh is not drawn beside it): each cap is named after itself."""
    wheel = _prim(
        "class",
        "Wheel",
        _mesh("tire"),
        _prim("def Xform", "hub", _mesh("rim", 2, 8), indent=4),
        _mesh("axis", extra='        uniform token purpose = "guide"\n'),
        _mesh("ghost", extra='        token visibility = "invisible"\n'),
        _mesh("nothing", empty=True),
    )
    cap = _prim(
        "class",
        "Cap",
        _mesh("hi", extra='        uniform token purpose = "render"\n'),
        _mesh("lo", extra='        uniform token purpose = "proxy"\n'),
    )
    car = _prim(
        "def Xform",
        "car",
        _instance("wheel_FL", "Wheel"),
        _instance("wheel_FR", "Wheel", (100, 0, 0)),
        _instance("cap_FL", "Cap", (0, 0, 50)),
    )
    a = _read(tmp_path / "car.usda", car + wheel + cap)
    assert list(zip(a.names, a.paths, strict=True)) == [
        ("wheel_FL_tire", ("car", "wheel_FL")),
        ("wheel_FL_rim", ("car", "wheel_FL", "hub")),
        ("wheel_FR_tire", ("car", "wheel_FR")),
        ("wheel_FR_rim", ("car", "wheel_FR", "hub")),
        ("cap_FL", ("car",)),
    ]
    np.testing.assert_allclose(a.vertices[3][0], [102, 0, 0])


def test_a_single_level_instance_keeps_the_instance_name(tmp_path):
    """Unchanged: instances of a one-mesh prototype (its mesh below an Xform in it) are named
    after their instance prims, in the groups above them."""
    hand = _prim(
        "def Xform", "hand", _instance("finger", "F", indent=8), _instance("finger_2", "F", indent=8), indent=4
    )
    body = _prim("def Xform", "plant", hand) + _prim("class", "F", _prim("def Xform", "shape", _mesh("geom", indent=8)))
    a = _read(tmp_path / "plant.usda", body)
    assert list(zip(a.names, a.paths, strict=True)) == [("finger", ("plant", "hand")), ("finger_2", ("plant", "hand"))]


def test_names_are_the_same_on_two_reads(tmp_path):
    """The nested car read twice through the loader (in its child process, not cached): the
    same names and groups, the repeated bolt names numbered in file order."""
    path = tmp_path / "car.usda"
    path.write_text("#usda 1.0\n\n" + _car())
    first, again = load_scene(path, cache=False), load_scene(path, cache=False)
    assert first.names == again.names and first.paths == again.paths
    rr = [first.names[i] for i in range(first.count) if first.path_of(i) == ("car", "wheel_RR")]
    assert rr == ["wheel_RR_tire"] + [f"bolt_{j}_4" for j in range(1, 6)], rr
