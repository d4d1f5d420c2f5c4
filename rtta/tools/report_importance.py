"""Section 7 of `rtta bench report`: what importance-driven capture and shading cost in error
and save in time (issue 24). Per scene: `ghosted` at context scales 1, 0.5, 0.25;
`ghosted-ao` at those scales with AO on the focus objects or on all; `transparent` in object
and in pixel order. Error is against the full-quality output of the same mode (scale 1, AO
and edges on every object; for `transparent` the exact per-pixel order): the share of pixels
off by more than 8/255 and the mean absolute error; time is a whole frame (capture, post,
composite), median after glFinish, with STD from the same run for the ratio."""

from __future__ import annotations

import numpy as np

from ..passes.composite import Style
from ..renderer.renderer import Renderer, Settings
from .bench import _gl_timed, _median_ms

SCALES = (1.0, 0.5, 0.25)
TOLERANCE = 8            # /255: a pixel is off beyond it
BUDGET = 0.01            # share of pixels off that a default may leave


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
    ok = c["scale"] == Settings.context_scale and c["order"] in ("object", style.order)
    if c["mode"] == "transparent":
        return c["order"] == style.order
    return ok and (c["ao"] == "-" or c["ao"] == style.ao_objects)


def importance_scenes(scenes, quick: bool) -> list:
    """The demo, the engine and the 580-part scene of the report's scenes (quick: the first two)."""
    return scenes[:2] if quick else [s for s in scenes if s[0] in ("demo", "engine_2cyl", "table1-580")]


def steps(scenes: int, quick: bool) -> int:
    return scenes * len(_configs(quick))


def importance_rows(ctx, scenes, viewport, quick: bool, tick) -> list[dict]:
    from .report_runs import _orbit

    frames = 2 if quick else 5
    rows = []
    for name, scene in scenes:
        cam = _orbit(scene)
        focus = {0, scene.count // 2}
        std = Renderer(ctx, scene)
        std_ms = _median_ms(_gl_timed(ctx, lambda r=std, cam=cam: r.std(cam, viewport)), frames)
        std.release()
        refs = {}
        for c in _configs(quick):
            r = Renderer(ctx, scene, Settings(context_scale=c["scale"]))
            style = _style(c, focus)

            def frame(r=r, cam=cam, c=c, style=style):
                r.capture(cam, viewport, focus=style.focus)
                return r.composite(c["mode"], style)

            img = frame().read()[0][..., :3].astype(np.int64)
            refs.setdefault(c["mode"], img)      # the first config of a mode is its reference
            ms = _median_ms(_gl_timed(ctx, frame), frames)
            r.release()
            diff = np.abs(img - refs[c["mode"]])
            rows.append({"scene": name, **c, "frame_ms": ms, "std_ms": std_ms,
                         "over": float((diff.max(-1) > TOLERANCE).mean()), "mae": float(diff.mean() / 255.0),
                         "default": _is_default(c)})
            tick()
    return rows
