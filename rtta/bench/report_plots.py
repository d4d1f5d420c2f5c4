"""Plots of `rtta bench report` (matplotlib, Agg): one PNG per section, axes with units,
legends, and the renderer in the title."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..outputs import atomic_write

SCALE_COLORS = {0.25: "tab:red", 0.5: "tab:orange", 1.0: "tab:green", 2.0: "tab:blue"}
BORDER_MARKERS = {0: "o", 1: "s", 2: "^", 4: "D"}


def _figure(rows: int, cols: int, w: float, h: float):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(rows, cols, figsize=(w, h), squeeze=False)
    return plt, fig, axes


def _save(plt, fig, path: Path, header: dict, layout: bool = True) -> Path:
    fig.suptitle(f"{header['renderer']} - {header['date']} - {header['command']}", fontsize=8, y=0.995)
    if layout:
        fig.tight_layout()
    atomic_write(path, lambda tmp: fig.savefig(tmp, format="png", dpi=110))
    plt.close(fig)
    return path


def error_plot(rows: list[dict], header: dict, path: Path) -> Path:
    from .report_runs import pareto

    scenes = list(dict.fromkeys(r["scene"] for r in rows))
    cols = min(3, len(scenes))
    nrows = -(-len(scenes) // cols)
    plt, fig, axes = _figure(nrows, cols, 4.2 * cols, 3.6 * nrows)
    front = pareto(rows)
    for ax, scene in zip(axes.flat, scenes, strict=False):
        mine = [r for r in rows if r["scene"] == scene]
        for r in mine:
            ax.scatter(
                r["frame_ms"],
                100 * r["color_off"],
                c=SCALE_COLORS.get(r["scale"], "k"),
                marker=BORDER_MARKERS.get(r["border"], "x"),
                s=40,
                edgecolors="k",
                linewidths=0.4,
            )
        best = sorted((r for r in mine if id(r) in front), key=lambda r: r["frame_ms"])
        ax.plot([r["frame_ms"] for r in best], [100 * r["color_off"] for r in best], "k--", lw=0.8)
        ax.set_title(scene, fontsize=9)
        ax.set_xlabel("frame time, capture + sprites (ms)")
        ax.set_ylabel("pixels off by > 3/255 (%)")
        ax.set_yscale("symlog", linthresh=0.01)
        ax.grid(alpha=0.3)
    for ax in list(axes.flat)[len(scenes) :]:
        ax.axis("off")
    handles = [plt.Line2D([], [], ls="", marker="o", color=c, label=f"scale {s:g}") for s, c in SCALE_COLORS.items()]
    handles += [
        plt.Line2D([], [], ls="", marker=m, color="gray", label=f"border {b}") for b, m in BORDER_MARKERS.items()
    ]
    handles.append(plt.Line2D([], [], ls="--", color="k", label="Pareto front"))
    fig.legend(handles=handles, fontsize=8, loc="lower center", ncol=len(handles))
    fig.tight_layout(rect=(0, 0.05, 1, 0.98))
    return _save(plt, fig, path, header, layout=False)


def packing_plot(rows: list[dict], header: dict, path: Path) -> Path:
    plt, fig, axes = _figure(1, 3, 13, 3.8)
    packers = list(dict.fromkeys(r["packer"] for r in rows))
    for p in packers:
        mine = sorted((r for r in rows if r["packer"] == p), key=lambda r: r["objects"])
        n = [r["objects"] for r in mine]
        axes[0, 0].plot(n, [r["region_util"] for r in mine], "o-", label=p)
        axes[0, 1].plot(n, [r["covered_util"] for r in mine], "o-", label=p)
        axes[0, 2].plot(n, [r["ms"] for r in mine], "o-", label=p)
    labels = ("region area / allocated atlas area", "covered texels / allocated atlas area", "time per frame (ms)")
    for ax, label in zip(axes.flat, labels, strict=True):
        ax.set_xscale("log")
        ax.set_xlabel("objects")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    axes[0, 2].set_yscale("log")
    return _save(plt, fig, path, header)


def capture_plot(rows: list[dict], header: dict, path: Path) -> Path:
    plt, fig, axes = _figure(1, 2, 10, 3.8)
    paths = (
        ("std_ms", "STD"),
        ("rtt_ms", "RTT"),
        ("rtta_gs_ms", "RTTA geometry shader"),
        ("rtta_vs_ms", "RTTA vertex shader"),
    )
    for ax, sweep, xkey, xlabel in (
        (axes[0, 0], "objects", "objects", "objects (fixed vertex total)"),
        (axes[0, 1], "vertices", "vertices", "vertices (20 objects)"),
    ):
        mine = sorted((r for r in rows if r["sweep"] == sweep), key=lambda r: r[xkey])
        for key, label in paths:
            ax.plot([r[xkey] for r in mine], [r[key] for r in mine], "o-", label=label)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel(xlabel)
        ax.set_ylabel("capture time per frame (ms)")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=7)
    return _save(plt, fig, path, header)


def stability_plot(rows: list[dict], header: dict, path: Path) -> Path:
    plt, fig, axes = _figure(1, 3, 13, 3.8)
    for ax, sweep, xlabel in zip(
        axes.flat,
        ("near/far", "offset", "size ratio"),
        ("far / near", "scene offset (world units; 0 drawn at 1)", "object size ratio"),
        strict=True,
    ):
        mine = sorted((r for r in rows if r["sweep"] == sweep), key=lambda r: r["value"])
        x = np.maximum([r["value"] for r in mine], 1.0)
        ax.plot(x, np.maximum([r["depth_max"] for r in mine], 1e-9), "o-", label="max depth error (window)")
        ax.plot(x, np.maximum([r["color_off"] for r in mine], 1e-9), "s--", label="fraction of pixels off")
        bad = [xi for xi, r in zip(x, mine, strict=True) if r["nan_frames"] or r["hole_frames"] or r["gl_error_frames"]]
        if bad:
            ax.scatter(bad, [1.0] * len(bad), marker="x", c="r", s=60, label="NaN, holes or GL errors")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_ylim(1e-9, 2)
        ax.set_xlabel(xlabel)
        ax.set_ylabel("sprites vs STD (floor 1e-9)")
        ax.set_title(sweep, fontsize=9)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    return _save(plt, fig, path, header)


def ldi_plot(rows: list[dict], header: dict, path: Path) -> Path:
    plt, fig, axes = _figure(1, 2, 10, 3.8)
    for mesh in dict.fromkeys(r["mesh"] for r in rows):
        mine = sorted((r for r in rows if r["mesh"] == mesh), key=lambda r: r["resolution"])
        n = [r["resolution"] for r in mine]
        axes[0, 0].plot(n, [max(r["error"], 1e-6) for r in mine], "o-", label=mesh)
        axes[0, 1].plot(
            [r["peel_ms"] + r["test_ms"] for r in mine], [max(r["error"], 1e-6) for r in mine], "o-", label=mesh
        )
    axes[0, 0].set_xlabel("LDI resolution N (texels per side)")
    axes[0, 1].set_xlabel("peel + parity test time (ms)")
    for ax in axes.flat:
        ax.set_xscale("log", base=2 if ax is axes[0, 0] else 10)
        ax.set_yscale("log")
        ax.set_ylabel("points classified unlike trimesh (fraction)")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=7)
    return _save(plt, fig, path, header)


def draw_all(results: dict, header: dict, folder: Path) -> dict[str, Path]:
    return {
        "error": error_plot(results["error"], header, folder / "error_vs_time.png"),
        "packing": packing_plot(results["packing"], header, folder / "packing.png"),
        "capture": capture_plot(results["capture"], header, folder / "capture.png"),
        "stability": stability_plot(results["stability"], header, folder / "stability.png"),
        "ldi": ldi_plot(results["ldi"], header, folder / "ldi.png"),
        "importance": importance_plot(results["importance"], header, folder / "importance.png"),
    }


def importance_plot(rows: list[dict], header: dict, path: Path) -> Path:
    from .report_importance import BUDGET, TOLERANCE

    scenes = list(dict.fromkeys(r["scene"] for r in rows))
    plt, fig, axes = _figure(1, len(scenes), 4.4 * len(scenes), 3.8)
    marks = {"ghosted": "o", "ghosted-ao": "s", "transparent": "^"}
    colors = {1.0: "tab:blue", 0.5: "tab:orange", 0.25: "tab:red"}
    for ax, scene in zip(np.atleast_1d(axes).flat, scenes, strict=False):
        for r in (r for r in rows if r["scene"] == scene):
            face = colors.get(r["scale"], "k") if r["ao"] != "focus" and r["order"] != "pixel" else "white"
            ax.scatter(
                r["ratio"],
                100 * r["over"] + 1e-3,
                marker=marks[r["mode"]],
                s=60 if r["default"] else 30,
                facecolors=face,
                edgecolors=colors.get(r["scale"], "k"),
                linewidths=2.0 if r["default"] else 0.8,
            )
        ax.axhline(100 * BUDGET, color="gray", ls=":", lw=0.8)
        ax.set_title(scene, fontsize=9)
        ax.set_xlabel("frame time / STD")
        ax.set_ylabel(f"pixels off by > {TOLERANCE}/255 (%)")
        ax.set_yscale("symlog", linthresh=0.01)
        ax.set_ylim(bottom=0)
        ax.grid(alpha=0.3)
    handles = [plt.Line2D([], [], ls="", marker=m, color="gray", label=k) for k, m in marks.items()]
    handles += [plt.Line2D([], [], ls="", marker="o", color=c, label=f"context scale {s:g}") for s, c in colors.items()]
    handles.append(plt.Line2D([], [], ls="", marker="o", mfc="white", color="gray", label="AO on focus / pixel order"))
    handles.append(plt.Line2D([], [], ls="", marker="o", mew=2.0, color="k", label="default (large)"))
    fig.legend(handles=handles, fontsize=7, loc="lower center", ncol=4)
    fig.tight_layout(rect=(0, 0.12, 1, 0.98))
    return _save(plt, fig, path, header, layout=False)
