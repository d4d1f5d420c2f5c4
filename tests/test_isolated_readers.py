"""Native readers (STEP, IFC, USD) run in a child process: a reader that crashes or never
ends gives one RttaError (and one CLI line, exit 2), the child is gone afterwards, and
what a reader says or returns comes back unchanged."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest
from assemblies import write_step

from rtta.errors import RttaError
from rtta.scene.loader import load_scene
from rtta.scene.readers import isolated

RTTA = str(Path(sys.executable).with_name("rtta"))

READERS = """
import os, signal, time
from pathlib import Path
from rtta.errors import RttaError
from rtta.scene.readers import Assembly

def crash(path):
    os.kill(os.getpid(), signal.SIGSEGV)

def hang(path):
    Path(path).with_suffix(".pid").write_text(str(os.getpid()))
    while True:
        time.sleep(0.05)

def refuse(path):
    raise RttaError("the reader says no", path)

def fail(path):
    raise KeyError("no such entity #42")

def give(path):
    out = Assembly(unit="mm")
    out.add("part", [[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], [1, 0, 0, 1], ("top",))
    return out
"""


@pytest.fixture
def reader(tmp_path, monkeypatch):
    """A module `readers_<kind>` per behaviour, importable by the child through sys.path."""
    for kind in ("crash", "hang", "refuse", "fail", "give"):
        (tmp_path / f"readers_{kind}.py").write_text(READERS + f"\nread = {kind}\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    target = tmp_path / "part.step"
    target.write_text("anything")
    return target


def test_a_crash_is_one_error(reader):
    with pytest.raises(RttaError, match=r"the LIB reader crashed on this file \(SIGSEGV\)"):
        isolated.read("readers_crash", reader, "LIB")


def test_a_hang_is_stopped_at_the_limit_and_the_child_killed(reader, monkeypatch):
    monkeypatch.setenv(isolated.ENV, "1.5")
    t = time.perf_counter()
    with pytest.raises(RttaError, match=r"did not finish within 2 s .*RTTA_READER_TIMEOUT"):
        isolated.read("readers_hang", reader, "LIB")
    assert time.perf_counter() - t < 30
    pid = int(reader.with_suffix(".pid").read_text())
    with pytest.raises(ProcessLookupError):
        os.kill(pid, 0)  # killed and reaped: no such process


def test_what_the_reader_says_comes_back(reader):
    with pytest.raises(RttaError, match="^.*part.step: the reader says no$"):
        isolated.read("readers_refuse", reader, "LIB")
    with pytest.raises(RttaError, match=r"the LIB reader failed \(no such entity #42\)$"):
        isolated.read("readers_fail", reader, "LIB")
    asm = isolated.read("readers_give", reader, "LIB")
    assert asm.names == ["part"] and asm.unit == "mm" and asm.paths == [("top",)]
    assert asm.vertices[0].shape == (3, 3) and asm.faces[0].tolist() == [[0, 1, 2]]


def test_time_limit_grows_with_the_file_and_the_variable_overrides_it(tmp_path, monkeypatch):
    monkeypatch.delenv(isolated.ENV, raising=False)
    small, big = tmp_path / "a.ifc", tmp_path / "b.ifc"
    small.write_bytes(b"x")
    big.write_bytes(b"x" * 2_000_000)
    assert isolated.time_limit(small) == pytest.approx(isolated.BASE_S, abs=0.1)
    assert isolated.time_limit(big) == pytest.approx(isolated.BASE_S + 2 * isolated.PER_MB_S, abs=0.1)
    for bad in ("soon", "-3", "0", "nan"):
        monkeypatch.setenv(isolated.ENV, bad)
        assert isolated.time_limit(small) == pytest.approx(isolated.BASE_S, abs=0.1)
    monkeypatch.setenv(isolated.ENV, "7")
    assert isolated.time_limit(big) == 7


def test_step_is_read_in_a_child_and_the_cli_says_a_crash_in_one_line(tmp_path, monkeypatch):
    path = tmp_path / "engine.step"
    write_step(path)
    seen = []
    real = isolated.read
    monkeypatch.setattr(isolated, "read", lambda module, p, lib: seen.append(module) or real(module, p, lib))
    assert load_scene(path).count > 0 and seen == ["rtta.scene.readers.step"]
    # the CLI, with a reader that crashes in place of OpenCASCADE's
    (tmp_path / "sitecustomize.py").write_text(
        "import rtta.scene.readers.step as s, os, signal\ns.read = lambda path: os.kill(os.getpid(), signal.SIGSEGV)\n"
    )
    env = dict(os.environ, PYTHONPATH=str(tmp_path))
    res = subprocess.run(
        [RTTA, "snapshot", str(path), "--size", "64x48", "--out", str(tmp_path / "o.png")],
        capture_output=True,
        text=True,
        timeout=120,
        env=env,
    )
    lines = [x for x in res.stderr.splitlines() if x.strip()]
    assert res.returncode == 2 and len(lines) == 1, res.stderr
    assert lines[0] == (
        f"rtta: error: {path}: the OpenCASCADE (cascadio) reader crashed on this file (SIGSEGV); it is probably damaged"
    )
    assert not (tmp_path / "o.png").exists()
