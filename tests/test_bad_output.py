"""Outputs and messages (issue 26): an output never replaces an input of the same run or a
folder rtta did not write; what cannot be written is one line; bad flag values are one line,
never a usage block or a RuntimeWarning. (Interruptions: test_interrupts.py.)"""

from __future__ import annotations

import json
import os
import resource
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import trimesh
from bad_gltf import _bomb_png, box_doc, glb, png

from rtta.cli.main import main

RTTA = str(Path(sys.executable).with_name("rtta"))
DEMO_ARGS = ["--size", "48x36"]
GRID = Path(__file__).resolve().parents[1] / "assets" / "projector_grid.png"  # an image that exists


def _run(args, cwd=None, env=None, **kw) -> subprocess.CompletedProcess:
    return subprocess.run(
        [RTTA, *map(str, args)],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=120,
        env={**os.environ, **(env or {})},
        **kw,
    )


def _one_line(proc_or_err: subprocess.CompletedProcess | str, needle: str = "") -> bool:
    err = proc_or_err if isinstance(proc_or_err, str) else proc_or_err.stderr
    lines = [line for line in err.splitlines() if line.strip()]
    return (
        len(lines) == 1
        and lines[0].startswith("rtta: error: ")
        and needle.lower() in lines[0].lower()
        and "Traceback" not in err
        and "usage:" not in err
        and "Warning" not in err
    )


def _snapshot(tree: Path) -> dict[str, bytes]:
    return {str(p.relative_to(tree)): p.read_bytes() for p in sorted(tree.rglob("*")) if p.is_file()}


@pytest.fixture
def model(tmp_path) -> Path:
    """model/a.glb (the box), model/notes.txt, model/tex.png, model/points.npy, model/cube.stl."""
    folder = tmp_path / "model"
    folder.mkdir()
    (folder / "a.glb").write_bytes(glb(*box_doc()))
    (folder / "notes.txt").write_text("the user's notes")
    (folder / "tex.png").write_bytes(png((8, 8)))
    np.save(folder / "points.npy", np.zeros((5, 3)))
    trimesh.creation.box().export(folder / "cube.stl")
    return folder


# ---- data loss ---------------------------------------------------------------------------
def test_export_never_replaces_a_folder_holding_the_scene(model, tmp_path):
    before = _snapshot(tmp_path)
    for args, cwd in (
        (["export", model / "a.glb", "--out", model], None),
        (["export", "a.glb", "--out", "."], model),
        (["export", "model/a.glb", "--out", "."], tmp_path),
        (["export", "a.glb", "--out", ".."], model),
    ):
        proc = _run([*args, *DEMO_ARGS], cwd=cwd)
        assert proc.returncode == 2 and _one_line(proc), (args, proc.stderr)
    assert _snapshot(tmp_path) == before


def test_outputs_never_replace_an_input(model, tmp_path):
    """ldi --out the points or the mesh, snapshot --out the projector image (also through a
    hard or symbolic link, and as one of --all-modes' files): refused, inputs unchanged."""
    os.link(model / "points.npy", tmp_path / "hard.npy")
    os.symlink(model / "tex.png", tmp_path / "soft.png")
    shots = tmp_path / "shots"
    shots.mkdir()
    shutil.copy(model / "tex.png", shots / "std.png")
    before = _snapshot(tmp_path)
    cube, points = model / "cube.stl", model / "points.npy"
    for args in (
        ["ldi", cube, "--points", points, "--out", points],
        ["ldi", cube, "--points", points, "--out", cube],
        ["ldi", cube, "--points", tmp_path / "hard.npy", "--out", points],
        ["ldi", cube, "--points", points, "--out", tmp_path / "hard.npy"],
        ["snapshot", "--projector", model / "tex.png", "--out", model / "tex.png", *DEMO_ARGS],
        ["snapshot", "--projector", f"{model / 'tex.png'},30,20,2", "--out", model / "tex.png", *DEMO_ARGS],
        ["snapshot", "--projector", model / "tex.png", "--out", tmp_path / "soft.png", *DEMO_ARGS],
        ["snapshot", "--projector", shots / "std.png", "--all-modes", shots, *DEMO_ARGS],
    ):
        proc = _run(args)
        assert proc.returncode == 2 and _one_line(proc), (args, proc.stderr)
    assert _snapshot(tmp_path) == before


def test_an_output_over_a_referenced_file_is_refused(tmp_path):
    """A glTF whose buffer is named like an output: ldi --out onto it is refused."""
    doc, binary = box_doc()
    doc["buffers"][0]["uri"] = "data.npy"
    (tmp_path / "scene.gltf").write_text(json.dumps(doc))
    (tmp_path / "data.npy").write_bytes(binary)
    np.save(tmp_path / "p.npy", np.zeros((2, 3)))
    proc = _run(["ldi", "scene.gltf", "--points", "p.npy", "--out", "data.npy"], cwd=tmp_path)
    assert proc.returncode == 2 and _one_line(proc, "input"), proc.stderr
    assert (tmp_path / "data.npy").read_bytes() == binary


@pytest.mark.parametrize(
    "args,needle",
    [
        (["snapshot", "--out", "folder.png"], "is a folder"),
        (["snapshot", "--out", "/proc/rtta-test.png"], "/proc"),
        (["snapshot", "--out", "full.png"], "not a regular file"),
        (["snapshot", "--out", "n" * 300 + ".png"], "longer than 255"),
        (["snapshot", "--out", "nowhere/a.png"], "parent directory does not exist"),
        (["snapshot", "--all-modes", "file.txt"], "not a folder"),
        (["export", "--out", "/dev/shm"], "mount point"),
        (["export", "--out", "/proc"], "mount point"),
        (["ldi", "shape:box", "--points", "p.npy", "--out", "folder.png"], ".npy"),
        (["ldi", "shape:box", "--points", "p.npy", "--out", "dir.npy"], "is a folder"),
    ],
)
def test_outputs_that_cannot_be_written_are_one_line(tmp_path, args, needle):
    (tmp_path / "folder.png").mkdir()
    (tmp_path / "dir.npy").mkdir()
    (tmp_path / "file.txt").write_text("mine")
    os.symlink("/dev/full", tmp_path / "full.png")
    np.save(tmp_path / "p.npy", np.zeros((2, 3)))
    before = _snapshot(tmp_path)
    proc = _run([*args, *DEMO_ARGS] if args[0] != "ldi" else args, cwd=tmp_path)
    assert proc.returncode == 2 and _one_line(proc, needle), proc.stderr
    assert _snapshot(tmp_path) == before


def _small_files():
    """In the child: writing more than 2 KiB fails with EFBIG (a full disk, without one)."""
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_FSIZE, (2048, 2048))


def test_a_full_disk_is_one_line_and_keeps_the_old_output(tmp_path):
    assert main(["export", "--out", str(tmp_path / "out"), *DEMO_ARGS]) == 0
    (tmp_path / "shot.png").write_bytes(b"old")
    before = _snapshot(tmp_path)
    for args in (
        ["snapshot", "--out", "shot.png", "--size", "320x240"],
        ["export", "--out", "out", "--size", "320x240"],
    ):
        proc = _run(args, cwd=tmp_path, preexec_fn=_small_files)
        assert proc.returncode == 2 and _one_line(proc, "too large"), proc.stderr
        assert _snapshot(tmp_path) == before and not list(tmp_path.glob(".*"))


def test_stdout_that_cannot_be_written_is_one_line():
    with open("/dev/full", "w") as full:
        proc = subprocess.run([RTTA, "info"], stdout=full, stderr=subprocess.PIPE, text=True, timeout=120)
    assert proc.returncode == 2 and _one_line(proc.stderr, "standard output"), proc.stderr


# ---- messages ---------------------------------------------------------------------------
@pytest.mark.parametrize(
    "argv",
    [
        [],
        ["--nope"],
        ["render"],
        ["snapshot", "--fov", "abc", "--out", "a.png"],
        ["export"],
        ["export", "--size"],
        ["snapshot", "--capture-path", "xx", "--out", "a.png"],
        ["export", "--border", "1.5", "--out", "o"],
        ["bench"],
        ["bench", "nope"],
        ["ldi"],
        ["ldi", "shape:box", "--resolution", "many"],
    ],
)
def test_bad_flags_are_one_line_without_usage(argv, capsys):
    assert main(argv) == 2
    captured = capsys.readouterr()
    assert _one_line(captured.err) and captured.out == "", captured.err


@pytest.mark.parametrize(
    "flags,needle",
    [
        (["--camera", ""], "--camera"),
        (["--camera", "0,0,1e300"], "--camera"),
        (["--camera", "nan,0,2"], "--camera"),
        (["--camera", "1e300,0,2"], "--camera"),
        (["--fov", "nan"], "--fov"),
        (["--fov", "0"], "--fov"),
        (["--lens", "sphere", "--lens-at", "1e300,0,0"], "--lens-at"),
        (["--lens", "sphere,1e300"], "--lens radius"),
        (["--lens", ""], "--lens"),
        (["--region-scale", "nan"], "--region-scale"),
        (["--size", "0x0"], "--size"),
        (["--projector", "default,0,0,1e300"], "--projector 'default,0,0,1e300': AZ and EL"),
        (["--projector", f"{GRID},nan,0,2"], f"--projector '{GRID},nan,0,2': AZ and EL"),
        (["--projector-fov", "nan", "--projector", "default"], "fov"),
        (["--size", "4096x4096", "--region-scale", "4"], "memory limit"),
    ],
)
def test_bad_values_are_one_line_without_warnings(flags, needle, tmp_path, capsys, gl):
    code = main(["snapshot", *DEMO_ARGS, *flags, "--out", str(tmp_path / "a.png")])
    captured = capsys.readouterr()
    assert code == 2 and _one_line(captured.err, needle), captured.err
    assert not (tmp_path / "a.png").exists()


@pytest.mark.parametrize("value", ["nan", "inf", "-1", "0", "lots", "1e300"])
def test_memory_limit_must_be_a_positive_number(value, monkeypatch, capsys):
    monkeypatch.setenv("RTTA_MEMORY_LIMIT_MB", value)
    assert main(["info"]) == 2
    assert _one_line(capsys.readouterr().err, "RTTA_MEMORY_LIMIT_MB")


def test_points_and_projector_files_are_checked_before_reading(tmp_path, capsys):
    header = "{'descr': '<f8', 'fortran_order': False, 'shape': (1000000000000, 3), }"
    header += " " * (117 - len(header)) + "\n"
    (tmp_path / "huge.npy").write_bytes(b"\x93NUMPY\x01\x00" + len(header).to_bytes(2, "little") + header.encode())
    os.mkfifo(tmp_path / "fifo.npy")
    (tmp_path / "bomb.png").write_bytes(_bomb_png())
    from PIL import Image

    Image.new("L", (10000, 10000)).save(tmp_path / "big.png")  # over PIL's warning threshold
    for argv, needle in (
        (["ldi", "shape:box", "--points", "huge.npy", "--out", "o.npy"], "1,000,000,000,000"),
        (["ldi", "shape:box", "--points", "fifo.npy", "--out", "o.npy"], "not a regular file"),
        (["snapshot", "--projector", "bomb.png", "--out", "o.png"], "too large"),
        (["snapshot", "--projector", "big.png", "--out", "o.png"], "too large"),
    ):
        t0 = time.perf_counter()
        proc = _run([*argv, *DEMO_ARGS] if argv[0] == "snapshot" else argv, cwd=tmp_path)
        assert proc.returncode == 2 and _one_line(proc, needle), (argv, proc.stderr)
        assert time.perf_counter() - t0 < 10
    assert not list(tmp_path.glob("o.*"))


def test_closed_meshes_at_any_scale_are_closed(tmp_path, capsys):
    """A sphere of radius 1e-30 or 1e12 is as closed as one of 1, and classifies the same."""
    rng = np.random.default_rng(3)
    points = rng.uniform(-1.5, 1.5, (400, 3))
    truth = np.linalg.norm(points, axis=1) < 0.98
    near = np.abs(np.linalg.norm(points, axis=1) - 1) < 0.05
    for scale in (1e-30, 1.0, 1e12):
        mesh = trimesh.creation.icosphere(3)
        mesh.vertices *= scale
        mesh.export(tmp_path / "s.stl")
        np.save(tmp_path / "p.npy", points * scale)
        assert (
            main(
                [
                    "ldi",
                    str(tmp_path / "s.stl"),
                    "--points",
                    str(tmp_path / "p.npy"),
                    "--out",
                    str(tmp_path / "in.npy"),
                    "--resolution",
                    "128",
                ]
            )
            == 0
        ), capsys.readouterr().err
        inside = np.load(tmp_path / "in.npy")
        assert (inside == truth)[~near].all(), scale


def test_viewer_flags_are_one_line():
    from viewer import main as view_main

    proc = subprocess.run(
        [sys.executable, "-c", "import sys, viewer; sys.exit(viewer.main(['--size']))"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 2 and proc.stderr.count("\n") == 1 and "usage" not in proc.stderr, proc.stderr
    assert view_main is not None
