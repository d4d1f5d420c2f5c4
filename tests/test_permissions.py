"""Outputs this user may not write and inputs it may not read: one line `rtta: error: <file>:
<reason>`, exit 2, before the work, with nothing replaced and nothing left behind; a cache
that cannot be written costs no message. The suite used to run as root only, where no
permission is ever refused: as root these commands run as `nobody` (setpriv), as another
user they run as that user. (Other unwritable outputs: test_bad_output.py.)"""

from __future__ import annotations

import errno
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pytest
from bad_gltf import box_doc, glb, png

from rtta.cli.main import main

NOBODY = 65534
RTTA_DOC = {"info": {"description": "rtta dataset"}, "images": [], "annotations": [], "categories": []}


@pytest.fixture
def space():
    """A folder `work` that the user the commands run as may write in, beside its `home`."""
    root = Path(tempfile.mkdtemp(prefix="rtta-permissions-"))
    for folder in (root, root / "home", root / "work"):
        folder.mkdir(exist_ok=True)
        os.chmod(folder, 0o755)
        if os.geteuid() == 0:
            os.chown(folder, NOBODY, NOBODY)
    yield root / "work"
    for path, folders, _ in os.walk(root):  # folders the test locked, opened again to remove them
        for name in folders:
            if not os.path.islink(os.path.join(path, name)):
                os.chmod(os.path.join(path, name), 0o700)
    shutil.rmtree(root)


@pytest.fixture(scope="module")
def as_user():
    """run(args, cwd, env=None): `python -m rtta ARGS` as a user that permissions bind."""
    prefix: list[str] = []
    if os.geteuid() == 0:
        if shutil.which("setpriv") is None:
            pytest.skip("root without setpriv (util-linux): no unprivileged user to run rtta as")
        prefix = ["setpriv", f"--reuid={NOBODY}", f"--regid={NOBODY}", "--clear-groups"]
        probe = subprocess.run([*prefix, sys.executable, "-c", "import rtta"], capture_output=True, timeout=120)
        if probe.returncode:
            pytest.skip("this Python cannot run as nobody (its files are readable by root alone)")

    def run(args, cwd: Path, env: dict | None = None) -> subprocess.CompletedProcess:
        home = cwd.parent / "home"
        return subprocess.run(
            [*prefix, sys.executable, "-m", "rtta", *map(str, args)],
            cwd=cwd,
            capture_output=True,
            text=True,
            timeout=120,
            env={**os.environ, "HOME": str(home), "RTTA_CACHE_DIR": str(home / "cache"), **(env or {})},
        )

    return run


def _tree(folder: Path) -> dict:
    """Every entry under `folder` (hidden ones too): its kind, mode and inode, and a file's
    size and mtime (a folder's change as temporaries come and go)."""
    out = {}
    for path, folders, files in os.walk(folder):
        for name in folders + files:
            st = os.lstat(os.path.join(path, name))
            file = name in files
            out[os.path.relpath(os.path.join(path, name), folder)] = (
                st.st_mode,
                st.st_ino,
                st.st_size if file else 0,
                st.st_mtime_ns if file else 0,
            )
    return out


def _own(work: Path) -> None:
    """What the test made in `work` becomes the files of the user the commands run as."""
    if os.geteuid() == 0:
        for path in work.rglob("*"):
            os.chown(path, NOBODY, NOBODY, follow_symlinks=False)


def _one_error(proc: subprocess.CompletedProcess, needle: str) -> bool:
    lines = [line for line in proc.stderr.splitlines() if line.strip()]
    return proc.returncode == 2 and len(lines) == 1 and lines[0].startswith("rtta: error: ") and needle in lines[0]


def _locked_outputs(work: Path) -> None:
    """ro/ (read-only), old.png (read-only), file.txt, shots/ (ghosted.png read-only),
    notes.json (a user's JSON), export_ro/ and export_files/ (rtta exports, read-only as a
    folder or file by file), dsro/ (a dataset, read-only), ds/annotations.json and
    merged.json (rtta annotations, the latter read-only)."""
    (work / "ro").mkdir()
    (work / "old.png").write_bytes(png())
    (work / "file.txt").write_text("mine")
    (work / "shots").mkdir()
    (work / "shots" / "ghosted.png").write_bytes(png())
    (work / "notes.json").write_text('{"mine": 1}')
    for name in ("export_ro", "export_files"):
        (work / name).mkdir()
        (work / name / "records.json").write_text("{}")
        (work / name / "std_color.png").write_bytes(png())
    (work / "dsro").mkdir()
    (work / "dsro" / "dataset.json").write_text("{}")
    (work / "ds").mkdir()
    (work / "ds" / "annotations.json").write_text(json.dumps(RTTA_DOC))
    (work / "merged.json").write_text(json.dumps(RTTA_DOC))
    _own(work)
    for path in ("old.png", "shots/ghosted.png", "export_files/records.json", "merged.json"):
        os.chmod(work / path, 0o444)
    for path in ("ro", "export_ro", "dsro"):
        os.chmod(work / path, 0o555)


@pytest.mark.parametrize(
    "args,needle",
    [  # missing.*: loading would fail first, so these outputs are refused before the work
        (["snapshot", "missing.glb", "--out", "ro/x.png"], "ro/x.png: cannot write (Permission denied)"),
        (["snapshot", "missing.glb", "--out", "old.png"], "old.png: is read-only; --out will not replace it"),
        (["snapshot", "missing.glb", "--out", "file.txt/x.png"], "file.txt: is not a folder"),
        (["snapshot", "missing.glb", "--all-modes", "shots"], "shots/ghosted.png: is read-only"),
        (["snapshot", "missing.glb", "--all-modes", "ro/new"], "ro/new: cannot write (Permission denied)"),
        (["snapshot", "missing.glb", "--out", "x.png", "--save-view", "ro/v.json"], "ro/v.json: cannot write"),
        (["snapshot", "missing.glb", "--out", "x.png", "--save-view", "notes.json"], "notes.json: exists and is not"),
        (["export", "missing.glb", "--out", "export_ro"], "export_ro: is read-only; --out will not replace it"),
        (["export", "missing.glb", "--out", "export_files"], "export_files: holds read-only files (records.json)"),
        (["ldi", "missing.stl", "--points", "p.npy", "--out", "ro/x.npy"], "ro/x.npy: cannot write"),
        (["bench", "formats", "missing.stl", "--json", "ro/b.json"], "ro/b.json: cannot write (Permission denied)"),
        (["dataset", "merge", "ds", "--out", "merged.json"], "merged.json: is read-only; --out will not"),
        (["dataset", "--no-progress", "--out", "dsro"], "dsro: cannot write (Permission denied)"),
    ],
)
def test_outputs_this_user_may_not_write_are_refused_first(space, as_user, args, needle):
    _locked_outputs(space)
    before = _tree(space)
    proc = as_user(args, space)
    assert _one_error(proc, needle), proc.stderr
    assert _tree(space) == before


def test_inputs_this_user_may_not_read_say_so(space, as_user):
    """Each reader says the file cannot be read and why (no `[Errno 13]`, no `not a .npy
    array`, no empty folder), and a dataset of an unreadable scene leaves no folder behind."""
    (space / "a.glb").write_bytes(glb(*box_doc()))
    np.save(space / "p.npy", np.zeros((2, 3)))
    (space / "cams.json").write_text(json.dumps([{"orbit": [30, 20, 2], "fov": 45}]))
    (space / "scenes").mkdir()
    (space / "scenes" / "b.glb").write_bytes(glb(*box_doc()))
    (space / "ds").mkdir()
    (space / "ds" / "annotations.json").write_text(json.dumps(RTTA_DOC))
    _own(space)
    for path in ("a.glb", "p.npy", "cams.json", "scenes", "ds/annotations.json"):
        os.chmod(space / path, 0)
    before = _tree(space)
    for args, needle in (
        (["info", "a.glb"], "a.glb: cannot read the scene file (Permission denied)"),
        (["ldi", "shape:box", "--points", "p.npy", "--out", "o.npy"], "p.npy: cannot read the points file (Perm"),
        (["dataset", "--cameras", "cams.json", "--out", "o"], "cams.json: cannot read cameras (Permission denied)"),
        (["dataset", "scenes", "--out", "o"], "scenes: cannot list the folder (Permission denied)"),
        (["dataset", "a.glb", "--no-progress", "--out", "o"], "a.glb: cannot read the scene file (Permission denied)"),
        (["dataset", "merge", "ds/annotations.json", "--out", "m.json"], "cannot read annotations (Permission denied)"),
        (["bench", "formats", "a.glb"], "rtta: error: a.glb: cannot read the scene file (Permission denied)"),
    ):
        proc = as_user(args, space)
        assert _one_error(proc, needle), (args, proc.stderr)
    assert _tree(space) == before


def test_the_scene_cache_never_hands_back_a_file_the_user_may_not_read(space, as_user):
    (space / "a.glb").write_bytes(glb(*box_doc()))
    hour_ago = time.time() - 3600  # older than the cache's racy window
    os.utime(space / "a.glb", (hour_ago, hour_ago))
    _own(space)
    assert as_user(["info", "a.glb"], space).returncode == 0
    assert list((space.parent / "home" / "cache").glob("*.scene"))  # it was cached
    os.chmod(space / "a.glb", 0)
    proc = as_user(["info", "a.glb"], space)
    assert _one_error(proc, "a.glb: cannot read the scene file (Permission denied)"), proc.stderr


def test_an_unwritable_shader_cache_is_silent(tmp_path):
    """Mesa prints a line of its own where its shader cache folder cannot be made: rtta turns
    that cache off instead (as a scene cache that cannot be written is no message)."""
    (tmp_path / "not_a_folder").write_text("mine")
    env = {k: v for k, v in os.environ.items() if not k.startswith(("MESA_SHADER_CACHE", "MESA_GLSL_CACHE"))}
    env["XDG_CACHE_HOME"] = str(tmp_path / "not_a_folder")
    proc = subprocess.run(
        [sys.executable, "-m", "rtta", "snapshot", "--size", "48x36", "--mode", "std", "--out", tmp_path / "a.png"],
        capture_output=True,
        text=True,
        timeout=120,
        env=env,
        cwd=tmp_path,  # not a checkout's root, whose rtta/ would shadow the installed package
    )
    assert proc.returncode == 0 and all(line.startswith("rtta: ") for line in proc.stderr.splitlines()), proc.stderr


def _failing_png_save(monkeypatch, nth: int) -> None:
    """The `nth` PNG PIL saves fails as on a full disk."""
    from PIL import Image

    real, calls = Image.Image.save, []

    def save(self, fp, *args, **kwargs):
        calls.append(fp)
        if len(calls) == nth:
            raise OSError(errno.ENOSPC, "No space left on device")
        return real(self, fp, *args, **kwargs)

    monkeypatch.setattr(Image.Image, "save", save)


def test_snapshot_outputs_are_written_all_or_none(tmp_path, monkeypatch, capsys, gl):
    """A full disk at the third of --all-modes' PNGs: no new file, no folder, the old
    files whole (not the first two modes written and the folder left)."""
    (tmp_path / "shots").mkdir()
    (tmp_path / "shots" / "std.png").write_bytes(b"old")
    before = _tree(tmp_path)
    for out in ("new", "shots"):
        _failing_png_save(monkeypatch, 3)
        code = main(["snapshot", "--size", "48x36", "--all-modes", str(tmp_path / out)])
        monkeypatch.undo()
        assert code == 2 and "No space left on device" in capsys.readouterr().err
        assert _tree(tmp_path) == before, out


def test_an_export_folder_gets_the_users_mode(tmp_path, capsys, gl):
    """An export is readable by others as any folder the user makes (it was 0700)."""
    assert main(["export", "--size", "48x36", "--out", str(tmp_path / "e")]) == 0
    umask = os.umask(0)
    os.umask(umask)
    assert os.stat(tmp_path / "e").st_mode & 0o777 == 0o777 & ~umask


def test_a_view_folder_that_cannot_be_made_is_named(tmp_path, monkeypatch):
    """The error names the view's folder, never the hidden temporary beside it."""
    from rtta.dataset.view import View, write_view
    from rtta.errors import RttaError

    def refuse(prefix="", dir=None, **_):
        raise PermissionError(errno.EACCES, "Permission denied", os.path.join(dir, f"{prefix}x1y2"))

    monkeypatch.setattr(tempfile, "mkdtemp", refuse)
    flat = {k: np.zeros(0) for k in ("oids", "rects", "amodal", "visible", "nearest")}
    image = {"rgb": np.zeros((2, 2, 3), np.uint8), "depth": np.zeros((2, 2), np.float32), "ids": np.zeros((2, 2), int)}
    view = View(**image, **flat)
    with pytest.raises(RttaError) as caught:
        write_view(view, tmp_path / "images" / "a" / "00001", "png", 1.0)
    assert caught.value.path == str(tmp_path / "images" / "a" / "00001") and "Permission denied" in str(caught.value)


def test_bench_json_on_a_full_disk_leaves_no_partial_file(tmp_path, monkeypatch, capsys):
    stl = tmp_path / "box.stl"
    import trimesh

    trimesh.creation.box().export(stl)
    real = Path.write_text

    def write_text(self, text, *args, **kwargs):
        if self.name.startswith((".b.json", "b.json")):
            real(self, text[:20], *args, **kwargs)
            raise OSError(errno.ENOSPC, "No space left on device")
        return real(self, text, *args, **kwargs)

    monkeypatch.setattr(Path, "write_text", write_text)
    assert main(["bench", "formats", str(stl), "--json", str(tmp_path / "b.json")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"rtta: error: {tmp_path / 'b.json'}: cannot write (No space left on device)"], err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["box.stl"]


def test_bench_formats_names_a_missing_file(tmp_path, capsys):
    """Not trimesh's ValueError taken for a bug in rtta."""
    assert main(["bench", "formats", str(tmp_path / "missing.stl")]) == 2
    assert capsys.readouterr().err == f"rtta: error: {tmp_path / 'missing.stl'}: no such file\n"
