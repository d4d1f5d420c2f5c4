"""Saved views (issue 45): `rtta snapshot --save-view` writes a versioned JSON view that
`--view-file` renders again byte for byte; malformed files are one error line and exit 2."""

from __future__ import annotations

import json

import pytest

from rtta.cli.main import main
from rtta.renderer.view_file import VERSION, parse_view, read_view

MODES = ("std", "sprites", "transparent", "ghosted", "ghosted-ao")
SET = ["--focus", "piston_1", "caliper", "--hide", "dust_shield", "lug_nut_2", "--opacity", "rotor=0.35", "bracket=0.6"]


def _snap(tmp_path, name: str, *args: str) -> bytes:
    out = tmp_path / name
    assert main(["snapshot", "--size", "160x120", "--out", str(out), *args]) == 0
    return out.read_bytes()


@pytest.mark.parametrize("mode", MODES)
def test_a_saved_view_renders_byte_identical(tmp_path, gl, mode):
    view = tmp_path / "view.json"
    first = _snap(tmp_path, "a.png", "--mode", mode, *SET, "--camera", "60,20", "--save-view", str(view))
    saved = json.loads(view.read_text())
    assert saved["rtta_view"] == VERSION and saved["mode"] == mode and saved["hidden"] == ["dust_shield", "lug_nut_2"]
    assert saved["opacity"] == {"rotor": 0.35, "bracket": 0.6} and saved["focus"] == ["piston_1", "caliper"]
    again = _snap(tmp_path, "b.png", "--view-file", str(view))
    assert again == first
    plain = _snap(tmp_path, "c.png", "--mode", mode, "--camera", "60,20")
    assert plain != first  # the focus, hidden parts and opacities were in the picture


def test_ortho_and_style_are_saved_too(tmp_path, gl):
    view = tmp_path / "view.json"
    args = ["--projection", "ortho", "--view", "iso", "--edge-width", "2", "--halo", "3", "--focus", "hub"]
    first = _snap(tmp_path, "a.png", "--mode", "ghosted-ao", *args, "--save-view", str(view))
    saved = json.loads(view.read_text())
    assert saved["projection"] == "ortho" and saved["style"]["edge_width"] == 2 and saved["style"]["halo"] == 3
    assert _snap(tmp_path, "b.png", "--view-file", str(view)) == first
    rec = tmp_path / "exp"
    assert main(["export", "--size", "160x120", "--out", str(rec), "--view-file", str(view)]) == 0
    meta = json.loads((rec / "records.json").read_text())
    assert meta["camera"]["projection"] == "ortho"


def test_save_view_replaces_only_a_view_file(tmp_path, gl, capsys):
    other = tmp_path / "settings.json"
    other.write_text('{"mine": true}\n')
    assert main(["snapshot", "--size", "64x48", "--out", str(tmp_path / "a.png"), "--save-view", str(other)]) == 2
    assert other.read_text() == '{"mine": true}\n'
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "settings.json: exists and is not an rtta view file" in err[0]
    view = tmp_path / "view.json"
    for camera in ("10,10", "20,10"):  # a view file is replaced by the next
        assert main(["snapshot", "--size", "64x48", "--out", str(tmp_path / "a.png"), "--camera", camera,
                     "--save-view", str(view)]) == 0  # fmt: skip
    assert json.loads(view.read_text())["camera"]["az"] == 20.0


BAD = [
    ("not json", "{nope", "is not a JSON view file"),
    ("not an object", "[1, 2]", "not an rtta view file"),
    ("no version", '{"camera": null}', "not an rtta view file"),
    ("newer", '{"rtta_view": 2}', "view file version 2 is newer than this rtta reads (1): update rtta"),
    ("bad version", '{"rtta_view": "1"}', "rtta_view must be a version number"),
    ("unknown key", '{"rtta_view": 1, "zoom": 2}', "unknown key 'zoom' in a version 1 view file"),
    ("camera key", '{"rtta_view": 1, "camera": {"az": 1}}', "camera: no 'el'"),
    ("nan", '{"rtta_view": 1, "camera": {"az": NaN, "el": 0, "distance": 1, "target": [0,0,0], "fov": 45}}', "NaN"),
    (
        "distance",
        '{"rtta_view": 1, "camera": {"az": 0, "el": 0, "distance": -1, "target": [0,0,0], "fov": 45}}',
        "distance must be in (0, 1e12]",
    ),
    ("target", '{"rtta_view": 1, "camera": {"az": 0, "el": 0, "distance": 1, "target": [0], "fov": 45}}', "target"),
    (  # overflowed the view matrix: a blank picture and "far/near inf/inf"
        "far target",
        '{"rtta_view": 1, "camera": {"az": 0, "el": 0, "distance": 1, "target": [1e300,0,0], "fov": 45}}',
        "each within 1e12",
    ),
    ("mode", '{"rtta_view": 1, "mode": "xray"}', "mode must be one of"),
    ("projection", '{"rtta_view": 1, "projection": "ortho"}', "projection needs a camera"),
    ("focus", '{"rtta_view": 1, "focus": "hub"}', "focus must be a list of object or group names"),
    ("opacity", '{"rtta_view": 1, "opacity": {"hub": 2}}', "opacity must map names to numbers in [0, 1]"),
    ("style key", '{"rtta_view": 1, "style": {"glow": 1}}', "unknown style key 'glow'"),
    ("sections", '{"rtta_view": 1, "sections": [1]}', "sections must be null or an object"),
    ("explode", '{"rtta_view": 1, "explode": {"factor": "far"}}', "explode.factor has the wrong type"),
    ("unknown name", '{"rtta_view": 1, "focus": ["pad_iner"]}', "did you mean pad_inner"),
    ("style value", '{"rtta_view": 1, "style": {"edge_width": 99}}', "--edge-width must be 1..8"),
    ("caps", '{"rtta_view": 1, "sections": {"planes": ["x=0"], "caps": "hatched"}}', "--caps must be one of"),
    ("plane", '{"rtta_view": 1, "sections": {"planes": ["w=0"]}}', "w=0"),
    ("explode factor", '{"rtta_view": 1, "explode": {"factor": 99}}', "explode"),
]


@pytest.mark.parametrize("case,text,says", BAD, ids=[c[0] for c in BAD])
def test_malformed_view_files_are_one_error_line(tmp_path, capsys, gl, case, text, says):
    path = tmp_path / "bad.json"
    path.write_text(text)
    out = tmp_path / "a.png"
    assert main(["snapshot", "--size", "64x48", "--out", str(out), "--view-file", str(path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("rtta: error:") and says in err[0], err
    if case != "unknown name":  # names need the scene: the error names the flag
        assert "bad.json: " in err[0]
    assert not out.exists()


def test_view_file_errors_name_the_file_and_conflicts(tmp_path, capsys, gl):
    missing = tmp_path / "missing.json"
    assert main(["export", "--out", str(tmp_path / "o"), "--view-file", str(missing)]) == 2
    assert "missing.json: cannot read the view file" in capsys.readouterr().err
    view = tmp_path / "v.json"
    view.write_text('{"rtta_view": 1}')
    assert main(["snapshot", "--out", str(tmp_path / "a.png"), "--view-file", str(view), "--camera", "1,2"]) == 2
    assert "--view-file gives the camera: leave out --camera" in capsys.readouterr().err
    assert main(["snapshot", "--out", str(tmp_path / "a.png"), "--view-file", str(view), "--save-view", str(view)]) == 2
    assert "is an input of this run" in capsys.readouterr().err


def test_version_one_round_trips_and_fills_the_slots():
    doc = {
        "rtta_view": 1,
        "camera": {"az": 1.5, "el": -2.0, "distance": 3.25, "target": [0.1, 0.2, 0.3], "fov": 30.0},
        "projection": "ortho",
        "sections": {"planes": ["x=0.5"], "caps": "hatch", "scope": "all"},
        "explode": {"factor": 0.5, "scope": "focus"},
    }
    view = parse_view(doc)
    again = view.to_json()
    assert again["camera"] == doc["camera"] and again["sections"] == doc["sections"]
    assert again["explode"] == doc["explode"] and again["projection"] == "ortho"
    assert parse_view(json.loads(json.dumps(again))) == view


def test_read_view_refuses_a_huge_file(tmp_path):
    big = tmp_path / "big.json"
    big.write_text('{"rtta_view": 1, "focus": [' + ",".join(['"a"'] * 300_000) + "]}")
    with pytest.raises(Exception, match="not a view file"):
        read_view(big)


def test_sections_and_explode_are_saved_too(tmp_path, gl):
    view = tmp_path / "view.json"
    args = ["--section", "x=0.2", "--caps", "hatch", "--explode", "0.5", "--focus", "hub", "--mode", "ghosted"]
    first = _snap(tmp_path, "a.png", *args, "--save-view", str(view))
    saved = json.loads(view.read_text())
    assert saved["sections"] == {"planes": ["x=0.2"], "caps": "hatch", "scope": "all"}
    assert saved["explode"] == {"factor": 0.5, "scope": "all"}
    assert _snap(tmp_path, "b.png", "--view-file", str(view)) == first
    assert _snap(tmp_path, "c.png", "--focus", "hub", "--mode", "ghosted") != first


def test_dataset_takes_the_projection_and_a_view_file(tmp_path, gl):
    """`rtta dataset --view-file`: one view per scene with the saved camera (the view matrix
    export gives for the same file), projection and hidden parts (not annotated)."""
    view = tmp_path / "view.json"
    saved = ["--camera", "30,20", "--hide", "caliper", "--projection", "ortho", "--save-view", str(view)]
    _snap(tmp_path, "a.png", *saved)
    out = tmp_path / "ds"
    assert main(["dataset", "--out", str(out), "--size", "96x72", "--view-file", str(view), "--no-progress"]) == 0
    doc = json.loads((out / "annotations.json").read_text())
    (image,) = doc["images"]
    assert image["camera"]["projection"] == "ortho"
    names = {c["id"]: c["name"] for c in doc["categories"]}
    assert "caliper" not in {names[a["category_id"]] for a in doc["annotations"]}
    assert main(["export", "--size", "96x72", "--out", str(tmp_path / "exp"), "--view-file", str(view)]) == 0
    rec = json.loads((tmp_path / "exp" / "records.json").read_text())
    assert rec["view"] == image["camera"]["view"] and rec["proj"] == image["camera"]["proj"]
    sampled = tmp_path / "ds2"
    assert main(["dataset", "--out", str(sampled), "--size", "96x72", "--views", "2", "--projection", "ortho"]) == 0
    cams = [i["camera"] for i in json.loads((sampled / "annotations.json").read_text())["images"]]
    assert [c["projection"] for c in cams] == ["ortho", "ortho"] and all(c["proj"][3][3] == 1.0 for c in cams)
