"""Every CLI command on the bad-input corpus (tests/bad_inputs.py): one error line naming
the file and the problem, exit 2, no traceback, nothing written outside --out and an
existing output left as it was; the cases that load do so with their warning."""

from __future__ import annotations

import hashlib
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from bad_inputs import make_corpus

from rtta.cli.main import main

RTTA = str(Path(sys.executable).with_name("rtta"))
SENTINEL = b"the user's file: must survive"


@pytest.fixture(scope="module")
def corpus(tmp_path_factory):
    folder = tmp_path_factory.mktemp("corpus")
    return folder, make_corpus(folder)


def _tree(root: Path) -> dict[str, str]:
    """Every file under root with a hash of its contents."""
    out = {}
    for p in sorted(root.rglob("*")):
        if p.is_file() and not p.is_symlink():
            try:
                out[str(p.relative_to(root))] = hashlib.sha1(p.read_bytes()).hexdigest()
            except PermissionError:
                out[str(p.relative_to(root))] = "unreadable"
    return out


def _commands(path: Path, out: Path) -> dict[str, list[str]]:
    return {
        "info": ["info", str(path)],
        "snapshot": ["snapshot", str(path), "--size", "64x48", "--out", str(out / "shot.png")],
        "export": ["export", str(path), "--size", "64x48", "--out", str(out / "export")],
        "ldi": ["ldi", str(path), "--points", str(out / "points.npy"), "--out", str(out / "inside.npy")],
    }


def test_corpus_is_large_enough(corpus):
    _, cases = corpus
    assert len(cases) >= 30
    assert sum(c.error for c in cases) >= 30


@pytest.mark.parametrize("command", ["info", "snapshot", "export", "ldi"])
def test_every_case_through_the_cli(corpus, command, tmp_path, capsys, monkeypatch, gl):
    monkeypatch.setenv("RTTA_MEMORY_LIMIT_MB", "1")      # the too-large cases exceed it
    folder, cases = corpus
    problems = []
    for case in cases:
        out = tmp_path / case.name
        out.mkdir()
        (out / "shot.png").write_bytes(SENTINEL)          # outputs the user already had
        (out / "export").mkdir()
        (out / "export" / "keep.txt").write_bytes(SENTINEL)
        (out / "inside.npy").write_bytes(SENTINEL)
        np.save(out / "points.npy", np.zeros((4, 3)))
        before, corpus_before = _tree(out), _tree(folder)
        code = main(_commands(case.path, out)[command])
        err = capsys.readouterr().err
        lines = [line for line in err.splitlines() if line.strip()]
        where = f"{case.name} ({command})"
        if _tree(folder) != corpus_before:
            problems.append(f"{where}: the input folder changed")
        if "Traceback" in err:
            problems.append(f"{where}: traceback")
        if case.error:
            ok = (code == 2 and len(lines) == 1 and lines[0].startswith(f"rtta: error: {case.path}: ")
                  and case.says.lower() in lines[0].lower())
            if not ok:
                problems.append(f"{where}: exit {code}, stderr {err!r}")
            if _tree(out) != before:
                problems.append(f"{where}: an output was written or changed on error")
        elif command == "ldi" and code == 2:      # loads, but is no closed mesh: refused the same way
            if not (len(lines) == 1 and lines[0].startswith(f"rtta: error: {case.path}: ")
                    and "not a closed mesh" in lines[0]) or _tree(out) != before:
                problems.append(f"{where}: exit {code}, stderr {err!r}")
        else:
            if code != 0 or (case.says and not any(case.says in line and "warning" in line for line in lines)):
                problems.append(f"{where}: exit {code}, stderr {err!r}")
            if command == "snapshot" and (out / "shot.png").read_bytes() == SENTINEL:
                problems.append(f"{where}: snapshot not written")
    assert not problems, "\n".join(problems)


@pytest.mark.parametrize("name", ["truncated.glb", "buffer_outside_folder.gltf", "stl_claims_2g_triangles.stl",
                                  "nan_vertices.obj"])
def test_real_process_one_line_exit_2(corpus, name, tmp_path):
    """The installed `rtta` executable itself: exit status and stderr as a user sees them."""
    _, cases = corpus
    case = next(c for c in cases if c.name == name)
    proc = subprocess.run([RTTA, "snapshot", str(case.path), "--out", str(tmp_path / "x.png")],
                          capture_output=True, text=True, timeout=120, env={"RTTA_MEMORY_LIMIT_MB": "1",
                                                                            "PATH": "/usr/bin:/bin"})
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.count("\n") == 1 and proc.stderr.startswith("rtta: error: ") and case.path.name in proc.stderr
    assert "Traceback" not in proc.stderr and proc.stdout == ""
    assert list(tmp_path.iterdir()) == []


def test_loaded_scenes_are_what_the_file_says(corpus):
    from rtta.scene.loader import load_scene

    _, cases = corpus
    by_name = {c.name: c for c in cases}
    dup = load_scene(by_name["duplicate_names.glb"].path)
    assert dup.count == 3 and len(set(dup.names)) == 3
    objs = load_scene(by_name["non_utf8_names.obj"].path)
    assert objs.count == 2 and all(name.startswith(("caf", "na")) for name in objs.names)
    tex = load_scene(by_name["missing_texture.gltf"].path)
    assert len(tex.warnings) == 1 and "no_such_texture.png" in tex.warnings[0]
    assert tex.colors[0][:3] == pytest.approx([0.2, 0.6, 0.9], abs=1 / 255)   # its material colour (8-bit)


def test_closed_pipe_is_not_a_traceback():
    """`rtta info | head`: a reader that leaves early ends the command quietly (exit 1, the
    usual status for a broken pipe), not with a BrokenPipeError traceback."""
    proc = subprocess.Popen([RTTA, "info"], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    proc.stdout.close()                 # gone before the first line is written
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 1 and b"Traceback" not in err and err == b"", err.decode()
