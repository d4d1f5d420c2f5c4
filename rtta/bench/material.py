"""`rtta bench material`: a generated scene of textured objects drawn without batching (one
draw call and texture bind per object), batched through the material atlas (one call), and
batched with BVH chunks frustum-culled (Knecht & Mattausch); atlas memory against the
original textures; and the textured scene's RTTA capture against the untextured one."""

from __future__ import annotations

import json
import platform
from dataclasses import replace
from functools import partial

from ..gl.context import shared_context
from ..gl.targets import LayeredTarget
from ..outputs import write_text
from ..passes.batching import ChunkedStdPass, SeparatePass
from ..renderer.renderer import Renderer
from ..scene.camera import Camera
from ..scene.generators.textured import textured_scene
from ..scene.material_atlas import original_nbytes
from .render import _gl_timed, _median_ms
from .tables import print_table

COLUMNS = ["view", "method", "draw calls", "frame ms"]


def _views(scene):
    """The seed's two walkthrough cases: an overview and a close-up where most is culled."""
    return [
        ("overview", Camera.orbit(scene.center, scene.radius, 0.0, 0.0, 1.4)),
        ("close-up", Camera.orbit(scene.center, scene.radius, 0.0, 0.0, 0.12)),
    ]


def _frame(r, pass_, cam, view, proj, target, viewport):
    """One STD frame: batched through the renderer, or through `pass_` into `target`."""
    if pass_ is None:
        return partial(r.std, cam, viewport)
    return partial(pass_.render, gpu=r.gpu, view=view, proj=proj, target=target, viewport=viewport)


def frame_rows(ctx, scene, viewport, frames: int, max_vertices: int) -> tuple[list[list], dict]:
    r = Renderer(ctx, scene)
    sep, chunked = SeparatePass(ctx), ChunkedStdPass(ctx, max_vertices)
    target = LayeredTarget(ctx, viewport, 1, normals=False)  # as the renderer's STD target
    rows = []
    try:
        for name, cam in _views(scene):
            view, proj = r.matrices(cam, viewport)
            runs = [
                ("separate textures, one call per object", sep, lambda: sep.draw_calls),
                ("material atlas, one batch", None, lambda: 1),
                (f"material atlas, BVH chunks <= {max_vertices} vertices, culled", chunked, lambda: chunked.draw_calls),
            ]
            for label, pass_, calls in runs:
                ms = _median_ms(_gl_timed(ctx, _frame(r, pass_, cam, view, proj, target, viewport)), frames)
                rows.append([name, label, calls(), f"{ms:.2f}"])
            ms = _median_ms(_gl_timed(ctx, partial(r.capture, cam, viewport)), frames)
            rows.append([name, "RTTA capture, textured (one call)", 1, f"{ms:.2f}"])
        plain = Renderer(ctx, replace(scene, textures=[], uvs=None, texture_ids=None, _corners={}))
        try:
            for name, cam in _views(scene):
                ms = _median_ms(_gl_timed(ctx, partial(plain.capture, cam, viewport)), frames)
                rows.append([name, "RTTA capture, same scene untextured", 1, f"{ms:.2f}"])
        finally:
            plain.release()
        leaves = len(chunked.bvh(r.gpu).leaves)
        info = r.gpu.atlas_info
        if info is None:
            raise ValueError("the material bench needs a textured scene (it has no material atlas)")
        memory = {
            "textures": len(scene.textures),
            "original_bytes": original_nbytes(scene.textures),
            "atlas_bytes": info.nbytes,
            "atlas": f"{info.size}x{info.size}x{info.layers}",
            "levels": info.levels,
            "bvh_leaves": leaves,
        }
    finally:
        for p in (sep, chunked, target):
            p.release()
        r.release()
    return rows, memory


def run_material(
    objects: int,
    quick: bool = False,
    json_path: str | None = None,
    viewport: tuple[int, int] = (1024, 768),
    max_vertices: int = 480,
) -> int:
    ctx = shared_context()
    renderer = ctx.info["GL_RENDERER"]
    frames = 5 if quick else 30
    scene = textured_scene(objects, seed=1, textures=48 if not quick else 16, untextured_every=9)
    print(
        f"renderer: {renderer}; cpu: {platform.processor() or platform.machine()}; viewport "
        f"{viewport[0]}x{viewport[1]}; {scene.count} objects, {len(scene.textures)} textures, "
        f"{scene.vertex_count} vertices; median of {frames} frames"
    )
    rows, memory = frame_rows(ctx, scene, viewport, frames, max_vertices)
    print_table(COLUMNS, rows)
    ratio = memory["atlas_bytes"] / memory["original_bytes"]
    print(
        f"memory: {memory['textures']} textures with full mip chains {memory['original_bytes'] / 2**20:.2f} MiB; "
        f"atlas {memory['atlas']} with levels 0..{memory['levels']} {memory['atlas_bytes'] / 2**20:.2f} MiB "
        f"({ratio:.2f}x); BVH leaves: {memory['bvh_leaves']}"
    )
    if json_path:
        write_text(
            json_path,
            json.dumps(
                {
                    "renderer": renderer,
                    "objects": scene.count,
                    "rows": [dict(zip(COLUMNS, r, strict=True)) for r in rows],
                    "memory": memory,
                },
                indent=1,
            ),
        )
    return 0
