"""A render loop on a moderngl context of your own: orbit the camera, capture, composite.

`rtta.snapshot` hides the context and the frames; a `rtta.Renderer` takes any moderngl
context (here a standalone one through EGL, no window or display needed; in an app, the
window's) and gives control over every frame: `capture` packs the atlas for a camera and
draws every part into it, `composite` makes a mode's picture from the last capture (a
change of mode or style alone captures nothing again). The last frame of the orbit is saved.

    python examples/own_context.py [OUT_DIR]     # writes OUT_DIR/own_context.png
"""

import sys
import time
from pathlib import Path

import moderngl
from PIL import Image

import rtta
from rtta.scene.generators.demo import demo_path  # the shipped demo brake (a .glb file)


def main(out: Path) -> Path:
    ctx = moderngl.create_standalone_context(backend="egl", require=430)  # or rtta.create_headless_context()
    scene = rtta.load_scene(demo_path())
    renderer = rtta.Renderer(ctx, scene, rtta.Settings(border=1))
    # the ghosted style: caliper and pads in focus (object ids), the rest faded around them
    style = rtta.Style(focus={scene.names.index(n) for n in ("caliper", "pad_outer", "pad_inner")})
    style.context_opacity = 0.25
    viewport = (480, 360)
    frames = 12
    t0 = time.perf_counter()
    for k in range(frames):  # a quarter turn about the up axis, ending at azimuth 60
        camera = rtta.Camera.orbit(scene.center, scene.radius, -30 + 90 * k / (frames - 1), 20, 2.0)
        renderer.capture(camera, viewport, focus=style.focus)  # parameterize + one draw into the atlas
        rgba, depth = renderer.composite("ghosted-ao", style).read()  # row 0 is the bottom row
    ms = (time.perf_counter() - t0) * 1e3 / frames
    print(f"{frames} frames, {ms:.1f} ms a frame (capture, composite and read back)")
    path = out / "own_context.png"
    Image.fromarray(rgba[::-1]).save(path)  # flip to top row first
    renderer.release()  # the renderer frees its GPU resources; the context is ours to release
    ctx.release()
    return path


if __name__ == "__main__":
    out = Path(sys.argv[1] if sys.argv[1:] else "out/examples")
    out.mkdir(parents=True, exist_ok=True)
    print("wrote", main(out))
