"""USD purposes (rtta.scene.readers.usd_stage): `default` and `render` prims are drawn, `guide`
ones never, `proxy` ones only where no `render` part is drawn; the purpose is inherited from
the prims above (through native instances), a prim's own opinion winning; in a
PointInstancer's prototype a `default` prim takes the instancer's purpose."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rtta.scene.loader import load_scene

pytest.importorskip("pxr")


def _mesh(name: str, purpose: str = "", x: float = 0, indent: int = 4) -> str:
    """A triangle mesh prim at x (its purpose authored where given)."""
    pad = " " * indent
    own = f'{pad}    uniform token purpose = "{purpose}"\n' if purpose else ""
    return (
        f'{pad}def Mesh "{name}"\n{pad}{{\n{own}'
        f"{pad}    point3f[] points = [({x}, 0, 0), ({x + 1}, 0, 0), ({x}, 1, 0)]\n"
        f"{pad}    int[] faceVertexCounts = [3]\n{pad}    int[] faceVertexIndices = [0, 1, 2]\n{pad}}}\n"
    )


def _group(name: str, purpose: str, *children: str, kind: str = "Xform", indent: int = 0) -> str:
    pad = " " * indent
    own = f'{pad}    uniform token purpose = "{purpose}"\n' if purpose else ""
    return f'{pad}def {kind} "{name}"\n{pad}{{\n{own}' + "".join(children) + f"{pad}}}\n"


def _read(tmp_path: Path, body: str):
    from rtta.scene.readers import usd

    path = tmp_path / "scene.usda"
    path.write_text("#usda 1.0\n\n" + body)
    return usd.read(path)


def test_guides_are_never_drawn(tmp_path):
    """A guide mesh, and a mesh two levels below a guide Xform (inherited), are left out; a
    mesh below the guide Xform whose own purpose is `render` is drawn (its opinion wins)."""
    rig = _group(
        "rig", "guide", _group("deep", "", _mesh("handle", indent=8), indent=4), _mesh("marked", "render", 2), indent=4
    )
    a = _read(tmp_path, _group("asset", "", _mesh("body"), _mesh("helper", "guide"), rig))
    assert a.names == ["body", "marked"], a.names


def test_proxies_are_left_out_where_render_parts_are_drawn(tmp_path):
    """The car's render hull is drawn and its proxy (inherited from an Xform two levels up)
    is not; a default mesh beside them is drawn. The whole way, through load_scene."""
    car = _group(
        "car",
        "",
        _group("hi", "render", _mesh("hull_hi", indent=8), indent=4),
        _group("lo", "proxy", _group("geo", "", _mesh("hull_lo", indent=12), indent=8), indent=4),
    )
    path = tmp_path / "car.usda"
    path.write_text("#usda 1.0\n\n" + car + _mesh("ground", x=5, indent=0))
    s = load_scene(path, cache=False)
    assert s.names == ["hull_hi", "ground"], s.names
    assert s.path_of(0) == ("car", "hi")


def test_proxies_are_drawn_where_no_render_part_is(tmp_path):
    """A file that ships only proxies (and guides, and an empty render Xform) still shows
    them, in file order with the default parts; the guide is left out."""
    body = (
        _group("empty", "render")
        + _group("asset", "proxy", _mesh("lo"), _mesh("curve", "guide", 3))
        + _mesh("ground", x=5, indent=0)
    )
    a = _read(tmp_path, body)
    assert a.names == ["lo", "ground"], a.names
    np.testing.assert_allclose(a.vertices[1][0], [5, 0, 0])


def test_purpose_is_inherited_through_native_instances(tmp_path):
    """Two instances of one prototype: the one below a guide Xform is left out, the other drawn;
    one whose instance prim is a proxy is left out beside the render mesh."""
    body = (
        'class "C"\n{\n'
        + _mesh("m")
        + "}\n"
        + _group("guides", "guide", 'def Xform "a" (\n instanceable = true\n references = </C>\n)\n{\n}\n')
        + 'def Xform "b" (\n instanceable = true\n references = </C>\n)\n{\n}\n'
        + 'def Xform "c" (\n instanceable = true\n references = </C>\n)\n{\n    uniform token purpose = "proxy"\n}\n'
        + _mesh("hi", "render", 9, indent=0)
    )
    a = _read(tmp_path, body)
    assert a.names == ["b", "hi"], a.names


def test_purpose_in_point_instancer_prototypes(tmp_path):
    """A guide mesh in a prototype is never drawn; a prototype prim of purpose `default` takes
    its instancer's (a guide instancer draws nothing of it), wherever the prototype sits; a
    prototype inside a native instance below a guide Xform is guide, the same prototype in
    another instance is not (each read for the purpose it inherits)."""
    body = f"""def PointInstancer "trees"
{{
    int[] protoIndices = [0, 1]
    point3f[] positions = [(0, 0, 0), (10, 0, 0)]
    rel prototypes = [</trees/P/tree>, </Lib/rock>]

    def Scope "P"
    {{
        def Xform "tree"
        {{
{_mesh("trunk", indent=12)}{_mesh("bounds", "guide", 4, indent=12)}        }}
    }}
}}

def PointInstancer "helpers"
{{
    uniform token purpose = "guide"
    int[] protoIndices = [0]
    point3f[] positions = [(0, 20, 0)]
    rel prototypes = </Lib/rock>
}}

over "Lib"
{{
{_mesh("rock")}}}

class "C"
{{
    over "Lib"
    {{
{_mesh("bolt", indent=8)}    }}
}}

def Xform "g"
{{
    uniform token purpose = "guide"

    def Xform "a" (
        instanceable = true
        references = </C>
    )
    {{
    }}
}}

def Xform "b" (
    instanceable = true
    references = </C>
)
{{
}}

def PointInstancer "bolts"
{{
    int[] protoIndices = [0, 1]
    point3f[] positions = [(0, 30, 0), (0, 40, 0)]
    rel prototypes = [</g/a/Lib/bolt>, </b/Lib/bolt>]
}}
"""
    a = _read(tmp_path, body)
    assert a.names == ["tree_0", "rock_1", "bolt_1"], a.names
    np.testing.assert_allclose(a.vertices[2][0], [0, 40, 0])


def test_a_purpose_the_schema_does_not_know_is_drawn_as_default(tmp_path):
    """`purpose = "bogus"` (a token a file may author) is drawn as `default`, in place and inside
    a native instance's prototype: naming the instances counted it and failed the whole file
    ("tuple.index(x): x not in tuple")."""
    proto = _group("proto", "", _mesh("a", "bogus"), _mesh("b", x=2), kind="Xform")
    refs = "".join(
        f'    def Xform "{w}" (\n        instanceable = true\n        references = </proto>\n    )\n    {{\n    }}\n'
        for w in ("w1", "w2")
    )
    a = _read(tmp_path, f'def Xform "car"\n{{\n{refs}}}\n' + proto)
    assert sorted(a.names) == ["a", "b", "w1_a", "w1_b", "w2_a", "w2_b"], a.names
