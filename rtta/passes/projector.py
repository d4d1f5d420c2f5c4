"""A projector that paints the scene (projective texturing, seed 004): an image projected
from a position, direction, fov and aspect; texture coordinates bias · P · V · world divided
by q per fragment, nothing behind the projector, and optional shadowing by a depth map
rendered from the projector.

`ProjectorPass` renders the shadow map and binds what the scene and composite shaders read
(`shaders/projector.glsl`): STD paints per fragment, the composited modes paint each sprite
texel at the world position reconstructed from its atlas depth.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import moderngl
import numpy as np

from ..gl import glsl
from ..gl.bindings import Texture
from ..gl.glsl import mat_bytes
from ..gl.gpu import GpuScene
from ..scene.camera import Camera
from .capture import ScenePass

BIAS = np.array([[0.5, 0, 0, 0.5], [0, 0.5, 0, 0.5], [0, 0, 0.5, 0.5], [0, 0, 0, 1.0]])
SHADOW_SIZE = 1024
SHADOW_BIAS = 0.005  # a surface is shadowed when something is nearer to the projector by > 0.5%


def default_image(size: int = 256) -> np.ndarray:
    """The shipped projector image (RGBA uint8, top row first): a grid of 8x8 coloured cells
    with a white frame and a black cross, asymmetric so orientation shows (red top-left)."""
    cells = 8
    y, x = np.mgrid[0:size, 0:size]
    cy, cx = y * cells // size, x * cells // size
    hue = np.stack([(cx + 1) / cells, (cells - cy) / cells, 0.35 + 0.4 * ((cx + cy) % 2)], -1)
    img = (hue * 255).astype(np.uint8)
    img[(cx == 0) & (cy == 0)] = (230, 40, 40)
    line = (x % (size // cells) < 2) | (y % (size // cells) < 2) | (x >= size - 2) | (y >= size - 2)
    img[line] = 255
    cross = (np.abs(x - size // 2) < 2) | (np.abs(y - size // 2) < 2)
    img[cross] = 0
    return np.concatenate([img, np.full((size, size, 1), 255, np.uint8)], -1)


def load_image(path: str | Path) -> np.ndarray:
    """An image file as RGBA uint8 (top row first); RttaError naming the file otherwise (not a
    regular file, damaged, or too many pixels: checked from the header before decoding)."""
    from ..scene.files import open_image

    with open_image(Path(path), "image") as im:
        return np.asarray(im.convert("RGBA"))


@dataclass
class Projector:
    """eye/target/up in world space; image RGBA uint8 (top row first); aspect None = the image's."""

    eye: np.ndarray
    target: np.ndarray
    up: np.ndarray = field(default_factory=lambda: np.array([0.0, 1.0, 0.0]))
    fov_y: float = 30.0
    aspect: float | None = None
    image: np.ndarray = field(default_factory=default_image)
    strength: float = 1.0
    shadows: bool = True
    near: float = 0.01
    far: float = 100.0

    @classmethod
    def orbit(cls, center, radius: float, az: float, el: float, dist: float, up_axis: str = "y", **kw) -> Projector:
        cam = Camera.orbit(center, radius, az, el, dist, up_axis=up_axis)
        return cls(eye=cam.eye, target=cam.target, up=cam.up, **kw).fit_depth(center, radius)

    @classmethod
    def at_camera(cls, camera: Camera, center, radius: float, **kw) -> Projector:
        """Attached to a camera: the same eye, target and up."""
        return cls(eye=camera.eye.copy(), target=camera.target.copy(), up=camera.up.copy(), **kw).fit_depth(
            center, radius
        )

    def fit_depth(self, center, radius: float) -> Projector:
        cam = Camera(eye=self.eye, target=self.target, up=self.up).fit_depth(center, radius)
        self.near, self.far = cam.near, cam.far
        return self

    @property
    def image_aspect(self) -> float:
        return self.aspect or self.image.shape[1] / self.image.shape[0]

    def camera(self) -> Camera:
        return Camera(eye=self.eye, target=self.target, up=self.up, fov_y=self.fov_y, near=self.near, far=self.far)

    def view_projection(self, origin) -> np.ndarray:
        """P · V for world positions relative to `origin` (what the shadow map is drawn with)."""
        cam = self.camera()
        return cam.projection(self.image_aspect) @ cam.view(origin)

    def matrix(self, origin) -> np.ndarray:
        """bias · P · V: world (relative to origin) -> homogeneous (s, t, r, q)."""
        return BIAS @ self.view_projection(origin)

    def key(self) -> tuple:
        return (
            tuple(self.eye),
            tuple(self.target),
            tuple(self.up),
            self.fov_y,
            self.image_aspect,
            self.near,
            self.far,
            id(self.image),
            self.strength,
            self.shadows,
        )


class ProjectorPass:
    """render(*, gpu, projector): the shadow map (depth from the projector) and the image
    texture; bind(program, origin) sets what shaders/projector.glsl reads."""

    def __init__(self, ctx: moderngl.Context) -> None:
        self.ctx = ctx
        self.shadow = ScenePass(ctx, fragment="depth.frag")
        self.depth = ctx.depth_texture((SHADOW_SIZE, SHADOW_SIZE))
        self.depth.compare_func = ""  # sampled as a plain depth value, compared in the shader
        self.depth.filter = (moderngl.NEAREST, moderngl.NEAREST)
        self.depth.repeat_x = self.depth.repeat_y = False
        self.fbo = ctx.framebuffer(depth_attachment=self.depth)
        self.image: moderngl.Texture | None = None
        self._image_id: int | None = None
        self._key: tuple | None = None

    def render(self, *, gpu: GpuScene, projector: Projector, ranges: list[tuple[int, int]] | None = None) -> None:
        """Upload the image and draw the shadow map when the projector changed; `ranges`:
        the (first, count) index runs of the objects shown (None: all; hidden ones cast no shadow)."""
        if id(projector.image) != self._image_id:
            self._upload(projector.image)
            self._image_id = id(projector.image)
        placed = None if gpu.placement is None else gpu.placement.serial  # cut, exploded
        key = (projector.key(), None if ranges is None else tuple(ranges), placed)
        if key == self._key:
            return
        vao = self.shadow.setup(gpu, np.identity(4), projector.view_projection(gpu.scene.origin))
        self.fbo.clear(depth=1.0)
        self.fbo.use()
        if ranges is None:
            vao.render(moderngl.TRIANGLES)
        for first, count in ranges or ():
            vao.render(moderngl.TRIANGLES, vertices=count, first=first)
        self._key = key

    def _upload(self, rgba: np.ndarray) -> None:
        if self.image is not None:
            self.image.release()
        h, w = rgba.shape[:2]
        self.image = self.ctx.texture((w, h), 4, np.ascontiguousarray(rgba[::-1]).tobytes())  # row 0 = t 0
        self.image.filter = (moderngl.LINEAR, moderngl.LINEAR)
        self.image.repeat_x = self.image.repeat_y = False

    def bind(self, program: moderngl.Program, projector: Projector, origin) -> None:
        glsl.uniform(program, "u_projector").write(mat_bytes(projector.matrix(origin)))
        for name, value in (
            ("u_projector_strength", float(projector.strength)),
            ("u_projector_shadows", int(projector.shadows)),
            ("u_projector_bias", SHADOW_BIAS),
            ("u_projector_range", (projector.near, projector.far)),
        ):
            if name in program:
                glsl.uniform(program, name).value = value
        if self.image is None:
            raise RuntimeError("ProjectorPass: render() a projector before binding it")
        self.image.use(Texture.PROJECTOR_IMAGE)
        self.depth.use(Texture.PROJECTOR_DEPTH)

    def release(self) -> None:
        from ..gl.targets import release_framebuffer

        release_framebuffer(self.ctx, self.fbo)
        self.shadow.release()
        for obj in (self.depth, self.image):
            if obj is not None:
                obj.release()
