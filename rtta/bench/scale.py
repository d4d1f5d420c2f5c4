"""`rtta bench scale`: large assemblies, from the file to the viewer's frame rate.

For generated assemblies of 1k, 10k and 100k parts (rtta.scene.generators.assembly, written as GLB
by the bench) and the real engine when ../shared/data has it: rtta's load time against
`trimesh.load` of the same file and their peak RSS (each in a fresh process, so the peaks
are the loads' own), parameterize + pack ms, STD, capture and ghosted frame ms (in turns
within rounds, so ratios cancel a slow phase of the machine), the viewer's frames per
second in `ghosted` (`rtta-view --bench`, in a headless window where there is no display),
and per path of Algorithm 1 (CPU, GPU) a ghosted frame's Python time outside GL calls, its
wall time and its GPU time per stage (rtta.bench.frame_cost).
"""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from ..atlas.parameterize import parameterize
from ..errors import RttaError
from ..gl.context import shared_context
from ..outputs import write_text
from ..renderer.renderer import Renderer
from ..scene.camera import Camera
from ..scene.generators.assembly import write_assembly
from ..scene.loader import load_scene
from .frame_cost import frame_costs, print_costs
from .render import _gl_timed, _interleaved_ms, _median_ms, shared_data

SIZES = (1_000, 10_000, 100_000)
QUICK_SIZES = (1_000,)

_CHILD = """
import sys, time
import trimesh
path, which = sys.argv[1], sys.argv[2]
if which == "trimesh":
    t = time.perf_counter()
    trimesh.load(path, force="scene", process=False)
else:
    from rtta.scene.loader import load_scene
    from rtta.memory import steady_heap
    steady_heap()
    t = time.perf_counter()
    load_scene(path, cache=False)
seconds = time.perf_counter() - t
peak = [ln for ln in open("/proc/self/status") if ln.startswith("VmHWM:")][0].split()[1]
print(seconds, int(peak) * 1024)
"""


def load_figures(path: Path) -> dict:
    """Seconds and peak RSS (bytes, VmHWM: getrusage's maximum survives exec and would
    report the parent's) of trimesh.load and of rtta's load_scene of `path`, each in a
    fresh Python process that imported trimesh first (imports in both peaks, in neither time)."""
    out = {}
    for which in ("trimesh", "rtta"):
        proc = subprocess.run(
            [sys.executable, "-c", _CHILD, str(path), which], capture_output=True, text=True, timeout=3600
        )
        if proc.returncode:
            raise RuntimeError(f"{which} load of {path.name} failed: {proc.stderr.strip()[-400:]}")
        seconds, rss = proc.stdout.split()
        out[which] = {"s": float(seconds), "peak_rss": int(rss)}
    return out


def frame_figures(ctx, path: Path, viewport: tuple[int, int], rounds: int) -> dict:
    """Parameterize + pack, STD, capture and ghosted (capture + post + composite) ms."""
    from ..passes.composite import Style

    scene = load_scene(path)
    r = Renderer(ctx, scene)
    r.atlas_sizing = "ahead"  # as the viewer: no frame waits for the GPU to size the atlas
    cam = Camera.orbit(scene.center, scene.radius, 30.0, 20.0, 2.2)
    view, proj = r.matrices(cam, viewport)
    corners, vpm = scene.box_corners(), proj @ view
    style = Style(focus={0, scene.count // 2})

    def ghosted():
        r.capture(cam, viewport, normals=False, ids=False)
        r.composite("ghosted", style)

    times = _interleaved_ms(
        {
            "std": _gl_timed(ctx, lambda: r.std(cam, viewport)),
            "capture": _gl_timed(ctx, lambda: r.capture(cam, viewport)),
            "ghosted": _gl_timed(ctx, ghosted),
        },
        rounds,
    )
    records = r.parameterize(cam, viewport)
    row = {
        "objects": scene.count,
        "triangles": len(scene.indices) // 3,
        "param_ms": _median_ms(lambda: parameterize(corners, vpm, viewport, border=1), max(5, rounds)),
        "visible": int(records.visible.sum()),
        "atlas": list(records.atlas_size),
    }
    std = np.array(times["std"])
    for k in ("std", "capture", "ghosted"):
        row[f"{k}_ms"] = float(np.median(times[k]))
        row[f"{k}_ratio"] = float(np.median(np.array(times[k]) / std))
    r.release()
    row["cost"] = frame_costs(ctx, scene, viewport, frames=3 if rounds < 5 else 5)
    return row


def viewer_fps(path: Path, frames: int, size: str = "1280x720", navigation_fps: float | None = None) -> float | None:
    """Frames per second of `rtta-view --bench` in ghosted (fast navigation at the viewer's
    default, or keeping `navigation_fps`; 0: every part in every frame; without a display in
    a headless window); None without the viewer."""
    exe = shutil.which("rtta-view") or str(Path(sys.executable).with_name("rtta-view"))
    if not Path(exe).exists():
        return None
    flags = [] if navigation_fps is None else ["--navigation-fps", str(navigation_fps)]
    proc = subprocess.run(
        [exe, str(path), "--bench", str(frames), "--bench-modes", "ghosted", "--size", size, *flags],
        capture_output=True,
        text=True,
        timeout=3600,
    )
    rows = [ln for ln in proc.stdout.splitlines() if re.match(r"\| ghosted \|", ln)]
    return float(rows[0].split("|")[2]) if proc.returncode == 0 and rows else None


def parse_parts(text: str | None) -> tuple[int, ...] | None:
    """'1000,10000' -> (1000, 10000); RttaError for anything else."""
    if not text:
        return None
    try:
        parts = tuple(int(v) for v in text.split(","))
    except ValueError:
        raise RttaError(f"--parts expects counts like 1000,10000, got '{text}'") from None
    if not parts or min(parts) < 1 or max(parts) > 1_000_000:
        raise RttaError(f"--parts {text}: counts must be between 1 and 1,000,000")
    return parts


def run_scale(
    viewport: tuple[int, int],
    quick: bool = False,
    sizes: str | None = None,
    json_path: str | None = None,
    viewer: bool = True,
    ctx=None,
    normals: bool = False,
) -> int:
    counts = parse_parts(sizes)
    ctx = ctx or shared_context()
    renderer = str(ctx.info["GL_RENDERER"])
    rounds = 3 if quick else 7
    rows = []
    with tempfile.TemporaryDirectory(prefix="rtta-scale-") as tmp:
        tag = "assembly-n" if normals else "assembly"
        scenes = [
            (f"{tag}-{n}", write_assembly(Path(tmp) / f"assembly_{n}.glb", n, normals=normals))
            for n in (counts or (QUICK_SIZES if quick else SIZES))
        ]
        engine = shared_data() / "engine_2cyl.glb"
        if engine.exists() and not quick:
            scenes.append(("engine_2cyl", engine))
        for name, path in scenes:
            row = {"scene": name, **frame_figures(ctx, path, viewport, rounds), "load": load_figures(path)}
            frames = 3 if quick else 10
            row["viewer_fps"] = viewer_fps(path, frames) if viewer else None
            row["viewer_fps_exact"] = viewer_fps(path, frames, navigation_fps=0) if viewer else None
            rows.append(row)
            _print_row(row, len(rows) == 1, renderer, viewport)
    print_costs([r["cost"] for r in rows], renderer, viewport)
    if json_path:
        write_text(json_path, json.dumps({"renderer": renderer, "viewport": list(viewport), "scenes": rows}, indent=1))
    return 0


def _print_row(r: dict, header: bool, renderer: str, viewport: tuple[int, int]) -> None:
    if header:
        print(
            f"renderer: {renderer}; viewport {viewport[0]}x{viewport[1]}; load and peak RSS each in a fresh "
            "process; frame ms are medians over rounds of STD, capture and ghosted in turn, ratios to STD "
            "taken within each round; viewer: rtta-view --bench in ghosted at 1280x720, with fast navigation "
            "(at the viewer's default frame rate) and exact (--navigation-fps 0: every part in every frame)"
        )
        print(
            "| scene | parts | triangles | load s | trimesh.load s | load / trimesh | peak RSS MB | "
            "trimesh RSS MB | RSS / trimesh | param+pack ms | STD ms | capture ms (x STD) | "
            "ghosted ms (x STD) | viewer fps | viewer fps exact |"
        )
        print("|---" * 15 + "|")
    ld = r["load"]
    fps, exact = ("n/a" if r[k] is None else f"{r[k]:.1f}" for k in ("viewer_fps", "viewer_fps_exact"))
    print(
        f"| {r['scene']} | {r['objects']:,} | {r['triangles']:,} | {ld['rtta']['s']:.2f} | {ld['trimesh']['s']:.2f} "
        f"| {ld['rtta']['s'] / ld['trimesh']['s']:.2f} | {ld['rtta']['peak_rss'] / 2**20:.0f} "
        f"| {ld['trimesh']['peak_rss'] / 2**20:.0f} | {ld['rtta']['peak_rss'] / ld['trimesh']['peak_rss']:.2f} "
        f"| {r['param_ms']:.1f} | {r['std_ms']:.1f} | {r['capture_ms']:.1f} ({r['capture_ratio']:.2f}x) "
        f"| {r['ghosted_ms']:.1f} ({r['ghosted_ratio']:.2f}x) | {fps} | {exact} |",
        flush=True,
    )
