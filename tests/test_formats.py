"""STEP (cascadio) and IFC (ifcopenshell) assemblies: tree, names, units, colours, and the
same bad-input care as every other format; files written by the tests (tests/assemblies.py)
and, when present, the real ones in ../shared/data."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from assemblies import IFC_TREE, STEP_PARTS, write_ifc, write_step

from rtta.errors import RttaError
from rtta.scene.loader import load_scene
from rtta.scene.select import resolve_names

RTTA = str(Path(sys.executable).with_name("rtta"))
SHARED = Path(__file__).resolve().parents[2] / "shared" / "data"


@pytest.fixture(scope="module")
def step_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("step") / "engine.step"
    write_step(path)
    return path


@pytest.fixture(scope="module")
def ifc_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("ifc") / "house.ifc"
    return path, write_ifc(path)


def _bounds(scene, oid):
    return scene.aabb_min[oid], scene.aabb_max[oid]


def test_step_tree_names_units_and_colours(step_file):
    s = load_scene(step_file)
    assert s.names == list(STEP_PARTS) and s.unit == "mm" and s.up_axis == "z"
    for oid, (name, (path, lo, hi, color)) in enumerate(STEP_PARTS.items()):
        assert s.path_of(oid) == path, name
        got_lo, got_hi = _bounds(s, oid)
        np.testing.assert_allclose(got_lo, lo, atol=0.05)  # millimetres, as written
        np.testing.assert_allclose(got_hi, hi, atol=0.05)
        if color is not None:  # sRGB as the CAD program shows it
            np.testing.assert_allclose(s.colors[oid, :3], color, atol=2e-3)
    assert sorted(s.groups) == ["engine", "engine/crank", "engine/head"]
    assert s.groups["engine/head"] == [2, 3]


def test_step_in_inches_keeps_inches(tmp_path):
    path = tmp_path / "inch.stp"
    write_step(path, unit=0.0254)
    assert "INCH" in path.read_text(encoding="latin-1")
    s = load_scene(path)
    assert s.unit == "in"
    np.testing.assert_allclose(s.aabb_max[0], [100, 20, 10], atol=0.01)


def test_step_length_unit_is_the_one_most_unit_contexts_name():
    """A context per part (as assemblies have): each names its length unit; a unit that only
    defines another (the millimetre an inch is converted from) or a missing entity counts not."""
    from rtta.scene.readers.step import length_unit

    def context(k: int, unit_ref: int) -> str:
        return (
            f"#{k}=(GEOMETRIC_REPRESENTATION_CONTEXT(3)GLOBAL_UNIT_ASSIGNED_CONTEXT((#{unit_ref},#2,#3))"
            "REPRESENTATION_CONTEXT('',''));\n"
        )

    units = (
        "#1=(LENGTH_UNIT()NAMED_UNIT(*)SI_UNIT(.MILLI.,.METRE.));\n#2=(NAMED_UNIT(*)PLANE_ANGLE_UNIT()"
        "SI_UNIT($,.RADIAN.));\n#3=(NAMED_UNIT(*)SI_UNIT($,.STERADIAN.)SOLID_ANGLE_UNIT());\n"
        "#4 = ( CONVERSION_BASED_UNIT('INCH',#5) LENGTH_UNIT() NAMED_UNIT(#6) );\n"
        "#5=LENGTH_MEASURE_WITH_UNIT(LENGTH_MEASURE(25.4),#1);\n#6=DIMENSIONAL_EXPONENTS(1.,0.,0.,0.,0.,0.,0.);\n"
    )
    inch_parts = "".join(context(100 + k, 4) for k in range(3))
    assert length_unit(units + inch_parts + context(200, 1) + context(201, 999)) == "in"
    assert length_unit(units + inch_parts + "".join(context(300 + k, 1) for k in range(4))) == "mm"
    assert length_unit(units) == ""


def test_step_stdout_stays_clean_and_nothing_is_written(step_file):
    before = sorted(p.name for p in step_file.parent.iterdir())
    res = subprocess.run([RTTA, "info", str(step_file), "--tree"], capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr
    lines = res.stdout.splitlines()
    assert lines[0].startswith(f"{step_file}: 4 objects") and lines[1] == "unit: mm, up axis: Z-up"
    assert lines[2].startswith("engine/  (4 objects, ") and len(lines) == 2 + 3 + 4  # nothing from OpenCASCADE
    assert sorted(p.name for p in step_file.parent.iterdir()) == before


def test_ifc_spatial_tree_names_and_classes(ifc_file):
    path, expected = ifc_file
    s = load_scene(path)
    assert sorted(s.names) == sorted(expected) and s.unit == "mm" and s.up_axis == "z"
    for name, (where, lo, hi) in expected.items():
        oid = s.index(name)
        assert s.path_of(oid) == where
        np.testing.assert_allclose(_bounds(s, oid)[0], lo, atol=1.0)
        np.testing.assert_allclose(_bounds(s, oid)[1], hi, atol=1.0)
    assert not any(n.startswith(("IfcOpeningElement", "IfcSpace")) for n in s.names)
    assert set(s.groups) == {"/".join(IFC_TREE[:k]) for k in (1, 2, 3)} | {
        "/".join((*IFC_TREE, f"Storey {k}")) for k in (1, 2)
    }
    wall = s.index("IfcWall 'Wall 1'")  # the opening is cut: more than a box
    assert s.index_ranges[wall, 1] // 3 > 12


def test_focus_by_group_and_glob_selects_the_subtree(ifc_file):
    s = load_scene(ifc_file[0])
    storey2 = [i for i in range(s.count) if "Storey 2" in s.path_of(i)]
    assert len(storey2) == 3
    assert resolve_names(s, ["Storey 2"], "--focus") == storey2
    assert resolve_names(s, ["Storey 2/*"], "--focus") == storey2
    assert resolve_names(s, ["/".join((*IFC_TREE, "Storey 2"))], "--focus") == storey2
    windows = resolve_names(s, ["IfcWindow*"], "--focus")
    assert [s.names[i] for i in windows] == ["IfcWindow 'Window 1'", "IfcWindow 'Window 2'"]
    assert resolve_names(s, ["IfcWindow"], "--focus") == windows  # the class
    assert resolve_names(s, ["IfcWindow 'Window 2'", "Storey 2"], "--focus") == [
        windows[1],
        *(i for i in storey2 if i != windows[1]),
    ]  # each id once
    with pytest.raises(RttaError, match="did you mean Storey 2"):
        resolve_names(s, ["Storey 22"], "--focus")
    with pytest.raises(RttaError, match="--focus: no object or group named 'Nothing\\*'"):
        resolve_names(s, ["Nothing*"], "--focus")


def test_snapshot_focus_and_opacity_accept_groups(ifc_file, tmp_path):
    path = ifc_file[0]
    out = tmp_path / "shot.png"
    res = subprocess.run(
        [
            RTTA,
            "snapshot",
            str(path),
            "--mode",
            "ghosted",
            "--focus",
            "Storey 2/*",
            "--opacity",
            "IfcSlab*=0.2",
            "--size",
            "96x72",
            "--out",
            str(out),
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert res.returncode == 0, res.stderr
    assert out.stat().st_size > 0
    res = subprocess.run(
        [RTTA, "snapshot", str(path), "--focus", "Storey 3", "--size", "96x72", "--out", str(tmp_path / "no.png")],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert res.returncode == 2 and "did you mean Storey" in res.stderr and not (tmp_path / "no.png").exists()


def test_ifc_tree_paths_shared_across_elements_match_each_walked_alone(ifc_file):
    """The read walks each storey up once (tree_path's memo); in any element order, and with
    a cycle of a damaged file (the site aggregated by a storey under it), every element
    gets the path it gets walked alone."""
    import random

    import ifcopenshell

    from rtta.scene.readers.ifc import tree_path

    model = ifcopenshell.open(str(ifc_file[0]))
    for damaged in (False, True):
        if damaged:
            model.by_type("IfcSite")[0].Decomposes[0].RelatingObject = model.by_type("IfcBuildingStorey")[1]
        elements = list(model.by_type("IfcProduct"))
        alone = {e.id(): tree_path(e) for e in elements}
        assert alone[model.by_type("IfcSite")[0].id()] == (("House", "Storey 2") if damaged else ("Demo project",))
        for seed in range(4):
            random.Random(seed).shuffle(elements)
            memo: dict = {}
            assert {e.id(): tree_path(e, memo) for e in elements} == alone


def test_ifc_truncated_is_refused(ifc_file, tmp_path):
    data = ifc_file[0].read_bytes()
    bad = tmp_path / "cut.ifc"
    bad.write_bytes(data[: len(data) * 2 // 3])
    with pytest.raises(RttaError, match="IFC file is truncated"):
        load_scene(bad)


@pytest.mark.parametrize(
    "suffix,content,says",
    [
        (".step", b"", "file is empty"),
        (".step", b"glTF\x02\x00\x00\x00" + bytes(40), "not a STEP file"),
        (".stp", b"ISO-10303-21;\nHEADER;\nENDSEC;\nDATA;\n#1=PRODUCT('a','a','',(#2));\n", "STEP file is truncated"),
        (".step", b"ISO-10303-21;\nHEADER;\nENDSEC;\nDATA;\nENDSEC;\nEND-ISO-10303-21;\n", "cannot read STEP file"),
        (
            ".step",
            b"ISO-10303-21;\nDATA;\n#1=DOCUMENT_FILE('/etc/passwd','',$,#2,'',$);\nENDSEC;\nEND-ISO-10303-21;\n",
            "outside the file's folder",
        ),
        (".ifc", b"solid x\nendsolid x\n", "not an IFC file"),
        (".ifc", b"ISO-10303-21;\nHEADER;\nENDSEC;\nDATA;\nENDSEC;\nEND-ISO-10303-21;\n", "cannot read IFC file"),
    ],
)
def test_bad_assembly_files_one_line_exit_2(tmp_path, suffix, content, says):
    path = tmp_path / f"bad{suffix}"
    path.write_bytes(content)
    res = subprocess.run(
        [RTTA, "snapshot", str(path), "--size", "64x48", "--out", str(tmp_path / "o.png")],
        capture_output=True,
        text=True,
        timeout=120,
    )
    lines = [x for x in res.stderr.splitlines() if x.strip()]
    assert res.returncode == 2 and len(lines) == 1, res.stderr
    assert lines[0].startswith(f"rtta: error: {path}: ") and says in lines[0] and "Traceback" not in res.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == [path.name]


def test_missing_extra_names_it(step_file, monkeypatch):
    monkeypatch.setitem(sys.modules, "cascadio", None)  # as if rtta[cad] were not installed
    with pytest.raises(RttaError, match=r"needs cascadio: pip install 'rtta\[cad\]'"):
        load_scene(step_file)


@pytest.mark.skipif(not (SHARED / "box_sides.STEP").exists(), reason="../shared/data/box_sides.STEP not present")
def test_real_step_assembly():
    s = load_scene(SHARED / "box_sides.STEP")
    assert s.count == 10 and s.unit == "in" and s.up_axis == "z"
    assert {"box_base", "box_top", "side_long", "gusset"} <= set(s.names)
    assert all(s.path_of(i) == ("box_sides",) for i in range(s.count))
    size = s.bounds[1] - s.bounds[0]
    assert 5 < size.max() < 10  # inches (the file's unit), not metres
