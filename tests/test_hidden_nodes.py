"""Legal but degenerate transforms: a node whose scale or matrix is singular (a zero scale is
glTF's way to hide a node) draws nothing, nor anything below it; the file loads with one
warning naming those nodes, in glTF, COLLADA, USD and 3DXML alike (issue 42)."""

from __future__ import annotations

import zipfile

import numpy as np
import pytest
from assemblies import write_3dxml, write_collada, write_usd
from bad_gltf import box_doc, glb

from rtta.cli.main import main
from rtta.errors import RttaError
from rtta.scene.loader import load_scene
from rtta.scene.readers.hidden import singular

ZERO_Y = [1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]  # column-major, y scaled to 0
RANK_2 = [1, 0, 0, 0, 2, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]  # x and y columns parallel


def _gltf(tmp_path, nodes, name="hidden.glb"):
    doc, binary = box_doc(nodes)
    doc["scenes"] = [{"nodes": [0]}]
    path = tmp_path / name
    path.write_bytes(glb(doc, binary))
    return path


def _hidden_warning(scene) -> str:
    notes = [w for w in scene.warnings if "singular transform" in w]
    assert len(notes) == 1, scene.warnings
    return notes[0]


@pytest.mark.parametrize(
    "hide",
    [{"scale": [1, 0, 1]}, {"matrix": ZERO_Y}, {"matrix": RANK_2}, {"scale": [0, 0, 0]}, {"matrix": [0] * 16}],
    ids=["zero-scale", "zero-column", "rank-2", "all-zero-scale", "zero-matrix"],
)
def test_gltf_singular_node_is_left_out_with_one_warning(tmp_path, hide):
    nodes = [
        {"name": "root", "children": [1, 2]},
        {"name": "shown", "mesh": 0, "translation": [3, 0, 0]},
        {"name": "gone", "mesh": 0, **hide},
    ]
    scene = load_scene(_gltf(tmp_path, nodes))
    assert scene.names == ["shown"]
    assert _hidden_warning(scene).endswith(": gone")
    np.testing.assert_allclose(scene.aabb_min[0], [2.5, -0.5, -0.5])


def test_gltf_hidden_group_hides_what_is_below_and_is_named_once(tmp_path):
    nodes = [
        {"name": "root", "children": [1, 2]},
        {"name": "shown", "mesh": 0},
        {"name": "folded", "scale": [1, 1, 0], "children": [3, 4]},
        {"name": "a", "mesh": 0, "translation": [2, 0, 0]},
        {"name": "b", "mesh": 0, "scale": [0, 1, 1]},  # hidden twice over: the group is named
    ]
    scene = load_scene(_gltf(tmp_path, nodes))
    assert scene.names == ["shown"]
    assert _hidden_warning(scene).startswith("1 node(s)") and _hidden_warning(scene).endswith(": folded")


def test_gltf_product_of_regular_transforms_that_underflows(tmp_path):
    nodes = [
        {"name": "root", "children": [1, 2]},
        {"name": "shown", "mesh": 0, "scale": [1e-9, 1e-9, 1e-9]},  # tiny but uniform: drawn
        {"name": "thin", "scale": [1, 1e-200, 1], "children": [3]},  # each regular; a scale of 0 together
        {"name": "thinner", "mesh": 0, "scale": [1, 1e-200, 1]},
    ]
    scene = load_scene(_gltf(tmp_path, nodes))
    assert scene.names == ["shown"] and _hidden_warning(scene).endswith(": thinner")


def test_gltf_everything_hidden_is_one_error(tmp_path):
    path = _gltf(tmp_path, [{"name": "gone", "mesh": 0, "scale": [1, 0, 1]}])
    with pytest.raises(RttaError, match="singular transform .* nothing to draw"):
        load_scene(path)


def test_cli_loads_the_file_with_a_warning(tmp_path, capsys):
    nodes = [
        {"name": "root", "children": [1, 2]},
        {"name": "shown", "mesh": 0},
        {"name": "gone", "mesh": 0, "scale": [1, 0, 1]},
    ]
    assert main(["info", str(_gltf(tmp_path, nodes))]) == 0
    out, err = capsys.readouterr()
    assert "shown" in out and "gone" not in out
    assert err.count("\n") == 1 and err.startswith("rtta: warning: ") and "singular transform" in err, err


def test_singular_is_scale_free():
    m = np.tile(np.eye(4), (5, 1, 1))
    m[1, :3, :3] *= 1e-100  # tiny uniform scale
    m[2, 1, 1] = 0.0
    m[3, :3, :3] = [[1, 1, 0], [1, 1, 0], [0, 0, 1]]
    m[4, 0, 0] = np.nan  # not finite: the loader's to refuse
    assert singular(m).tolist() == [False, False, True, True, False]


def _collada_hidden(path):
    write_collada(path)
    text = path.read_text()
    start = text.index('<node id="hand"')
    end = text.index(">", start) + 1
    path.write_text(text[:end] + "<scale>1 0 1</scale>" + text[end:])


def _usd_hidden(path):
    write_usd(path)
    from pxr import Gf, Usd, UsdGeom

    stage = Usd.Stage.Open(str(path))
    UsdGeom.Xformable(stage.GetPrimAtPath("/plant/arm/hand")).AddScaleOp().Set(Gf.Vec3f(1, 0, 1))
    stage.GetRootLayer().Save()


def _3dxml_hidden(path):
    write_3dxml(path)
    with zipfile.ZipFile(path) as z:
        members = {name: z.read(name) for name in z.namelist()}
    text = members["plant.3dxml"].decode()
    start = text.index('name="hand.1"')
    at = text.index("<RelativeMatrix>", start) + len("<RelativeMatrix>")
    end = text.index("</RelativeMatrix>", at)
    members["plant.3dxml"] = (text[:at] + "1 0 0 0 0 0 0 0 1 0 0 0" + text[end:]).encode()
    with zipfile.ZipFile(path, "w") as z:
        for name, data in members.items():
            z.writestr(name, data)


@pytest.mark.parametrize(
    "suffix, hide, named",
    [
        (".dae", _collada_hidden, "hand"),
        (".usda", _usd_hidden, "/plant/arm/hand"),
        (".3dxml", _3dxml_hidden, "finger"),  # trimesh keeps no group nodes: the part is named
    ],
)
def test_assembly_formats_leave_a_hidden_subtree_out(tmp_path, suffix, hide, named):
    path = tmp_path / f"plant{suffix}"
    hide(path)
    scene = load_scene(path)
    assert sorted(scene.names) == ["base", "link"]
    note = _hidden_warning(scene)
    assert note.startswith("1 node(s)") and note.endswith(f": {named}"), note


def test_3mf_through_trimesh_leaves_a_hidden_item_out(tmp_path):
    """3MF's build items and components carry transforms (read by trimesh, placed by rtta)."""
    import trimesh

    s = trimesh.Scene()
    box = trimesh.creation.box()
    s.add_geometry(box, node_name="shown", transform=trimesh.transformations.translation_matrix([3, 0, 0]))
    flat = np.eye(4)
    flat[1, 1] = 0.0
    s.add_geometry(box, node_name="gone", geom_name="second", transform=flat)
    path = tmp_path / "hidden.3mf"
    path.write_bytes(s.export(file_type="3mf"))
    scene = load_scene(path)
    assert scene.names == ["shown"] and _hidden_warning(scene).endswith(": gone")
