"""Benchmarks run (quick) and print/write their tables; no timing assertions."""

import json
import math
import os

import pytest

import rtta
from rtta.bench import render as bench


def test_capture_bench_quick(gl, tmp_path, capsys):
    out = tmp_path / "cap.json"
    assert bench.run_capture((256, 256), quick=True, json_path=str(out), ctx=gl) == 0
    data = json.loads(out.read_text())
    assert data["renderer"] == gl.info["GL_RENDERER"]
    assert [s["objects"] for s in data["scenes"]] == [5, 21, 580, 269]
    for s in data["scenes"]:
        for key in ("std_ms", "rtt_ms", "rtta_gs_ms", "rtta_vs_ms", "param_ms"):
            assert math.isfinite(s[key]) and s[key] > 0
    assert [p["objects"] for p in data["param_scaling"]] == [100, 1000]
    printed = capsys.readouterr().out
    assert "RTTA-VS" in printed and gl.info["GL_RENDERER"] in printed


def test_packing_bench_quick(tmp_path, capsys):
    out = tmp_path / "pack.json"
    assert bench.run_packing(quick=True, json_path=str(out)) == 0
    rows = json.loads(out.read_text())["rows"]
    assert [r["objects"] for r in rows] == [10, 100, 1000]
    assert all(0 < r["shelf_util"] <= 1 for r in rows)
    assert "rectpack_util" in rows[1]


def test_ci_tests_the_installed_wheel():
    """In CI the package under test is the one pip installed, with shaders and demo inside."""
    if os.environ.get("CI"):
        assert "site-packages" in rtta.__file__


def test_composite_bench_quick(gl, tmp_path, capsys):
    out = tmp_path / "comp.json"
    assert bench.run_composite((200, 160), quick=True, json_path=str(out), ctx=gl) == 0
    data = json.loads(out.read_text())
    assert data["renderer"] == gl.info["GL_RENDERER"]
    assert [s["name"] for s in data["scenes"]] == ["demo", "table1-5", "table1-21"]
    for s in data["scenes"]:
        assert set(s["modes"]) == {
            "sprites",
            "transparent",
            "ghosted",
            "ghosted-ao",
            "ghosted-ao full",
            "transparent object",
        }
        assert all(v > 0 for v in s["modes"].values()) and s["std_ms"] > 0 and s["recomposite_ms"] > 0
        assert s["pixel_over_object"] > 0 and 0 <= s["ao_error"]["over_8"] <= 1
    assert "recomposite" in capsys.readouterr().out
    assert bench.run_composite((160, 120), quick=True, ctx=gl, scenes=["random-30"]) == 0
    assert "random-30" in capsys.readouterr().out


def test_ldi_bench_quick(gl, tmp_path, capsys):
    from rtta.bench.ldi import run_ldi

    out = tmp_path / "ldi.json"
    assert run_ldi(quick=True, json_path=str(out)) == 0
    data = json.loads(out.read_text())
    assert [r["mesh"] for r in data["table"]] == ["sphere", "torus", "torus-knot", "vase"]
    assert all(s["agree"] > 0.99 and s["compressed_equal"] for s in data["throughput"])
    errors = {(e["mesh"], e["resolution"]): e["error"] for e in data["resolution"]}
    assert all(errors[(m, 256)] < errors[(m, 64)] for m in ("sphere", "torus"))  # finer is better
    printed = capsys.readouterr().out
    assert "t_peel ms" in printed and "speed-up" in printed and gl.info["GL_RENDERER"] in printed


def test_material_bench_quick(gl, tmp_path, capsys):
    from rtta.bench.material import run_material

    out = tmp_path / "material.json"
    assert run_material(40, quick=True, json_path=str(out), viewport=(256, 192), max_vertices=96) == 0
    data = json.loads(out.read_text())
    assert data["renderer"] == gl.info["GL_RENDERER"] and data["objects"] == 40
    calls = {(r["view"], r["method"].split(",")[0]): r["draw calls"] for r in data["rows"]}
    assert calls[("overview", "separate textures")] == 40
    assert calls[("overview", "material atlas")] == 1
    assert all(float(r["frame ms"]) > 0 for r in data["rows"])
    mem = data["memory"]
    assert mem["atlas_bytes"] > 0 and mem["original_bytes"] > 0 and mem["bvh_leaves"] >= 10
    assert "memory:" in capsys.readouterr().out


def test_reliability_bench_scene_choice(gl, tmp_path, capsys):
    """--scenes runs only the named scenes (here the textured one, a few frames); an unknown
    name is one error line naming the choices, exit 2."""
    from rtta.bench.reliability_table import run_reliability
    from rtta.cli.main import main

    out = tmp_path / "rel.json"
    assert run_reliability(3, 40, json_path=str(out), ctx=gl, only=["textured-64"]) == 0
    data = json.loads(out.read_text())
    assert [s["name"] for s in data["scenes"]] == ["textured-64"]
    assert data["scenes"][0]["sweep_failures"] == 0 and data["scenes"][0]["gl_errors"] == 0
    assert "--scenes textured-64" in capsys.readouterr().out
    assert main(["bench", "reliability", "--scenes", "demo,nope"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "nope" in err[0] and "textured-64" in err[0]


def test_dataset_bench_quick(gl, tmp_path, capsys):
    """Both methods write the same annotations (no amodal pixel differs off the silhouette band)."""
    from rtta.bench.dataset import run_bench

    out = tmp_path / "dataset.json"
    assert run_bench((0, 0), quick=True, json_path=str(out), ctx=gl) == 0
    data = json.loads(out.read_text())
    assert data["renderer"] == gl.info["GL_RENDERER"] and data["size"] == [320, 240]
    assert [s["name"] for s in data["scenes"]] == ["demo", "random-200"]
    for s in data["scenes"]:
        assert s["only_one"] == 0 and s["off_band_px"] == 0, s
        assert s["rtta"]["masks_per_view"] == s["rtt"]["masks_per_view"] > 0
        assert math.isfinite(s["ratio_masks"]) and s["ratio_masks"] > 0
    assert "RTTA v/s" in capsys.readouterr().out


@pytest.mark.slow  # measured: 11.1 s
def test_scale_bench_quick(gl, tmp_path, capsys):
    from rtta.bench.scale import run_scale

    out = tmp_path / "scale.json"
    assert run_scale((256, 144), quick=True, sizes="300", json_path=str(out), viewer=False, ctx=gl) == 0
    (row,) = json.loads(out.read_text())["scenes"]
    assert row["scene"] == "assembly-300" and row["objects"] == 300 and row["triangles"] > 300 * 12
    for key in ("param_ms", "std_ms", "capture_ms", "ghosted_ms", "capture_ratio", "ghosted_ratio"):
        assert math.isfinite(row[key]) and row[key] > 0
    for which in ("rtta", "trimesh"):
        assert row["load"][which]["s"] > 0 and row["load"][which]["peak_rss"] > 10 * 2**20
    cost = row["cost"]  # per path: Python outside GL, wall and GPU ms per ghosted frame
    for path in ("cpu", "gpu"):
        for key in ("python_ms", "wall_ms", "gpu_capture_ms", "gpu_composite_ms"):
            assert math.isfinite(cost[f"{path}_{key}"]) and cost[f"{path}_{key}"] > 0
    printed = capsys.readouterr().out
    assert "| assembly-300 | 300 |" in printed and "Frame cost per path" in printed


def test_frame_bench(gl, tmp_path, capsys):
    """rtta bench frame: per path, Python, GL-call, wall and GPU ms of a frame (no timing
    asserted: a shared machine), for a generated assembly and a scene file."""
    from rtta.cli.main import main
    from rtta.scene.generators.demo import demo_path

    out = tmp_path / "frame.json"
    argv = ["bench", "frame", "--parts", "200", "--scene", str(demo_path()), "--frames", "1", "--size", "160x120"]
    assert main([*argv, "--json", str(out)]) == 0
    rows = json.loads(out.read_text())["rows"]
    assert [r["objects"] for r in rows][0] == 200 and rows[1]["scene"] == demo_path().name
    for row in rows:
        for path in ("cpu", "gpu"):
            for key in ("python_ms", "gl_call_ms", "wall_ms", "gpu_capture_ms", "gpu_composite_ms"):
                assert math.isfinite(row[f"{path}_{key}"]) and row[f"{path}_{key}"] >= 0
    printed = capsys.readouterr().out
    assert printed.count("Frame cost per path") == 1 and printed.count(" gpu ") == 2
    assert main(["bench", "frame", "--frames", "0"]) == 2
