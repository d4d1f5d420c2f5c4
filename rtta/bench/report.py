"""`rtta bench report [--quick]`: error against run time, regenerated from measurements.

Runs the sections of report_runs.py, writes them as markdown tables between two markers in
docs/performance/report.md, a page of the docs site (the rest of the page is kept), and draws
the plots of report_plots.py into docs/bench/. Every table states the renderer, the CPU, the date and the command; every
number comes from the run.
"""

from __future__ import annotations

import math
import os
import platform
import re
import time
from pathlib import Path

from ..errors import RttaError
from ..outputs import atomic_write
from . import report_importance as importance
from . import report_runs as runs
from .reliability_table import _progress

BEGIN = "<!-- rtta bench report: begin (generated; edit report.py, not this block) -->"
END = "<!-- rtta bench report: end -->"
DEFAULT_MARKDOWN = Path("docs/performance/report.md")  # the docs site's report page
NEW_PAGE = "# `rtta bench report`: choosing settings\n\n"  # a page that does not exist yet starts so
SECTIONS = (
    "1. Reconstruction error against frame time",
    "2. Packing",
    "3. Capture cost",
    "4. Numerical stability",
    "5. Layered depth images: error against resolution and time",
    "6. Material atlas",
    "7. Importance: context scale, AO on the focus, transparency order",
)


def cpu_name() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def table(columns: list[str], rows: list[list]) -> str:
    """A markdown table; floats as given by the caller (already formatted strings)."""
    out = ["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
    out += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(out)


def _g(x: float, digits: int = 3) -> str:
    if isinstance(x, float) and not math.isfinite(x):
        return "-"
    return f"{x:.{digits}g}"


def _ticker(total: int):
    """A tick() per finished step, drawn by the reliability bench's progress bar (stderr,
    terminals only)."""
    show = _progress("report", total)
    done = [0]

    def tick() -> None:
        done[0] += 1
        if show:
            show(done[0])

    return tick


def _steps(quick: bool, scenes: int, meshes: int) -> int:
    """Ticks of the whole run, as report_runs' loops make them."""
    return (
        scenes * (4 if quick else 16)
        + 2 * (2 if quick else 4)
        + 2 * min(scenes, 2)
        + (4 if quick else 12)
        + (9 if quick else 17)
        + meshes
    )


def run_report(quick: bool = False, markdown: str | None = None, plots: str | None = None, ctx=None) -> int:
    from ..gl.context import shared_context
    from .report_plots import draw_all

    base = Path("out/report-quick") if quick else Path(".")
    md_path = Path(markdown) if markdown else (base / "report.md" if quick else DEFAULT_MARKDOWN)
    plot_dir = Path(plots) if plots else (base if quick else Path("docs/bench"))
    _check_markdown(md_path)
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        raise RttaError("needs matplotlib for its plots: pip install 'rtta[report]'") from None
    ctx = ctx or shared_context()
    viewport = (256, 256) if quick else (1024, 1024)
    header = {
        "renderer": str(ctx.info["GL_RENDERER"]),
        "cpu": cpu_name(),
        "date": time.strftime("%Y-%m-%d"),
        "command": "rtta bench report" + (" --quick" if quick else ""),
        "viewport": viewport,
    }
    scenes, meshes = runs.report_scenes(quick), runs.ldi_meshes(quick)
    important = importance.importance_scenes(scenes, quick)
    tick = _ticker(_steps(quick, len(scenes), len(meshes)) + importance.steps(len(important), quick))
    results = {
        "error": runs.error_vs_time(ctx, scenes, viewport, quick, tick),
        "packing": runs.packing(ctx, viewport, quick, tick),
        "bounds": runs.bounds_cost(ctx, scenes, viewport, quick, tick),
        "capture": runs.capture_cost(ctx, viewport, quick, tick),
        "stability": runs.stability(ctx, (256, 256) if quick else (512, 512), quick, tick),
        "ldi": runs.ldi_error(ctx, meshes, quick, tick),
        "importance": importance.importance_rows(ctx, important, viewport, quick, tick),
    }
    plot_dir.mkdir(parents=True, exist_ok=True)
    images = draw_all(results, header, plot_dir)
    text = render_markdown(results, header, images, md_path.parent)
    write_block(md_path, text)
    print(f"wrote {md_path} and {len(images)} plots in {plot_dir}")
    return 0


def _check_markdown(path: Path) -> None:
    """Refuse before measuring anything if the file has one marker but not the other."""
    if path.is_file():
        old = path.read_text()
        if (BEGIN in old) != (END in old):
            raise RttaError("has one report marker but not the other; fix it by hand", str(path))


def write_block(path: Path, text: str) -> None:
    """Replace the generated block of `path` (or append one); the rest stays as it is."""
    block = f"{BEGIN}\n{text.rstrip()}\n{END}\n"
    old = path.read_text() if path.is_file() else NEW_PAGE
    if BEGIN in old:
        new = re.sub(re.escape(BEGIN) + ".*?" + re.escape(END) + "\n?", lambda _: block, old, flags=re.S)
    else:
        new = old.rstrip() + "\n\n" + block
    atomic_write(path, lambda tmp: Path(tmp).write_text(new))


def _stamp(h: dict) -> str:
    return (
        f"renderer `{h['renderer']}`; CPU {h['cpu']}; {h['date']}; command `{h['command']}`; "
        f"viewport {h['viewport'][0]}x{h['viewport'][1]} unless stated"
    )


def render_markdown(res: dict, h: dict, images: dict, md_dir: Path) -> str:
    parts = ["## Error against run time (`rtta bench report`)", ""]
    for title, body, key in (
        (SECTIONS[0], _error_md(res["error"]), "error"),
        (SECTIONS[1], _packing_md(res["packing"], res["bounds"]), "packing"),
        (SECTIONS[2], _capture_md(res["capture"]), "capture"),
        (SECTIONS[3], _stability_md(res["stability"]), "stability"),
        (SECTIONS[4], _ldi_md(res["ldi"]), "ldi"),
    ):
        parts += [f"### {title}", "", _stamp(h), "", body, ""]
        if key in images:
            rel = os.path.relpath(images[key].resolve(), md_dir.resolve())
            parts += [f"![{title}]({Path(rel).as_posix()})", ""]
    parts += [
        f"### {SECTIONS[5]}",
        "",
        "Measured by `rtta bench material`, not by this report: see [Material atlas](material.md).",
        "",
    ]
    parts += [f"### {SECTIONS[6]}", "", _stamp(h), "", _importance_md(res["importance"]), ""]
    if "importance" in images:
        rel = os.path.relpath(images["importance"].resolve(), md_dir.resolve())
        parts += [f"![{SECTIONS[6]}]({Path(rel).as_posix()})", ""]
    return "\n".join(parts)


def _error_md(rows: list[dict]) -> str:
    cols = [
        "scene",
        "scale",
        "border",
        "frame ms",
        "pixels off > 3/255",
        "depth RMS",
        "depth max",
        "holes",
        "atlas WxHxL",
        "pareto",
    ]
    front = runs.pareto(rows)
    body = [
        [
            r["scene"],
            r["scale"],
            r["border"],
            f"{r['frame_ms']:.1f}",
            f"{r['color_off']:.3%}",
            f"{r['depth_rms']:.2e}",
            f"{r['depth_max']:.2e}",
            r["holes"],
            "x".join(map(str, r["atlas"])),
            "*" if id(r) in front else "",
        ]
        for r in rows
    ]
    note = (
        "sprites against STD from the same camera (orbit 30°, 20°, 2.2 radii); frame = capture + sprites "
        "composite, median after glFinish; depth = window depth where both cover the pixel; holes = pixels "
        "STD covers and sprites do not; pareto `*`: no other setting of the scene is both faster and "
        "more accurate."
    )
    return note + "\n\n" + table(cols, body)


def _packing_md(rows: list[dict], bounds: list[dict]) -> str:
    cols = [
        "objects",
        "packer / bounds",
        "ms per frame",
        "bounds setup ms",
        "region area / atlas",
        "covered texels / atlas",
        "layers",
    ]
    body = [
        [
            r["objects"],
            r["packer"],
            _g(r["ms"]),
            _g(r["setup_ms"]),
            _g(r["region_util"]),
            _g(r["covered_util"]),
            r["layers"],
        ]
        for r in rows
    ]
    note = (
        "random boxes and spheres (64 vertices each); shelf = our packer inside parameterization (ms "
        "= the whole parameterization); rectpack and rectangle-packer pack the same AABB regions once "
        "(ms = that one packing; `-`: rectangle-packer found no packing within one layer); obb = "
        "oriented bounds (principal-axes boxes computed once per scene: setup)."
    )
    cols2 = [
        "scene",
        "bounds",
        "setup ms (once)",
        "parameterize ms",
        "capture ms",
        "region area (px)",
        "atlas texels",
        "covered texels / atlas",
        "atlas WxHxL",
    ]
    body2 = [
        [
            r["scene"],
            r["bounds"],
            _g(r["setup_ms"]),
            _g(r["param_ms"]),
            _g(r["capture_ms"]),
            r["region_px"],
            r["atlas_texels"],
            _g(r["covered_util"]),
            "x".join(map(str, r["atlas"])),
        ]
        for r in bounds
    ]
    note2 = (
        "The paper's AABB against our oriented bounds (per object, the intersection of the projections "
        "of its AABB and of its principal-axes box) on assemblies, same camera as section 1:"
    )
    return note + "\n\n" + table(cols, body) + "\n\n" + note2 + "\n\n" + table(cols2, body2)


def _capture_md(rows: list[dict]) -> str:
    cols = ["sweep", "objects", "vertices", "STD ms", "RTT ms", "RTTA-GS ms", "RTTA-VS ms", "RTT / best RTTA"]
    body = [
        [
            r["sweep"],
            r["objects"],
            r["vertices"],
            _g(r["std_ms"]),
            _g(r["rtt_ms"]),
            _g(r["rtta_gs_ms"]),
            _g(r["rtta_vs_ms"]),
            _g(r["rtt_ms"] / min(r["rtta_gs_ms"], r["rtta_vs_ms"])),
        ]
        for r in rows
    ]
    cross = runs.crossover(rows)
    where = (
        f"RTTA is faster than RTT from **{cross} objects** on (the paper: about 20)."
        if cross
        else "RTTA never stays faster than RTT in this sweep."
    )
    return (
        "tori (Table 1 generator); objects sweep at a fixed vertex total, vertices sweep at 20 objects. "
        + where
        + "\n\n"
        + table(cols, body)
    )


def _stability_md(rows: list[dict]) -> str:
    cols = [
        "sweep",
        "value",
        "frames",
        "pixels off > 3/255 (worst)",
        "depth max",
        "NaN frames",
        "hole frames",
        "GL-error frames",
        "what the program said",
    ]
    body = [
        [
            r["sweep"],
            f"{r['value']:g}",
            r["frames"],
            f"{r['color_off']:.3%}",
            f"{r['depth_max']:.2e}",
            r["nan_frames"],
            r["hole_frames"],
            r["gl_error_frames"],
            "; ".join(r["warnings"]) or "-",
        ]
        for r in rows
    ]
    note = (
        "near/far: the demo with the near plane at far/ratio; offset: the demo rebuilt at (1, 0.5, -1) x "
        "offset; size ratio: a unit sphere touching one 1/ratio its size. Worst over the frames (orbits)."
    )
    return note + "\n\n" + table(cols, body)


def _ldi_md(rows: list[dict]) -> str:
    cols = ["mesh", "N", "layers", "points", "error", "peel ms", "test ms"]
    body = [
        [r["mesh"], r["resolution"], r["layers"], r["points"], f"{r['error']:.5f}", _g(r["peel_ms"]), _g(r["test_ms"])]
        for r in rows
    ]
    return (
        "error = fraction of random points in the bounding box classified unlike trimesh.contains; test ms "
        "= upload, test and read back, best of 3.\n\n" + table(cols, body)
    )


def _importance_md(rows: list[dict]) -> str:
    tol, budget = importance.TOLERANCE, importance.BUDGET
    cols = [
        "scene",
        "mode",
        "context scale",
        "AO on",
        "order",
        "frame ms",
        "x STD",
        f"pixels > {tol}/255",
        "MAE /255",
        "default",
    ]
    body = [
        [
            r["scene"],
            r["mode"],
            f"{r['scale']:g}",
            r["ao"],
            r["order"],
            f"{r['frame_ms']:.1f}",
            f"{r['ratio']:.2f}",
            f"{r['over']:.3%}",
            f"{255 * r['mae']:.2f}",
            "**yes**" if r["default"] else "",
        ]
        for r in rows
    ]
    note = (
        f"Focus: objects 0 and n/2; orbit 30°, 20°, 2.2 radii. Frame: capture + post + composite, median "
        f"over rounds in which STD and every setting take turns; x STD: the median over rounds of the "
        f"ratio within a round. Error against the full-quality output of the "
        f"same mode (context scale 1, AO and edges on every object; `transparent`: the exact per-pixel "
        f"order). A default must keep at most {budget:.0%} of pixels over {tol}/255 in `ghosted` and "
        f"`ghosted-ao` on every scene; among those it is the cheapest."
    )
    return note + "\n\n" + table(cols, body)
