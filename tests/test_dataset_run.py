"""`rtta dataset` acceptance, runs: the same seed gives the same bytes; shards merged equal one
run; a run killed by a signal and restarted equals an uninterrupted one; --workers and a dask
cluster give the same bytes; the options (cameras, categories, min-visible, appearance, depth)."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from dataset_checks import nested_glb, read_json
from PIL import Image

from rtta.cli.main import main
from rtta.dataset.options import Options, Run
from rtta.dataset.run import run
from rtta.scene.model import from_meshes

pytest.importorskip("pycocotools")
RTTA = str(Path(sys.executable).with_name("rtta"))
SMALL = ["--size", "160x120", "--no-progress"]


@pytest.fixture(scope="module")
def scenes(tmp_path_factory):
    """Two scene files (the demo's copy and a nested scene), so that shards split across scenes."""
    from rtta.scene.generators.demo import demo_path

    folder = tmp_path_factory.mktemp("scenes")
    (folder / "brake.glb").write_bytes(demo_path().read_bytes())
    nested_glb(folder / "nested.glb", copies=2)
    return folder


@pytest.fixture(scope="module")
def reference(scenes, tmp_path_factory, ctx):
    out = tmp_path_factory.mktemp("ref") / "ds"
    assert main(["dataset", str(scenes), "--views", "3", "--seed", "7", "--out", str(out), *SMALL]) == 0
    return out


def _bytes(path: Path) -> bytes:
    return path.read_bytes()


def test_same_seed_same_bytes_other_seed_not(scenes, reference, tmp_path):
    again = tmp_path / "again"
    assert main(["dataset", str(scenes), "--views", "3", "--seed", "7", "--out", str(again), *SMALL]) == 0
    assert _bytes(again / "annotations.json") == _bytes(reference / "annotations.json")
    assert _bytes(again / "images/nested/00002/depth.png") == _bytes(reference / "images/nested/00002/depth.png")
    globbed = tmp_path / "globbed"  # a glob names the same scenes as the folder
    assert main(["dataset", str(scenes / "*.glb"), "--views", "3", "--seed", "7", "--out", str(globbed), *SMALL]) == 0
    assert _bytes(globbed / "annotations.json") == _bytes(reference / "annotations.json")
    other = tmp_path / "other"
    assert main(["dataset", str(scenes), "--views", "3", "--seed", "8", "--out", str(other), *SMALL]) == 0
    assert _bytes(other / "annotations.json") != _bytes(reference / "annotations.json")
    doc = read_json(reference / "annotations.json")
    assert [im["id"] for im in doc["images"]] == list(range(1, 7))
    assert [a["id"] for a in doc["annotations"]] == list(range(1, len(doc["annotations"]) + 1))


def test_shards_merge_into_the_one_run(scenes, reference, tmp_path, capsys):
    shared = tmp_path / "shared"  # one shared folder, as on a cluster's file system
    for i in range(2):
        assert (
            main(
                [
                    "dataset",
                    str(scenes),
                    "--views",
                    "3",
                    "--seed",
                    "7",
                    "--out",
                    str(shared),
                    "--shard",
                    f"{i}/2",
                    *SMALL,
                ]
            )
            == 0
        )
    assert sorted(p.name for p in shared.glob("annotations*.json")) == [
        "annotations-shard-0-of-2.json",
        "annotations-shard-1-of-2.json",
    ]
    assert main(["dataset", "merge", str(shared), "--out", str(shared / "annotations.json")]) == 0
    assert _bytes(shared / "annotations.json") == _bytes(reference / "annotations.json")
    apart = [tmp_path / "m0", tmp_path / "m1"]  # or one folder per machine, merged afterwards
    for i, out in enumerate(apart):
        assert (
            main(
                ["dataset", str(scenes), "--views", "3", "--seed", "7", "--out", str(out), "--shard", f"{i}/2", *SMALL]
            )
            == 0
        )
    assert main(["dataset", "merge", *map(str, apart), "--out", str(tmp_path / "all.json")]) == 0
    merged, single = read_json(tmp_path / "all.json"), read_json(reference / "annotations.json")
    assert len(merged["images"]) == len(single["images"]) and merged["annotations"] == single["annotations"]
    for im in merged["images"]:
        assert (tmp_path / im["file_name"]).is_file() and im["file_name"].startswith(("m0/", "m1/"))
    assert {im["id"] for im in merged["images"]} == {im["id"] for im in single["images"]}
    capsys.readouterr()


def _views_written(out: Path) -> list[Path]:
    return sorted(p for p in (out / "parts").glob("*/*.json") if not p.name.startswith("."))


@pytest.mark.slow  # measured: 10.8 s
def test_killed_run_restarts_to_the_same_dataset(scenes, tmp_path, ctx):
    argv = [str(scenes / "brake.glb"), "--views", "40", "--seed", "3", "--out", "k", *SMALL]
    proc = subprocess.Popen([RTTA, "dataset", *argv], cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    deadline = time.monotonic() + 60
    while len(_views_written(tmp_path / "k")) < 4 and time.monotonic() < deadline and proc.poll() is None:
        time.sleep(0.02)
    os.kill(proc.pid, signal.SIGKILL)
    proc.communicate()
    out = tmp_path / "k"
    done = _views_written(out)
    assert 4 <= len(done) < 40 and not (out / "annotations.json").exists()
    for part in done:  # every view said complete is whole
        folder = out / read_json(part)["image"]["file_name"]
        assert {p.name for p in folder.parent.iterdir()} == {"rgb.png", "depth.png", "visible_id.png"}
    for folder in (out / "images/brake").iterdir():  # and nothing half-written is in place
        if not folder.name.startswith("."):
            assert (folder / "rgb.png").is_file() and (folder / "visible_id.png").is_file()
    assert main(["dataset", *argv[:-5], "--out", str(out), *SMALL]) == 0
    assert not [p for p in out.rglob(".*")]  # temporaries gone
    whole = tmp_path / "whole"
    assert main(["dataset", *argv[:-5], "--out", str(whole), *SMALL]) == 0
    assert _bytes(out / "annotations.json") == _bytes(whole / "annotations.json")


def test_sigterm_leaves_no_temporaries(scenes, tmp_path):
    proc = subprocess.Popen(
        [RTTA, "dataset", str(scenes / "brake.glb"), "--views", "40", "--out", "t", *SMALL],
        cwd=tmp_path,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    deadline = time.monotonic() + 60
    while len(_views_written(tmp_path / "t")) < 2 and time.monotonic() < deadline and proc.poll() is None:
        time.sleep(0.02)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130 and err.strip().splitlines() == ["rtta: interrupted"]
    leftovers = [p for p in (tmp_path / "t").rglob(".*")]
    assert not leftovers and _views_written(tmp_path / "t")


@pytest.mark.slow  # measured: 13.7 s
def test_workers_give_the_same_bytes(scenes, reference, tmp_path):
    res = subprocess.run(
        [RTTA, "dataset", str(scenes), "--views", "3", "--seed", "7", "--out", "w", "--workers", "2", *SMALL],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert res.returncode == 0, res.stderr
    assert _bytes(tmp_path / "w/annotations.json") == _bytes(reference / "annotations.json")


@pytest.mark.slow  # measured: 18.0 s
def test_dask_cluster_runs_the_shards(scenes, reference, tmp_path):
    """The recipe of docs/datasets.md: shards as tasks of a dask.distributed cluster (a LocalCluster of
    two worker processes here; a scheduler address on a real one), then merge."""
    distributed = pytest.importorskip("distributed")
    from rtta.dataset.cluster import run_shards

    out = tmp_path / "d"
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None)
    with cluster, distributed.Client(cluster) as client:
        codes = run_shards(client, [str(scenes), "--views", "3", "--seed", "7", "--out", str(out), *SMALL], 2)
    assert [c for c, _ in codes] == [0, 0], codes
    assert main(["dataset", "merge", str(out), "--out", str(out / "annotations.json")]) == 0
    assert _bytes(out / "annotations.json") == _bytes(reference / "annotations.json")


def _ifc_scene():
    box = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    faces = np.array(
        [
            [0, 1, 3],
            [0, 3, 2],
            [4, 6, 7],
            [4, 7, 5],
            [0, 4, 5],
            [0, 5, 1],
            [2, 3, 7],
            [2, 7, 6],
            [0, 2, 6],
            [0, 6, 4],
            [1, 5, 7],
            [1, 7, 3],
        ]
    )
    names = ["IfcWall 'w1'", "IfcWall 'w2'", "IfcDoor 'd1'", "bolt"]
    return from_meshes([(n, box + [1.5 * i, 0, 0], faces, None) for i, n in enumerate(names)])


def test_options_categories_min_visible_appearance_depth(scenes, tmp_path):
    nested = str(scenes / "nested.glb")
    base = Options(scenes=[nested], views=2, size=(160, 120), seed=1)
    assert (
        run(
            Options(**{**base.__dict__, "category_by": "group", "appearance": True}),
            Run(out=tmp_path / "g", progress=False),
        )
        == 0
    )
    doc = read_json(tmp_path / "g/annotations.json")
    assert {c["name"] for c in doc["categories"]} == {"shell", "inner", "core", "rod"}
    rgb = {im["id"]: np.asarray(Image.open(tmp_path / "g" / im["file_name"])) for im in doc["images"]}
    from pycocotools import mask as cmask

    for a in doc["annotations"]:
        x, y, w, h = a["appearance"]["rect"]
        crop = np.asarray(Image.open(tmp_path / "g" / a["appearance"]["file"]))
        assert crop.shape == (h, w, 4)
        amodal = cmask.decode(a["amodal_segmentation"]).astype(bool)
        assert np.array_equal(crop[..., 3] > 0, amodal[y : y + h, x : x + w]) and not amodal[:, :x].any()
        seen = cmask.decode(a["segmentation"]).astype(bool)[y : y + h, x : x + w]
        diff = np.abs(crop[..., :3].astype(int) - rgb[a["image_id"]][y : y + h, x : x + w]).max(-1)[seen]
        assert not seen.any() or (diff <= 3).mean() >= 0.99  # unoccluded appearance = STD where visible
    hidden = [a for a in doc["annotations"] if a["area"] == 0]
    assert hidden
    assert (
        run(Options(**{**base.__dict__, "min_visible": 1, "depth": "npy"}), Run(out=tmp_path / "m", progress=False))
        == 0
    )
    kept = read_json(tmp_path / "m/annotations.json")
    assert all(a["area"] >= 1 for a in kept["annotations"])
    assert len(kept["annotations"]) == len(doc["annotations"]) - len(hidden)
    rank = {(a["image_id"], a["object_id"]): a["depth_order"] for a in doc["annotations"]}
    assert all(rank[a["image_id"], a["object_id"]] == a["depth_order"] for a in kept["annotations"])
    first = kept["images"][0]
    assert "depth_scale" not in first and np.load(tmp_path / "m" / first["depth_file"]).dtype == np.float32
    ifc = _ifc_scene()
    assert (
        run(
            Options(scenes=["ifc"], views=1, size=(160, 120), category_by="ifc-class", distance=(2.5, 2.5)),
            Run(out=tmp_path / "i", progress=False),
            {"ifc": ifc},
        )
        == 0
    )
    names = {c["name"] for c in read_json(tmp_path / "i/annotations.json")["categories"]}
    assert names == {"IfcWall", "IfcDoor", "unclassified"}


def test_settings_are_kept_in_dataset_json(reference):
    saved = read_json(reference / "dataset.json")["settings"]
    assert saved["views"] == 3 and saved["seed"] == 7 and [s["key"] for s in saved["scenes"]] == ["brake", "nested"]
    info = read_json(reference / "annotations.json")["info"]
    assert info["settings"] == saved and json.dumps(info).count("shard") == 0
