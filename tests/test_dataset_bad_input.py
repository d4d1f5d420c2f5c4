"""`rtta dataset` on bad input: one line naming the file and the problem, exit 2; an
unreadable scene among several stops the run (default) or is skipped (--keep-going); nothing
written is ever corrupted, and no folder or file that is not rtta's is written into."""

from __future__ import annotations

import pytest
from dataset_checks import read_json

from rtta.cli.main import main
from rtta.scene.generators.demo import demo_path

pytest.importorskip("pycocotools")
SMALL = ["--size", "120x90", "--no-progress", "--views", "2"]


def _one_error(capsys, needle: str) -> None:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("rtta: error: ") and needle in err[0], err


@pytest.fixture
def three(tmp_path):
    """good.glb, broken.glb (truncated) and last.glb, in that order."""
    good = demo_path().read_bytes()
    (tmp_path / "a_good.glb").write_bytes(good)
    (tmp_path / "b_broken.glb").write_bytes(good[:300])
    (tmp_path / "c_last.glb").write_bytes(good)
    return tmp_path


def test_unreadable_scene_stops_the_run(three, capsys, ctx):
    out = three / "out"
    scenes = [str(three / n) for n in ("a_good.glb", "b_broken.glb", "c_last.glb")]
    assert main(["dataset", *scenes, "--out", str(out), *SMALL]) == 2
    _one_error(capsys, "b_broken.glb: GLB file is truncated")
    assert not (out / "annotations.json").exists() and not (out / "images/c_last").exists()
    parts = sorted(p.name for p in (out / "parts/a_good").iterdir())
    assert parts == ["00000.json", "00001.json"]  # what was done before stays done, whole
    assert main(["dataset", *scenes, "--out", str(out), "--keep-going", *SMALL]) == 2
    _one_error(capsys, "b_broken.glb: GLB file is truncated")
    doc = read_json(out / "annotations.json")
    assert sorted({im["scene"] for im in doc["images"]}) == ["a_good", "c_last"] and len(doc["images"]) == 4
    assert {im["id"] for im in doc["images"]} == {1, 2, 5, 6}  # ids do not depend on what failed


def test_missing_scene_with_keep_going(three, capsys):
    out = three / "out"
    assert (
        main(["dataset", str(three / "a_good.glb"), str(three / "nope.glb"), "--out", str(out), "--keep-going", *SMALL])
        == 2
    )
    _one_error(capsys, "nope.glb: no such file")
    assert len(read_json(out / "annotations.json")["images"]) == 2


def test_folder_that_is_not_a_dataset_is_left_alone(tmp_path, capsys):
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("mine")
    assert main(["dataset", "--out", str(mine), *SMALL]) == 2
    _one_error(capsys, "holds no rtta dataset")
    assert [p.name for p in mine.iterdir()] == ["notes.txt"]
    (tmp_path / "file").write_text("x")
    assert main(["dataset", "--out", str(tmp_path / "file"), *SMALL]) == 2
    _one_error(capsys, "exists and is not a directory")


def test_other_settings_do_not_resume(tmp_path, capsys):
    out = tmp_path / "ds"
    assert main(["dataset", "--out", str(out), *SMALL]) == 0
    before = {p: p.read_bytes() for p in out.rglob("*") if p.is_file()}
    capsys.readouterr()
    assert main(["dataset", "--out", str(out), *SMALL, "--seed", "5"]) == 2
    _one_error(capsys, "other settings (seed)")
    assert {p: p.read_bytes() for p in out.rglob("*") if p.is_file()} == before
    assert main(["dataset", "--out", str(out), *SMALL]) == 0  # the same settings resume: nothing to do
    assert "0 views rendered, 2 already complete" in capsys.readouterr().out


@pytest.mark.parametrize(
    "args,needle",
    [
        (["--size", "12by4"], "--size expects WxH"),
        (["--shard", "2/2"], "--shard expects I/N"),
        (["--fov", "0,200"], "--fov expects LO,HI"),
        (["--elevation", "80,10"], "--elevation expects LO,HI"),
        (["--views", "0"], "--views must be"),
        (["--cameras", "cams.json"], "cams.json: camera 1: expected"),
        (["--cameras", "nothing.json"], "nothing.json: cannot read cameras"),
        (["--category-by", "ifc-class"], "no object is named by an IFC class"),
        (["*.nothing"], "*.nothing: matches no file"),
        (["empty_folder"], "empty_folder: folder holds no scene file"),
    ],
)
def test_bad_arguments(tmp_path, capsys, monkeypatch, args, needle):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "cams.json").write_text('[{"orbit": [0, 10, 2]}, {"orbit": [0, 10]}]')
    (tmp_path / "empty_folder").mkdir()
    assert main(["dataset", "--out", "o", *SMALL, *args]) == 2
    _one_error(capsys, needle)
    assert not (tmp_path / "o" / "annotations.json").exists()


def test_merge_never_replaces_an_input_or_a_users_file(tmp_path, capsys):
    out = tmp_path / "ds"
    assert main(["dataset", "--out", str(out), *SMALL]) == 0
    capsys.readouterr()
    ann = out / "annotations.json"
    before = ann.read_bytes()
    assert main(["dataset", "merge", str(ann), "--out", str(ann)]) == 2
    _one_error(capsys, "--out is one of the inputs")
    mine = tmp_path / "mine.json"
    mine.write_text('{"mine": true}')
    assert main(["dataset", "merge", str(out), "--out", str(mine)]) == 2
    _one_error(capsys, "not an annotations file written by rtta")
    assert mine.read_text() == '{"mine": true}' and ann.read_bytes() == before
    assert main(["dataset", "merge", str(tmp_path / "none"), "--out", str(tmp_path / "m.json")]) == 2
    _one_error(capsys, "none: no such file or folder")
    assert main(["dataset", "merge", str(out), "--out", str(tmp_path / "m.json")]) == 0
    assert read_json(tmp_path / "m.json")["images"][0]["file_name"].startswith("ds/images/")


def test_shards_starting_together_see_each_others_marker_on_its_way(tmp_path):
    """Two shards into a new folder: the second finds the first's dataset.json temporary
    (outputs.atomic_write's) before the marker and must not take it for a foreign file; a
    file that only looks like one (a folder of that name) still counts."""
    from rtta.dataset.options import prepare_out
    from rtta.errors import RttaError

    out = tmp_path / "d"
    out.mkdir()
    (out / ".dataset.json.k2j9x_.json").write_text("{")  # the other shard, mid-write
    prepare_out(out, {"views": 3})
    assert (out / "dataset.json").is_file()
    other = tmp_path / "e"
    (other / ".dataset.json.x.json").mkdir(parents=True)
    with pytest.raises(RttaError, match="holds no rtta dataset"):
        prepare_out(other, {"views": 3})


def test_a_marker_that_lands_while_the_folder_is_read(tmp_path, monkeypatch):
    """The other shard's dataset.json lands in place between this shard's look at the folder
    and its look for the marker: the folder is listed first, so it is found."""
    import json
    from pathlib import Path

    from rtta.dataset.options import prepare_out

    out = tmp_path / "d"
    out.mkdir()
    settings = {"views": 3}
    real, landed = Path.iterdir, []

    def listing(self):
        if self == out and not landed:
            landed.append(True)
            monkeypatch.setattr(Path, "iterdir", real)
            prepare_out(out, settings)  # the other shard, just then
            (out / "parts").mkdir()
        return real(self)

    monkeypatch.setattr(Path, "iterdir", listing)
    prepare_out(out, settings)
    assert json.loads((out / "dataset.json").read_text())["settings"] == settings
