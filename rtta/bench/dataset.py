"""`rtta bench dataset`: views and amodal masks per second of `rtta dataset` (ONE RTTA capture
per view) against the per-object baseline that amodal datasets are made with today: each object
in view rendered alone (RTT) and read back. Both produce the same files and annotations through
the same code (render, pycocotools encoding, PNG writing, parts); they take turns view by view
in one run, so a slow phase of a shared machine hits both alike."""

from __future__ import annotations

import json
import shutil
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from ..dataset.alone import alone_rtt, alone_rtta
from ..dataset.coco import encode_flat
from ..dataset.objects import object_meta
from ..dataset.options import Options, camera_for, part_path, settings
from ..dataset.run import Writer, produce_view
from ..dataset.view import render_rtt, render_rtta
from ..gl.context import shared_context
from ..outputs import write_text
from ..renderer.renderer import Renderer
from ..scene.generators.generate import random_scene, table1_scene
from ..scene.model import Scene
from .compare import near_edges
from .render import shared_data

METHODS = {"rtta": render_rtta, "rtt": render_rtt}
STAGES = {"rtta": alone_rtta, "rtt": alone_rtt}
PER_ROUND = 2  # views a method renders in a row (so that writing overlaps the next view, as in a run)


def bench_scenes(quick: bool) -> list[tuple[str, Callable[[], Scene]]]:
    """(name, loader): the demo, the engine (when ../shared/data has it), the paper's 580-object
    Table 1 scene and a 2,000-part scene; --quick: the demo and 200 parts."""
    from ..scene.generators.demo import demo_path
    from ..scene.loader import load_scene

    out: list[tuple[str, Callable[[], Scene]]] = [("demo", lambda: load_scene(demo_path()))]
    if quick:
        return out + [("random-200", lambda: random_scene(200, seed=3, spread=18.0))]
    engine = shared_data() / "engine_2cyl.glb"
    if engine.is_file():
        out.append(("engine_2cyl", lambda: load_scene(engine)))
    return out + [
        ("table1-580", lambda: table1_scene(580, 56654)),
        ("random-2000", lambda: random_scene(2000, seed=3, spread=40.0)),
    ]


def _amodal(out: Path, key: str, view: int) -> dict[int, Any]:
    doc = json.loads(part_path(out, key, view).read_text())
    return {a["object_id"]: a["amodal_segmentation"] for a in doc["annotations"]}


def disagreement(a: dict[int, Any], b: dict[int, Any]) -> tuple[int, int, int]:
    """(objects only one method annotated, amodal pixels that differ off the 1-pixel silhouette
    band of b's mask, all differing pixels) between two views' annotations."""
    from pycocotools import mask

    only = len(set(a) ^ set(b))
    off = total = 0
    for oid in set(a) & set(b):
        ma, mb = mask.decode(a[oid]), mask.decode(b[oid])
        diff = ma != mb
        if diff.any():
            total += int(diff.sum())
            off += int((diff & ~near_edges(mb)).sum())
    return only, off, total


def bench_scene(ctx, name: str, scene, size: tuple[int, int], views: int, appearance: bool, tmp: Path) -> dict:
    s = settings(Options(views=views, size=size, appearance=appearance), [name])
    meta = object_meta(scene)
    renderer = Renderer(ctx, scene)
    row = {"name": name, "parts": scene.count, "views": views}
    try:
        for method, render in METHODS.items():  # warm-up: shaders, targets, caches
            produce_view(renderer, s, meta, (0, 0), tmp / "warm" / method, render)
        wall = {m: [] for m in METHODS}
        masks = {m: [] for m in METHODS}
        split = {m: {} for m in METHODS}
        for start in range(0, views, PER_ROUND):  # rounds: each method writes PER_ROUND views in turn
            for method, render in METHODS.items():
                ctx.finish()
                writer = Writer()
                t0 = time.perf_counter()
                for v in range(start, min(views, start + PER_ROUND)):
                    masks[method].append(
                        produce_view(renderer, s, meta, (0, v), tmp / method, render, split[method], writer)
                    )
                writer.close()
                wall[method].append(time.perf_counter() - t0)
        for m in METHODS:
            w = float(np.sum(wall[m]))
            row[m] = {
                "views_per_s": views / w,
                "masks_per_s": float(np.sum(masks[m])) / w,
                "masks_per_view": float(np.mean(masks[m])),
                "ms_per_view": {k: v / views * 1e3 for k, v in split[m].items()},
            }
        row["ratio_masks"] = row["rtta"]["masks_per_s"] / row["rtt"]["masks_per_s"]
        row["ratio_median"] = float(np.median(np.array(wall["rtt"]) / np.array(wall["rtta"])))  # per round
        row["only_one"], row["off_band_px"], row["differing_px"] = disagreement(
            _amodal(tmp / "rtta", name, 0), _amodal(tmp / "rtt", name, 0)
        )
        row["stage"] = amodal_stage(ctx, renderer, s, name, views)
    finally:
        renderer.release()
    return row


def amodal_stage(ctx, renderer, s: dict, key: str, views: int) -> dict:
    """The amodal masks alone, without what both methods share (STD, visible masks, files):
    one capture and the gather, or every object drawn alone and read back; then the same
    encoding. The methods take turns view by view."""
    w, h = s["size"]
    scene = renderer.scene
    wall = {m: [] for m in STAGES}
    masks = {m: 0 for m in STAGES}
    for v in range(views):
        camera, _ = camera_for(s, key, v, scene.center, scene.radius)
        for method, alone in STAGES.items():
            ctx.finish()
            t0 = time.perf_counter()
            objects = alone(renderer, camera, (w, h))
            _, areas, _ = encode_flat(objects.mask, objects.rects, h, w)
            wall[method].append(time.perf_counter() - t0)
            masks[method] += int((areas > 0).sum())
    out: dict[str, Any] = {
        m: {"masks_per_s": masks[m] / float(np.sum(wall[m])), "ms_per_view": float(np.mean(wall[m])) * 1e3}
        for m in STAGES
    }
    out["ratio"] = out["rtta"]["masks_per_s"] / out["rtt"]["masks_per_s"]
    return out


def run_bench(
    size: tuple[int, int],
    views: int = 5,
    quick: bool = False,
    appearance: bool = False,
    json_path: str | None = None,
    ctx=None,
) -> int:
    ctx = ctx or shared_context()
    if quick:
        size, views = (320, 240), 2
    gl_renderer = str(ctx.info["GL_RENDERER"])
    rows = []
    tmp = Path(tempfile.mkdtemp(prefix="rtta-bench-dataset-"))
    try:
        for name, load in bench_scenes(quick):
            rows.append(bench_scene(ctx, name, load(), size, views, appearance, tmp))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    _print(rows, gl_renderer, size, views, appearance)
    if json_path:
        write_text(
            json_path,
            json.dumps(
                {"renderer": gl_renderer, "size": list(size), "views": views, "appearance": appearance, "scenes": rows},
                indent=1,
            ),
        )
    return 0


def _print(rows: list[dict], gl_renderer: str, size, views: int, appearance: bool) -> None:
    print(
        f"renderer: {gl_renderer}; {size[0]}x{size[1]}; {views} views per scene, RTTA and RTT taking turns "
        f"every {PER_ROUND} views; every file written, as `rtta dataset` writes it (on a background thread)"
        f"{' with --appearance' if appearance else ''}"
    )
    print(
        f"{'scene':>12} {'parts':>6} {'masks':>6} | {'RTTA v/s':>8} {'masks/s':>8} | {'RTT v/s':>8} "
        f"{'masks/s':>8} | {'ratio':>6} {'median':>6} | {'RTTA render/annot/write ms':>27} | "
        f"{'RTT render ms':>13} | {'diff px (off band)':>18} || {'amodal only: RTTA ms':>20} "
        f"{'RTT ms':>7} {'ratio':>6}"
    )
    for r in rows:
        a, b = r["rtta"], r["rtt"]
        split = "/".join(f"{a['ms_per_view'].get(k, 0):.0f}" for k in ("render", "annotate", "write"))
        print(
            f"{r['name']:>12} {r['parts']:>6} {a['masks_per_view']:>6.0f} | {a['views_per_s']:>8.2f} "
            f"{a['masks_per_s']:>8.0f} | {b['views_per_s']:>8.2f} {b['masks_per_s']:>8.0f} | "
            f"{r['ratio_masks']:>5.2f}x {r['ratio_median']:>5.2f}x | {split:>27} | "
            f"{b['ms_per_view'].get('render', 0):>13.0f} | {r['differing_px']:>9} ({r['off_band_px']}) || "
            f"{r['stage']['rtta']['ms_per_view']:>20.1f} {r['stage']['rtt']['ms_per_view']:>7.1f} "
            f"{r['stage']['ratio']:>5.2f}x"
        )
    print(
        f"masks: amodal masks (annotations) per view; ratio: RTTA masks/s over RTT masks/s; median: of the "
        f"ratios per turn of {PER_ROUND} views; ms: per view (write: on the writer thread, overlapping the "
        f"next view); diff px: amodal pixels of view 0 where the two differ (off the 1-px silhouette band); "
        f"amodal only: ms per view to the encoded amodal masks (one capture and its gather, or every object "
        f"drawn alone and read back; no STD, no visible masks, no files), ratio of masks/s"
    )
