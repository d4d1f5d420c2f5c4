"""The measurements behind `rtta bench report`: each function runs one section and returns
rows (dicts of numbers and names). Nothing here formats or writes; report.py does that."""

from __future__ import annotations

import time
import warnings

import numpy as np

from ..renderer.renderer import Renderer, Settings
from ..scene.camera import Camera
from ..scene.generators.generate import TABLE1, random_scene, table1_scene
from ..scene.model import Scene, from_meshes, oriented_corners
from .reliability import COLOR_TOL, sprites_and_std
from .render import _gl_timed, _median_ms, _rectpack, _rpack, shared_data


def sprites_error(r: Renderer, camera: Camera, viewport: tuple[int, int]) -> dict:
    """`sprites` against STD for one view: fraction of pixels off by more than 3/255, RMS and
    max window-depth error where both cover the pixel, holes (STD covers, sprites do not),
    whether records and depth are finite, and the GL error state."""
    records, finite, _, depth, std, color_diff = sprites_and_std(r, camera, viewport)
    off = color_diff > COLOR_TOL
    covered = std["id"][0] >= 0
    both = covered & (depth < 1.0)
    d = np.abs(depth[both].astype(np.float64) - std["depth"][0][both])
    return {
        "color_off": float(off.mean()),
        "depth_rms": float(np.sqrt((d**2).mean())) if d.size else 0.0,
        "depth_max": float(d.max()) if d.size else 0.0,
        "holes": int((covered & (depth >= 1.0) & off).sum()),
        "finite": finite and bool(np.isfinite(depth).all()),
        "gl_error": r.ctx.error,
        "atlas": records.atlas_size,
    }


def report_scenes(quick: bool) -> list[tuple[str, Scene]]:
    """The demo, the 2-cylinder engine when ../shared/data has it, and the Table 1 scenes."""
    from ..scene.loader import load_scene, load_scene_or_demo

    scenes = [("demo", load_scene_or_demo(None))]
    engine = shared_data() / "engine_2cyl.glb"
    if engine.is_file() and not quick:
        scenes.append(("engine_2cyl", load_scene(str(engine))))
    for objects, vertices in TABLE1[:1] if quick else TABLE1:
        scenes.append((f"table1-{objects}", table1_scene(objects, min(vertices, 20000) if quick else vertices)))
    return scenes


def _orbit(scene: Scene) -> Camera:
    return Camera.orbit(scene.center, scene.radius, 30.0, 20.0, 2.2)


def error_vs_time(ctx, scenes, viewport, quick: bool, tick) -> list[dict]:
    """Section 1: every region scale x border on every scene: sprites error and frame time
    (capture + sprites composite, median of frames after glFinish)."""
    scales = (0.5, 1.0) if quick else (0.25, 0.5, 1.0, 2.0)
    borders = (0, 1) if quick else (0, 1, 2, 4)
    frames = 3 if quick else 7
    rows = []
    for name, scene in scenes:
        cam = _orbit(scene)
        for scale in scales:
            for border in borders:
                r = Renderer(ctx, scene, Settings(border=border, region_scale=scale))
                err = sprites_error(r, cam, viewport)
                ms = _median_ms(
                    _gl_timed(ctx, lambda r=r, cam=cam: (r.capture(cam, viewport), r.composite("sprites"))), frames
                )
                r.release()
                rows.append({"scene": name, "scale": scale, "border": border, "frame_ms": ms, **err})
                tick()
    return rows


def packing(ctx, viewport, quick: bool, tick) -> list[dict]:
    """Section 2: utilization and time per frame against object count, for our shelf packer
    (AABB and oriented bounds) and, on the same regions, rectpack and rectangle-packer."""
    from ..atlas.parameterize import parameterize

    counts = (10, 100) if quick else (10, 100, 1000, 10000)
    frames = 3 if quick else 9
    rows = []
    for n in counts:
        scene = random_scene(n, seed=7, spread=4.0 * np.cbrt(n), vertices_per_object=64)
        cam = Camera.orbit(scene.center, scene.radius, 30.0, 20.0, 2.2)
        vpm = cam.projection(viewport[0] / viewport[1]) @ cam.view(scene.origin)
        for bounds in ("aabb", "obb"):
            t0 = time.perf_counter()
            corners = scene.box_corners(bounds)
            setup_ms = (time.perf_counter() - t0) * 1e3
            ms = _median_ms(lambda c=corners, m=vpm: parameterize(c, m, viewport), frames)
            r = Renderer(ctx, scene, Settings(bounds=bounds))
            rec = r.capture(cam, viewport)
            covered = _covered_texels(r, rec)
            r.release()
            sizes = rec.atlas_rect[rec.visible, 2:]
            area = float((sizes[:, 0] * sizes[:, 1]).sum())
            tw, th, td = rec.atlas_size
            rows.append(
                {
                    "objects": n,
                    "packer": f"shelf/{bounds}",
                    "ms": ms,
                    "setup_ms": setup_ms,
                    "region_util": area / (tw * th * td),
                    "covered_util": covered / (tw * th * td),
                    "layers": td,
                }
            )
            if bounds == "aabb" and n <= (100 if quick else 1000):
                rows += _other_packers(n, sizes, area, covered, viewport)
            tick()
    return rows


def bounds_cost(ctx, scenes, viewport, quick: bool, tick) -> list[dict]:
    """Section 2b: the paper's AABB against oriented bounds on real assemblies: region area,
    atlas use and the time each costs (setup once per scene, parameterize and capture per frame)."""
    frames = 3 if quick else 7
    rows = []
    for name, scene in scenes[:2]:
        cam = _orbit(scene)
        for bounds in ("aabb", "obb"):
            t0 = time.perf_counter()
            if bounds == "obb":  # what box_corners('obb') computes once per scene
                oriented_corners(scene.positions, scene.object_ids, scene.count)
            setup_ms = (time.perf_counter() - t0) * 1e3
            r = Renderer(ctx, scene, Settings(bounds=bounds))
            rec = r.capture(cam, viewport)
            covered = _covered_texels(r, rec)
            param_ms = _median_ms(lambda r=r, cam=cam: r.parameterize(cam, viewport), frames * 3)
            capture_ms = _median_ms(_gl_timed(ctx, lambda r=r, cam=cam: r.capture(cam, viewport)), frames)
            r.release()
            inner = rec.viewport_rect[rec.visible, 2:] - rec.viewport_rect[rec.visible, :2]
            tw, th, td = rec.atlas_size
            rows.append(
                {
                    "scene": name,
                    "bounds": bounds,
                    "setup_ms": setup_ms,
                    "param_ms": param_ms,
                    "capture_ms": capture_ms,
                    "region_px": int((inner[:, 0] * inner[:, 1]).sum()),
                    "atlas_texels": tw * th * td,
                    "covered_util": covered / (tw * th * td),
                    "atlas": rec.atlas_size,
                }
            )
            tick()
    return rows


def _covered_texels(r: Renderer, rec) -> int:
    tw, th, td = rec.atlas_size
    ids = r.atlas.read((tw, th), td, parts=("id",))["id"]
    return int((ids >= 0).sum())


def _other_packers(n, sizes, area, covered, viewport) -> list[dict]:
    """rectpack (MaxRects BSSF) and rectangle-packer on the regions our packer placed; they
    allocate bins of the same maximum size (viewport + border)."""
    W, H = viewport[0] + 2, viewport[1] + 2
    w, h = sizes[:, 0], sizes[:, 1]
    out = []
    t0 = time.perf_counter()
    bins, used = _rectpack(w, h, W, H)
    out.append(
        {
            "objects": n,
            "packer": "rectpack",
            "ms": (time.perf_counter() - t0) * 1e3,
            "setup_ms": 0.0,
            "region_util": area / used,
            "covered_util": covered / used,
            "layers": bins,
        }
    )
    t0 = time.perf_counter()
    used = _rpack(w, h, W, H)
    out.append(
        {
            "objects": n,
            "packer": "rectangle-packer",
            "ms": (time.perf_counter() - t0) * 1e3,
            "setup_ms": 0.0,
            "region_util": area / used,
            "covered_util": covered / used,
            "layers": 1 if np.isfinite(used) else 0,
        }
    )
    return out


def capture_cost(ctx, viewport, quick: bool, tick) -> list[dict]:
    """Section 3: STD, RTT, RTTA-GS and RTTA-VS per frame against object count (fixed
    vertex total) and against vertex count (fixed object count)."""
    from .render import capture_row

    frames = 3 if quick else 7
    by_objects = (1, 5, 20) if quick else (1, 2, 5, 10, 20, 50, 100, 300, 1000)
    by_vertices = (10_000,) if quick else (10_000, 100_000, 1_000_000)
    total = 20_000 if quick else 60_000
    rows = []
    for n in by_objects:
        rows.append({"sweep": "objects", **capture_row(ctx, table1_scene(n, max(total, 64 * n)), viewport, frames)})
        tick()
    for v in by_vertices:
        rows.append({"sweep": "vertices", **capture_row(ctx, table1_scene(20, v), viewport, frames)})
        tick()
    return rows


def crossover(rows: list[dict]) -> int | None:
    """The smallest object count from which RTTA (the faster path) stays faster than RTT."""
    obj = sorted((r for r in rows if r["sweep"] == "objects"), key=lambda r: r["objects"])
    faster = [r["rtt_ms"] > min(r["rtta_gs_ms"], r["rtta_vs_ms"]) for r in obj]
    for i, r in enumerate(obj):
        if all(faster[i:]):
            return r["objects"]
    return None


def _moved(scene: Scene, offset: float) -> Scene:
    """The scene rebuilt from float64 world vertices moved by `offset` along (1, 0.5, -1)."""
    shift = offset * np.array([1.0, 0.5, -1.0])
    parts = []
    for i, name in enumerate(scene.names):
        first, count = scene.index_ranges[i]
        f = scene.indices[first : first + count].astype(np.int64).reshape(-1, 3)
        vids = np.flatnonzero(scene.object_ids == i)
        v = scene.positions[vids].astype(np.float64) + scene.origin + shift
        parts.append((name, v, f - vids[0], scene.normals[vids]))
    return from_meshes(parts, colors=list(scene.colors), source=f"{scene.source} moved by {offset:g}")


def _two_spheres(ratio: float) -> Scene:
    """A unit sphere and one 1/ratio its size touching it."""
    import trimesh

    s = trimesh.creation.icosphere(subdivisions=3)
    small = 1.0 / ratio
    v = np.asarray(s.vertices)
    return from_meshes(
        [("large", v, s.faces, None), ("small", v * small + [1.0 + small, 0, 0], s.faces, None)],
        source=f"<spheres 1:{ratio:g}>",
    )


def stability(ctx, viewport, quick: bool, tick) -> list[dict]:
    """Section 4: sprites against STD under extreme near/far ratios, scene offsets and object
    size ratios, over a few orbit cameras each."""
    from ..scene.loader import load_scene_or_demo

    demo = load_scene_or_demo(None)
    angles = [(30.0, 20.0), (200.0, -35.0)] if quick else [(30.0, 20.0), (110.0, 60.0), (200.0, -35.0), (300.0, 5.0)]
    rows = []
    ratios = (1e2, 1e5, 1e7) if quick else (1e2, 1e3, 1e4, 1e5, 1e6, 1e7)
    for ratio in ratios:
        cams = []
        for az, el in angles:
            cam = Camera.orbit(demo.center, demo.radius, az, el, 2.2)
            cam.near = cam.far / ratio
            cams.append(cam)
        rows.append(_stability_row(ctx, demo, "near/far", ratio, cams, viewport))
        tick()
    for offset in (0.0, 1e4, 1e7) if quick else (0.0, 1e2, 1e4, 1e5, 1e6, 1e7):
        scene = _moved(demo, offset)
        rows.append(_stability_row(ctx, scene, "offset", offset, _cams(scene, angles), viewport))
        tick()
    for ratio in (1.0, 1e4, 1e8) if quick else (1.0, 1e2, 1e4, 1e6, 1e8):
        scene = _two_spheres(ratio)
        small = (scene.aabb_min[1] + scene.aabb_max[1]) / 2
        close_up = Camera.orbit(small, 1.0 / ratio, 30.0, 20.0, 2.2)  # the small one fills the view
        rows.append(_stability_row(ctx, scene, "size ratio", ratio, [*_cams(scene, angles), close_up], viewport))
        tick()
    return rows


def _cams(scene: Scene, angles) -> list[Camera]:
    return [Camera.orbit(scene.center, scene.radius, az, el, 2.2) for az, el in angles]


def _stability_row(ctx, scene: Scene, sweep: str, value: float, cams, viewport) -> dict:
    r = Renderer(ctx, scene)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        errs = [sprites_error(r, cam, viewport) for cam in cams]
    r.release()
    return {
        "sweep": sweep,
        "value": value,
        "frames": len(errs),
        "color_off": max(e["color_off"] for e in errs),
        "depth_max": max(e["depth_max"] for e in errs),
        "nan_frames": sum(not e["finite"] for e in errs),
        "hole_frames": sum(e["holes"] > 0 for e in errs),
        "gl_error_frames": sum(e["gl_error"] != "GL_NO_ERROR" for e in errs),
        "warnings": list(scene.warnings) + r.warnings,
    }


def ldi_meshes(quick: bool):
    """(name, trimesh) of section 5: the LDI benchmark's shapes (two with --quick)."""
    from .ldi import bench_meshes

    return bench_meshes(quick)[: 2 if quick else None]


def ldi_error(ctx, meshes, quick: bool, tick) -> list[dict]:
    """Section 5: LDI parity-test error against trimesh.contains, by resolution, with peel
    and test times."""
    from .ldi import error_by_resolution

    points = 20_000 if quick else 100_000
    resolutions = (64, 256) if quick else (64, 128, 256, 512, 1024)
    rows = []
    for name, mesh in meshes:
        rows += error_by_resolution(ctx, name, mesh, points, resolutions)
        tick()
    return rows


def pareto(rows: list[dict]) -> set[int]:
    """ids of the rows no other row of the same scene beats in both frame time and error."""
    out = set()
    for r in rows:
        same = [o for o in rows if o["scene"] == r["scene"] and o is not r]
        if not any(
            o["frame_ms"] <= r["frame_ms"]
            and o["color_off"] <= r["color_off"]
            and (o["frame_ms"] < r["frame_ms"] or o["color_off"] < r["color_off"])
            for o in same
        ):
            out.add(id(r))
    return out
