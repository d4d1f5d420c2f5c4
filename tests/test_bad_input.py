"""Every CLI command on the bad-input corpus (tests/bad_inputs.py): one error line naming the
file (escaped) and the problem, exit 2, no traceback, fast, nothing written outside --out and
an existing output left as it was; the cases that load do so with their warning, and what
they load is what the file says (names numbered in file order, instances, fans, colours)."""

from __future__ import annotations

import hashlib
import os
import shlex
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from bad_inputs import Case, make_corpus, many_nodes_glb, many_objects_obj

from rtta.cli.common import scene_after_names
from rtta.cli.main import main
from rtta.errors import printable

RTTA = str(Path(sys.executable).with_name("rtta"))
SENTINEL = b"the user's file: must survive"
MIN_CASES = {"format": 30, "gltf": 60, "limits": 12, "references": 12, "names": 12, "pictures": 9}


@pytest.fixture(scope="module")
def corpus(tmp_path_factory):
    folder = tmp_path_factory.mktemp("corpus")
    return folder, make_corpus(folder)


def _tree(root: Path) -> dict[str, str]:
    """Every regular file under root (FIFOs are not read) with a hash of its contents."""
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
        "ldi": [
            "ldi",
            str(path),
            "--points",
            str(out / "points.npy"),
            "--out",
            str(out / "inside.npy"),
            "--resolution",
            "64",
        ],
        "dataset": [
            "dataset",
            str(path),
            "--out",
            str(out / "dataset"),
            "--views",
            "1",
            "--size",
            "32x24",
            "--no-progress",
        ],
    }


def _outputs(out: Path) -> None:
    """What the user already had: a PNG, an earlier export, an LDI result, the points."""
    out.mkdir()
    (out / "shot.png").write_bytes(SENTINEL)
    (out / "export").mkdir()
    (out / "export" / "records.json").write_bytes(SENTINEL)
    (out / "export" / "std_color.png").write_bytes(SENTINEL)
    (out / "inside.npy").write_bytes(SENTINEL)
    np.save(out / "points.npy", np.zeros((4, 3)))


def test_corpus_is_large_enough(corpus):
    _, cases = corpus
    per = {c: sum(case.category == c for case in cases) for c in MIN_CASES}
    assert all(per[c] >= n for c, n in MIN_CASES.items()), per
    assert sum(c.error for c in cases) >= 110 and sum(not c.error for c in cases) >= 25
    assert len({c.name for c in cases}) == len(cases)


def _one_line_error(case, lines: list[str]) -> bool:
    return (
        len(lines) == 1
        and lines[0].startswith(f"rtta: error: {printable(case.path)}: ")
        and case.says.lower() in lines[0].lower()
    )


@pytest.mark.parametrize("command", ["info", "snapshot", "export", "ldi", "dataset"])
def test_every_case_through_the_cli(corpus, command, tmp_path, capsys, monkeypatch, gl):
    monkeypatch.setenv("RTTA_MEMORY_LIMIT_MB", "1")  # the too-large cases exceed it
    folder, cases = corpus
    problems = []
    for i, case in enumerate(cases):
        out = tmp_path / f"case{i}"
        _outputs(out)
        before, corpus_before = _tree(out), _tree(folder)
        t0 = time.perf_counter()
        code = main(_commands(case.path, out)[command])
        seconds = time.perf_counter() - t0
        captured = capsys.readouterr()
        err = captured.err
        lines = [line for line in err.splitlines() if line.strip()]
        where = f"{case.name} ({command})"
        if seconds > 10:
            problems.append(f"{where}: took {seconds:.1f} s")
        if _tree(folder) != corpus_before:
            problems.append(f"{where}: the input folder changed")
        if command == "ldi" and code == 0:  # its result line: "<out>: N of M points inside ..."
            lines = [line for line in lines if not line.endswith("layers)")]
        if "Traceback" in err or any(not line.startswith("rtta: ") for line in lines):
            problems.append(f"{where}: stray stderr {err!r}")
        if any(ord(ch) < 32 and ch != "\n" for ch in err + captured.out):
            problems.append(f"{where}: a control character reached the terminal")
        if command == "dataset":  # its own new folder may appear; what was there stays
            after = {k: v for k, v in _tree(out).items() if not k.startswith("dataset/")}
            if after != before:
                problems.append(f"{where}: an existing file changed")
            if case.error and (os.path.isdir(case.path) or "[" in case.path.name):  # a folder, or a glob
                case = Case(case.name, case.path, True, "", case.category)
        if case.error:
            if code != 2 or not _one_line_error(case, lines):
                problems.append(f"{where}: exit {code}, stderr {err!r}")
            if command != "dataset" and _tree(out) != before:
                problems.append(f"{where}: an output was written or changed on error")
        elif command == "ldi" and code == 2:  # loads, but is no closed mesh: refused the same way
            if (
                not (len(lines) - sum("warning" in line for line in lines) == 1 and "not a closed mesh" in lines[-1])
                or _tree(out) != before
            ):
                problems.append(f"{where}: exit {code}, stderr {err!r}")
        else:
            if code != 0 or (case.says and not any(case.says in line and "warning" in line for line in lines)):
                problems.append(f"{where}: exit {code}, stderr {err!r}")
            if command == "snapshot" and (out / "shot.png").read_bytes() == SENTINEL:
                problems.append(f"{where}: snapshot not written")
            left = [p.name for p in out.rglob(".*")]
            if left:
                problems.append(f"{where}: temporaries left: {left}")
    assert not problems, "\n".join(problems)


@pytest.mark.parametrize(
    "name",
    [
        "truncated.glb",
        "buffer_outside_folder.gltf",
        "stl_claims_2g_triangles.stl",
        "nan_vertices.obj",
        "gltf_nodes_each_others_child.glb",
        "escape_in_file_name.glb",
    ],
)
def test_real_process_one_line_exit_2(corpus, name, tmp_path):
    """The installed `rtta` executable itself: exit status and stderr as a user sees them."""
    _, cases = corpus
    case = next(c for c in cases if c.name == name)
    proc = subprocess.run(
        [RTTA, "snapshot", str(case.path), "--out", str(tmp_path / "x.png")],
        capture_output=True,
        text=True,
        timeout=120,
        env={"RTTA_MEMORY_LIMIT_MB": "1", "PATH": "/usr/bin:/bin"},
    )
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.count("\n") == 1 and proc.stderr.startswith("rtta: error: ")
    assert printable(case.path.name) in proc.stderr and "\x1b" not in proc.stderr
    assert "Traceback" not in proc.stderr and proc.stdout == ""
    assert list(tmp_path.iterdir()) == []


def test_hostile_sizes_stay_fast_and_small(corpus, tmp_path):
    """What would hang or take gigabytes (declared sizes, zip bombs, FIFOs, deep and exploding
    graphs): refused in a real process within seconds, its peak memory far under twice a
    256 MiB limit."""
    _, cases = corpus
    hostile = [
        c
        for c in cases
        if (c.category == "limits" and c.name != "too_large_for_limit.glb")  # 1 MiB's
        or c.name.startswith(("gltf_chain", "gltf_dag", "gltf_bufferless"))
    ]
    (tmp_path / "at_limit.obj").write_text(many_objects_obj(10_000))  # many objects: loads in seconds
    (tmp_path / "at_limit.glb").write_bytes(many_nodes_glb(10_000))
    names = [str(c.path) for c in hostile] + [str(tmp_path / "at_limit.obj"), str(tmp_path / "at_limit.glb")]
    script = (
        "import sys, time\nfrom rtta.cli.main import main\nfor p in sys.argv[1:]:\n"
        "    t = time.perf_counter(); code = main(['info', p])\n"
        "    print(p, code, round(time.perf_counter() - t, 2), file=sys.stderr)\n"
        # VmHWM, not getrusage: its maximum survives exec and holds pytest's own peak
        "print([ln for ln in open('/proc/self/status') if ln.startswith('VmHWM:')][0].split()[1])\n"
    )
    proc = subprocess.run(
        [sys.executable, "-c", script, *names],
        capture_output=True,
        text=True,
        timeout=300,
        env={"RTTA_MEMORY_LIMIT_MB": "256", "PATH": "/usr/bin:/bin"},
        cwd=tmp_path,
    )
    timings = [line.rsplit(" ", 2) for line in proc.stderr.splitlines() if not line.startswith("rtta: ")]
    assert len(timings) == len(names), proc.stderr[-2000:]
    slow = [t for t in timings if float(t[2]) > 10]
    assert not slow, slow
    expect = {str(c.path): 2 if c.error else 0 for c in hostile} | {names[-2]: 0, names[-1]: 0}
    wrong = [(p, code) for p, code, _ in timings if int(code) != expect[p]]
    assert not wrong, wrong
    peak_mib = int(proc.stdout.strip().splitlines()[-1]) / 1024
    assert peak_mib < 512, f"peak {peak_mib:.0f} MiB"


def test_loaded_scenes_are_what_the_file_says(corpus):
    from rtta.scene.loader import load_scene

    _, cases = corpus
    by_name = {c.name: c for c in cases}

    def load(name):
        return load_scene(by_name[name].path)

    dup = load("duplicate_names.glb")
    assert dup.names == ["part", "part_2", "part_3"] and "part -> part_2" in dup.warnings[0]
    for name in (
        "duplicate_names.glb",
        "names_two_primitives.glb",
        "names_control_esc.glb",
        "obj_same_name_twice.obj",
        "pictures_second_parent.glb",
        "3mf_named.3mf",
    ):
        assert load(name).names == load(name).names, name  # the same names on every load
    assert load("names_two_primitives.glb").names == ["box", "box_2"]
    assert load("obj_same_name_twice.obj").names == ["part", "part_2"]
    assert load("obj_unnamed_object.obj").count == 2
    assert load("names_control_newline.glb").names == ["two\nlines"]  # kept; escaped where printed
    objs = load("non_utf8_names.obj")
    assert objs.count == 2 and all(name.startswith(("caf", "na")) for name in objs.names)
    tex = load("missing_texture.gltf")
    assert len(tex.warnings) == 1 and "no_such_texture.png" in tex.warnings[0]
    assert tex.colors[0][:3] == pytest.approx([0.2, 0.6, 0.9], abs=1 / 255)  # its material colour (8-bit)
    shared = load("pictures_second_parent.glb")
    assert shared.count == 2 and shared.aabb_min[1][0] - shared.aabb_min[0][0] == pytest.approx(3.0)
    fan = load("pictures_fan_beside_triangles.glb")
    assert fan.count == 2 and fan.index_ranges[1][1] == 6  # the fan's two triangles
    assert load("pictures_nan_base_color.glb").colors[0][0] == pytest.approx(1.0)
    assert load("pictures_lines_beside_triangles.glb").count == 1
    for name in ("pictures_corrupt_embedded_texture.glb", "pictures_oversized_embedded_texture.glb"):
        assert not load(name).textured


def test_info_prints_hostile_names_escaped(corpus, capsys):
    _, cases = corpus
    for case in cases:
        if case.name.startswith(("names_control", "obj_escape")):
            assert main(["info", str(case.path)]) == 0
            out = capsys.readouterr().out
            assert not any(ord(ch) < 32 and ch != "\n" for ch in out) and "\u202e" not in out
            assert len(out.splitlines()) == 3, out  # the summary, unit and axes, one object


def test_closed_pipe_is_not_a_traceback():
    """`rtta info | head`: a reader that leaves early ends the command quietly (exit 1, the
    usual status for a broken pipe), not with a BrokenPipeError traceback."""
    proc = subprocess.Popen([RTTA, "info"], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    proc.stdout.close()  # gone before the first line is written
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 1 and b"Traceback" not in err and err == b"", err.decode()


def test_object_limit_grows_with_the_file(tmp_path):
    """Small files may make 10,000 objects (instancing cannot make minutes of work); larger
    ones one per 256 bytes, so real 100,000-part assemblies load; never over 1,000,000."""
    from rtta.scene.files import max_objects

    small, large, huge = tmp_path / "small.glb", tmp_path / "large.glb", tmp_path / "huge.glb"
    small.write_bytes(b"x" * 1000)
    with open(large, "wb") as f:
        f.truncate(30 * 1024 * 1024)
    with open(huge, "wb") as f:
        f.truncate(2 * 1024**3)
    assert max_objects(small) == 10_000
    assert max_objects(large) == 30 * 1024 * 1024 // 256 == 122_880
    assert max_objects(small, extra_bytes=30 * 1024 * 1024) == (30 * 1024 * 1024 + 1000) // 256
    assert max_objects(huge) == 1_000_000


def test_reference_warnings_name_the_file_once(corpus):
    """A refused texture or material file is named once, with a reason that reads as a
    sentence (no empty 'the  must be', no 'file X file X')."""
    from rtta.scene.loader import load_scene

    _, cases = corpus
    by_name = {c.name: c for c in cases}
    notes = {
        name: load_scene(by_name[name].path).warnings
        for name in ("fifo_texture.gltf", "fifo_mtllib.obj", "obj_mtllib_absolute.obj", "obj_mtllib_outside.obj")
    }
    for name, warnings in notes.items():
        assert warnings, name
        for note in warnings:
            assert "  " not in note, note
            quoted = note.split("'")[1] if "'" in note else None
            assert quoted is None or note.count(f"'{quoted}'") == 1, note
    assert any("'/etc/passwd' is outside the scene's folder" in n for n in notes["obj_mtllib_absolute.obj"])
    assert any("'fifo.mtl' is not a regular file" in n for n in notes["fifo_mtllib.obj"])


@pytest.mark.parametrize("first", ["cow.glb", "my part.stp", "plain"])
def test_a_scene_where_the_command_goes_says_what_to_run(first, tmp_path, capsys, monkeypatch):
    """`rtta FILE` (as a viewer is called): one line naming the file and the commands that open
    it, quoted for the shell; a word that is no scene keeps argparse's message."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "plain").write_bytes(b"")  # a file without a scene suffix is still a file
    assert main([first, "--mode", "ghosted"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"rtta: error: {first}: a command comes first")
    assert f"`rtta-view {shlex.quote(first)}`" in err[0] and f"rtta snapshot {shlex.quote(first)} -o" in err[0]
    assert main(["nonsense"]) == 2
    assert "invalid choice: 'nonsense'" in capsys.readouterr().err


def test_out_has_a_short_form(tmp_path, gl):
    """`-o` is `--out` (snapshot; export, dataset and ldi take it too)."""
    out = tmp_path / "demo.png"
    assert main(["snapshot", "-o", str(out), "--size", "64x48"]) == 0
    assert out.stat().st_size > 0


def test_a_scene_after_a_list_of_names_is_the_scene(tmp_path, capsys, gl):
    """`--focus hub model.glb`: argparse gives the list every word, the file too; with no scene
    given, the last word naming a scene file is the scene (it was a part name looked up in the
    demo: "no object named 'model.glb' in brake_assembly.glb")."""
    import trimesh

    from viewer import build_parser

    path = tmp_path / "two.glb"
    scene = trimesh.Scene()
    for name, x in (("hub", 0.0), ("rim", 2.0)):
        scene.add_geometry(
            trimesh.creation.box((1, 1, 1)),
            node_name=name,
            transform=trimesh.transformations.translation_matrix((x, 0, 0)),
        )
    scene.export(path)
    out = tmp_path / "a.png"
    assert main(["snapshot", "--size", "64x48", "--mode", "ghosted", "--focus", "hub", str(path), "-o", str(out)]) == 0
    assert (
        main(["snapshot", "--size", "64x48", "--hide", "rim", "--opacity", "hub=0.5", str(path), "-o", str(out)]) == 0
    )
    capsys.readouterr()
    assert main(["snapshot", "--focus", "hub", str(tmp_path / "gone.step"), "-o", str(out)]) == 2
    assert capsys.readouterr().err.strip().endswith("gone.step: no such file")
    args = build_parser().parse_args(["--focus", "hub", "rim", "m.IFC"])  # rtta-view reads its words alike
    scene_after_names(args)
    assert (args.scene, args.focus) == ("m.IFC", ["hub", "rim"])
    args = build_parser().parse_args(["x.glb", "--focus", "hub", "m.glb"])  # a scene given: the names stay
    scene_after_names(args)
    assert (args.scene, args.focus) == ("x.glb", ["hub", "m.glb"])
