"""Limits of the native readers' child (rtta.scene.readers.isolated) and of the USD reader's
instance expansion: prototypes that instance prototypes (10^10 parts in 18 KB) are refused
from their counts, before any is expanded; a reader child that runs out of its memory cap
(RTTA_READER_MEMORY_MB) gives one line that says memory, and exit status 2."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from rtta.cli.main import main
from rtta.errors import RttaError
from rtta.scene.loader import load_scene
from rtta.scene.readers import isolated

RTTA = str(Path(sys.executable).with_name("rtta"))


def _nested_usda(levels: int, fan: int, triangles: int = 1) -> str:
    """Class L0 holds one mesh of `triangles` triangles; class Lk holds `fan` instances of
    L(k-1), each moved by its index along x; /top is an instance of L`levels`."""
    rows = ["#usda 1.0", 'class "L0"', "{", '    def Mesh "m"', "    {"]
    rows += [
        "        point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]",
        f"        int[] faceVertexCounts = [{', '.join(['3'] * triangles)}]",
        f"        int[] faceVertexIndices = [{', '.join(['0, 1, 2'] * triangles)}]",
        "    }",
        "}",
    ]
    for k in range(1, levels + 1):
        rows += [f'class "L{k}"', "{"]
        for i in range(fan):
            rows += [
                f'    def Xform "i{i}" (',
                "        instanceable = true",
                f"        references = </L{k - 1}>",
                "    )",
                "    {",
                f"        double3 xformOp:translate = ({i * fan ** (k - 1)}, 0, 0)",
                '        uniform token[] xformOpOrder = ["xformOp:translate"]',
                "    }",
            ]
        rows += ["}"]
    rows += ['def Xform "top" (', "    instanceable = true", f"    references = </L{levels}>", ")", "{", "}"]
    return "\n".join(rows) + "\n"


def _one_error(capsys, path: Path, says: str) -> None:
    err = [line for line in capsys.readouterr().err.splitlines() if line.strip()]
    assert len(err) == 1 and err[0].startswith(f"rtta: error: {path}: ") and says in err[0], err


@pytest.mark.parametrize(
    "levels,fan,triangles,memory_mb,says",
    [
        (
            10,
            10,
            1,
            None,
            "the USD stage, its instances expanded, makes 10,000,000,000 parts in 21,111,111,111 prims, "
            "over the 10,000 parts or 500,000 prims a file of its size may make",
        ),
        (40, 2, 1, None, "instances expanded, makes 1,099,511,627,776 parts"),
        (3, 10, 500, "64", "the USD stage, its instances expanded, has 3,000 vertices and 500,000 triangles"),
    ],
)
def test_usd_instance_bombs_are_one_line_and_fast(
    tmp_path, capsys, monkeypatch, levels, fan, triangles, memory_mb, says
):
    """Ten levels of ten instances ran until the reader's timeout (61 s); each part was one
    prim visit and one copy of the prototype's points. Triangles that instancing multiplies
    past the memory limit are refused from the counts too."""
    pytest.importorskip("pxr")
    monkeypatch.setenv(isolated.ENV, "15")  # without the counts: the timeout's message, after 15 s
    if memory_mb:
        monkeypatch.setenv("RTTA_MEMORY_LIMIT_MB", memory_mb)
    path = tmp_path / "bomb.usda"
    path.write_text(_nested_usda(levels, fan, triangles))
    t0 = time.perf_counter()
    assert main(["info", "--no-cache", str(path)]) == 2
    assert time.perf_counter() - t0 < 12
    _one_error(capsys, path, says)


def test_usd_nested_instances_up_to_the_limit_still_load(tmp_path):
    """Four levels of ten: 10,000 parts, as many as a small file may make, each in its place."""
    pytest.importorskip("pxr")
    path = tmp_path / "nested.usda"
    path.write_text(_nested_usda(4, 10))
    s = load_scene(path, cache=False)
    assert s.count == 10_000
    assert sorted(np.round(s.aabb_min[:, 0]).astype(int).tolist()) == list(range(10_000))


def test_usd_expansion_counts_each_prototype_once_and_stops_at_a_cycle(monkeypatch):
    """(parts, prims, vertices, triangles) summed innermost first, each prototype scanned once;
    a prototype below itself (USD's composition allows none) is an error, not an endless count."""
    from rtta.scene.readers import usd

    class Prim(str):
        def GetPath(self):
            return str(self)

    class Stage:
        looked_up = 0

        def GetPseudoRoot(self):
            return Prim("/")

        def GetPrimAtPath(self, path):
            Stage.looked_up += 1
            assert Stage.looked_up < 100, "the count does not end"
            return Prim(path)

    inside = {"/": {"/A": 1, "/B": 5}, "/A": {"/B": 2}, "/B": {}}
    scanned = []
    monkeypatch.setattr(usd, "_own_counts", lambda p: scanned.append(p) or ((1, 2, 3, 4), inside[p]))
    assert usd._expansion(Stage(), Path("x.usda")) == (9, 18, 27, 36)  # / + A + 2 B + 5 B
    assert sorted(scanned) == ["/", "/A", "/B"]
    inside["/B"] = {"/A": 1}
    with pytest.raises(RttaError, match="the USD stage's instances hold themselves"):
        usd._expansion(Stage(), Path("x.usda"))


def test_memory_cap_is_half_the_machine_or_the_variable(monkeypatch, tmp_path):
    monkeypatch.delenv(isolated.MEMORY_ENV, raising=False)
    monkeypatch.setattr(isolated, "CGROUP_MAX", tmp_path / "none")
    machine = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    assert isolated.memory_cap() == machine // 2
    (tmp_path / "memory.max").write_text("max\n")
    monkeypatch.setattr(isolated, "CGROUP_MAX", tmp_path / "memory.max")
    assert isolated.memory_cap() == machine // 2
    (tmp_path / "memory.max").write_text(f"{2**30}\n")  # a container's limit, lower than the machine's
    assert isolated.memory_cap() == 2**29
    for bad in ("lots", "-3", "0", "nan", "inf"):
        monkeypatch.setenv(isolated.MEMORY_ENV, bad)
        assert isolated.memory_cap() == 2**29, bad
    monkeypatch.setenv(isolated.MEMORY_ENV, "300.5")
    assert isolated.memory_cap() == int(300.5 * 2**20)


READERS = """
import os, sys

def vt(path):  # a C++ std::bad_alloc, which boost.python raises as MemoryError
    from pxr import Vt
    Vt.FloatArray(200_000_000)  # 800 MB, written to (zeros)

def abort(path):  # an uncaught std::bad_alloc: std::terminate's words, then SIGABRT
    os.write(2, b"terminate called after throwing an instance of 'std::bad_alloc'\\n  what():  std::bad_alloc\\n")
    os.abort()

def wrapped(path):  # a library that reports the failure as its own exception
    raise RuntimeError("Standard_OutOfMemory: Standard_MMgrRaw::Allocate(): malloc failed")

def crash(path):  # no words: a crash is a crash
    os.abort()
"""


@pytest.fixture
def reader(tmp_path, monkeypatch):
    for kind in ("vt", "abort", "wrapped", "crash"):
        (tmp_path / f"memory_{kind}.py").write_text(READERS + f"\nread = {kind}\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setenv("RTTA_READER_MEMORY_MB", "640")
    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "1")  # numpy's buffers per core count as data too
    target = tmp_path / "part.usd"
    target.write_text("anything")
    return target


def test_running_out_of_memory_in_the_child_says_memory(reader):
    pytest.importorskip("pxr")
    says = r"the LIB reader ran out of memory at its limit of 640 MiB \(the file may be damaged; RTTA_READER_MEMORY_MB"
    for kind in ("vt", "abort", "wrapped"):
        with pytest.raises(RttaError, match=says):
            isolated.read(f"memory_{kind}", reader, "LIB")
    with pytest.raises(RttaError, match=r"the LIB reader crashed on this file \(SIGABRT\)"):
        isolated.read("memory_crash", reader, "LIB")


def test_the_cli_says_the_reader_ran_out_of_memory_in_one_line(tmp_path):
    """The USD reader replaced by one that asks for 8 GiB (numpy, not written to: without
    the cap it is given and uses nothing, and the reader gives None); RTTA_READER_MEMORY_MB=512
    refuses it."""
    pytest.importorskip("pxr")
    path = tmp_path / "plant.usda"
    path.write_text("#usda 1.0\n")
    (tmp_path / "sitecustomize.py").write_text(
        "import numpy, rtta.scene.readers.usd as u\n"
        "u.read = lambda path: (numpy.empty(8 << 30, numpy.uint8), None)[1]\n"
    )
    env = dict(os.environ, PYTHONPATH=str(tmp_path), RTTA_READER_MEMORY_MB="512", OPENBLAS_NUM_THREADS="1")
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
        f"rtta: error: {path}: the USD reader ran out of memory at its limit of 512 MiB (the file may be "
        "damaged; RTTA_READER_MEMORY_MB=MIB allows more)"
    )
    assert not (tmp_path / "o.png").exists()


def test_a_small_file_instancing_more_parts_on_purpose_loads_with_rtta_max_parts(tmp_path, monkeypatch, capsys):
    """12,000 nodes sharing one box mesh in a 0.5 MB GLB: over the 10,000 parts a file of its
    size may make (a refusal that names the override), loaded whole with RTTA_MAX_PARTS; a bad
    value is one line."""
    from bad_gltf import box_doc, glb

    from rtta.cli.main import main
    from rtta.scene.loader import load_scene

    nodes = [{"name": "root", "children": list(range(1, 12_001))}]
    nodes += [{"mesh": 0, "name": f"bolt{i}", "translation": [i % 100, i // 100, 0]} for i in range(12_000)]
    path = tmp_path / "bolts.glb"
    path.write_bytes(glb(*box_doc(nodes)))
    assert main(["info", str(path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "RTTA_MAX_PARTS=N allows more" in err[0], err
    monkeypatch.setenv("RTTA_MAX_PARTS", "20000")
    assert load_scene(path, cache=False).count == 12_000
    monkeypatch.setenv("RTTA_MAX_PARTS", "lots")
    assert main(["info", str(path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "RTTA_MAX_PARTS must be a whole number" in err[0], err


def _step_structure(levels: int, width: int) -> str:
    """A STEP file whose product structure uses each level's definition `width` times in the one
    above, `levels` deep (no geometry: the check runs before OpenCASCADE)."""
    lines = [f"#{k + 1}=PRODUCT_DEFINITION('d{k}','',#100,#200);" for k in range(levels + 1)]
    n = 1000
    for k in range(levels):
        for _ in range(width):
            lines.append(f"#{n}=NEXT_ASSEMBLY_USAGE_OCCURRENCE('NAUO{n}','','',#{k + 1},#{k + 2},$);")
            n += 1
    head = "ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION((''),'2;1');\nENDSEC;\nDATA;\n"
    return head + "\n".join(lines) + "\nENDSEC;\nEND-ISO-10303-21;\n"


def test_a_step_structure_placing_too_many_parts_is_refused_before_opencascade(tmp_path, capsys):
    """Ten levels of ten occurrences each: 10^10 parts in 9 KB, refused in one line before
    cascadio expands them; RTTA_MAX_PARTS names the way round; a modest structure passes the check."""
    from rtta.cli.main import main
    from rtta.scene.readers import step

    path = tmp_path / "bomb.step"
    path.write_text(_step_structure(10, 10))
    t0 = time.perf_counter()
    assert main(["info", str(path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "STEP product structure places over 10,000 parts" in err[0], err
    assert "RTTA_MAX_PARTS" in err[0] and time.perf_counter() - t0 < 30
    step._check_occurrences(step._children(_step_structure(3, 10)), path)  # 1,000 parts: fine
