"""Section 7 of `rtta bench report`: what importance-driven capture and shading cost in error
and save in time (issue 24). Per scene: `ghosted` at context scales 1, 0.5, 0.25;
`ghosted-ao` at those scales with AO on the focus objects or on all; `transparent` in object
and in pixel order. Error is against the full-quality output of the same mode (scale 1, AO
and edges on every object; for `transparent` the exact per-pixel order): the share of pixels
off by more than 8/255 and the mean absolute error; time is a whole frame (capture, post,
composite) after glFinish, STD and every setting taking turns within each round."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ..passes.composite import Style
from ..passes.oit import resolved_order
from ..passes.style import Mode
from ..renderer.renderer import Renderer, Settings
from .render import _gl_timed, _interleaved_ms

SCALES = (1.0, 0.5, 0.25)
TOLERANCE = 8  # /255: a pixel is off beyond it
BUDGET = 0.01  # share of pixels off that a default may leave


def _configs(quick: bool) -> list[dict]:
    scales = (1.0, 0.5) if quick else SCALES
    out = [{"mode": "ghosted", "scale": s, "ao": "-", "order": "object"} for s in scales]
    out += [{"mode": "ghosted-ao", "scale": s, "ao": ao, "order": "object"} for s in scales for ao in ("all", "focus")]
    out += [{"mode": "transparent", "scale": 1.0, "ao": "-", "order": o} for o in ("pixel", "object")]
    return out


def _style(c: dict, focus: set[int]) -> Style:
    return Style(focus=focus, ao_objects="all" if c["ao"] == "-" else c["ao"], order=c["order"])


def _is_default(c: dict) -> bool:
    style = Style()
    order = c["order"] == resolved_order(style.order, c["mode"])
    if c["mode"] == "transparent":
        return order
    ok = c["scale"] == Settings.context_scale and order
    return ok and (c["ao"] == "-" or c["ao"] == style.ao_objects)


def importance_scenes(scenes, quick: bool) -> list:
    """The demo, the engine and the 580-part scene of the report's scenes (quick: the first two)."""
    return scenes[:2] if quick else [s for s in scenes if s[0] in ("demo", "engine_2cyl", "table1-580")]


def steps(scenes: int, quick: bool) -> int:
    return scenes * len(_configs(quick))


def _frame(r: Renderer, cam, viewport, mode: str, style: Style):
    def frame():
        r.capture(cam, viewport, focus=style.focus, normals=r.needs_normals(mode), ids=False)
        return r.composite(Mode(mode), style)

    return frame


def importance_rows(ctx, scenes, viewport, quick: bool, tick) -> list[dict]:
    """One row per scene and setting; STD and the settings take turns within each round
    (bench._interleaved_ms), and the ratio to STD is the median over rounds of the ratio
    within a round, so a slow phase of a shared machine cancels."""
    from .report_runs import _orbit

    frames = 3 if quick else 7
    rows = []
    for name, scene in scenes:
        cam = _orbit(scene)
        focus = {0, scene.count // 2}
        configs = _configs(quick)
        renderers = [Renderer(ctx, scene, Settings(context_scale=c["scale"])) for c in configs]
        frames_of = {
            k: _frame(r, cam, viewport, c["mode"], _style(c, focus))
            for k, (c, r) in enumerate(zip(configs, renderers, strict=True))
        }
        refs, images = {}, {}
        for k, c in enumerate(configs):
            images[k] = frames_of[k]().read()[0][..., :3].astype(np.int64)
            refs.setdefault(c["mode"], images[k])  # the first setting of a mode is its reference
        fns: dict[str | int, Callable[[], None]] = {
            "std": _gl_timed(ctx, lambda r=renderers[0], cam=cam: r.std(cam, viewport))
        }
        fns.update({k: _gl_timed(ctx, f) for k, f in frames_of.items()})
        times = _interleaved_ms(fns, frames)
        std = np.array(times["std"])
        for k, c in enumerate(configs):
            diff = np.abs(images[k] - refs[c["mode"]])
            rows.append(
                {
                    "scene": name,
                    **c,
                    "frame_ms": float(np.median(times[k])),
                    "std_ms": float(np.median(std)),
                    "ratio": float(np.median(np.array(times[k]) / std)),
                    "over": float((diff.max(-1) > TOLERANCE).mean()),
                    "mae": float(diff.mean() / 255.0),
                    "default": _is_default(c),
                }
            )
            tick()
        for r in renderers:
            r.release()
    return rows
