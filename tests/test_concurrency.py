"""Several processes at once (issue 42): processes reading the same file together (the
direct readers, trimesh's, and the native readers in their child processes) all succeed with
the same answer and leave no temporary behind; dataset shards started together into one
folder all succeed, leave nothing half-written, and merge into what one run writes. (The
scene cache's own concurrency is tested with the cache.)"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from assemblies import write_ifc, write_step, write_usd
from bad_gltf import box_doc, glb
from dataset_checks import nested_glb
from PIL import Image

RTTA = str(Path(sys.executable).with_name("rtta"))
TOGETHER = 3  # processes per file, started at once


def _start(args, tmp: Path, cwd: Path | None = None) -> subprocess.Popen:
    env = {**os.environ, "TMPDIR": str(tmp)}  # the readers' temporaries, to be looked for afterwards
    return subprocess.Popen(
        [RTTA, *map(str, args)], cwd=cwd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )


def _files(tmp_path: Path) -> dict[str, Path]:
    folder = tmp_path / "models"
    folder.mkdir()
    nodes = [
        {"name": "root", "children": [1, 2]},
        {"name": "a", "mesh": 0},
        {"name": "b", "mesh": 0, "scale": [2, 2, 2]},
    ]
    (folder / "parts.glb").write_bytes(glb(*box_doc(nodes)))
    (folder / "parts.mtl").write_text("newmtl red\nKd 0.8 0.1 0.1\nnewmtl blue\nKd 0.1 0.2 0.9\n")
    box = "".join(f"v {x} {y} {z}\n" for x in (0, 1) for y in (0, 1) for z in (0, 1))
    quads = "f 1 2 4 3\nf 5 7 8 6\nf 1 5 6 2\nf 3 4 8 7\nf 1 3 7 5\nf 2 6 8 4\n"
    moved = box.replace("v 1", "v 3").replace("v 0 ", "v 2 ")
    (folder / "parts.obj").write_text(
        f"mtllib parts.mtl\no a\nusemtl red\n{box}{quads}o b\nusemtl blue\n{moved}{quads}"
    )
    write_step(folder / "engine.step")
    write_usd(folder / "plant.usda")
    write_ifc(folder / "house.ifc", storeys=1)
    return {p.suffix: p for p in folder.iterdir() if p.suffix != ".mtl"}


@pytest.mark.slow  # 15 processes at once: about a minute on 2 shared cores
def test_processes_reading_one_file_together(tmp_path):
    files = _files(tmp_path)
    temp = tmp_path / "tmp"
    temp.mkdir()
    running = {suffix: [_start(["info", path], temp) for _ in range(TOGETHER)] for suffix, path in files.items()}
    for suffix, procs in running.items():
        results = [p.communicate(timeout=300) + (p.returncode,) for p in procs]
        assert all(code == 0 for _, _, code in results), (suffix, [err for _, err, _ in results])
        outputs = {out for out, _, _ in results}
        assert len(outputs) == 1 and " objects" in outputs.pop(), suffix
    assert list(temp.iterdir()) == []  # the native readers' pickles and folders are gone


def _every_file_whole(folder: Path) -> int:
    """No temporary (a dot name) left; every JSON parses and every PNG decodes. Returns the
    number of files."""
    count = 0
    for path in folder.rglob("*"):
        assert not path.name.startswith("."), path
        if path.suffix == ".json":
            json.loads(path.read_text(encoding="utf-8"))
        elif path.suffix == ".png":
            with Image.open(path) as image:
                image.load()
        count += path.is_file()
    return count


@pytest.mark.slow  # four dataset runs at once on llvmpipe
@pytest.mark.parametrize("shards", [3])
def test_dataset_shards_started_together_into_one_folder(tmp_path, shards):
    pytest.importorskip("pycocotools")
    scene = nested_glb(tmp_path / "nested.glb", copies=2)
    common = ["dataset", scene, "--views", str(2 * shards), "--seed", "5", "--size", "96x72", "--no-progress"]
    shared, single = tmp_path / "shared", tmp_path / "single"
    procs = [_start([*common, "--out", shared, "--shard", f"{i}/{shards}"], tmp_path) for i in range(shards)]
    procs.append(_start([*common, "--out", single], tmp_path))
    for p in procs:
        out, err = p.communicate(timeout=600)
        assert p.returncode == 0, err
    assert sorted(p.name for p in shared.glob("annotations*.json")) == [
        f"annotations-shard-{i}-of-{shards}.json" for i in range(shards)
    ]
    assert _every_file_whole(shared) > 2 * shards and _every_file_whole(single) > 2 * shards
    merge = subprocess.run(
        [RTTA, "dataset", "merge", str(shared), "--out", str(shared / "annotations.json")],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert merge.returncode == 0, merge.stderr
    assert (shared / "annotations.json").read_bytes() == (single / "annotations.json").read_bytes()
    for image in json.loads((single / "annotations.json").read_text())["images"]:
        assert (shared / image["file_name"]).read_bytes() == (single / image["file_name"]).read_bytes()
