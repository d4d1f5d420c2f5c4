"""`Capture`: one captured frame as arrays, what `rtta.capture` gives (and `rtta export` writes)."""

from __future__ import annotations

import difflib
from dataclasses import dataclass

import numpy as np

from ..atlas.parameterize import Records
from ..errors import RttaError
from ..gl.readback import map_back
from ..scene.camera import Camera


@dataclass
class Capture:
    """One captured frame in arrays, as `rtta export` writes it (docs: Library, "Export format").

    What `rtta.capture` returns. Rows follow GL window coordinates like the export's .npy files
    and the rectangles: row 0 is the BOTTOM row (the PNGs, and `snapshot`, are top row first:
    flip with ``[::-1]``).

    Attributes
    ----------
    records : Records
        Algorithm 1's records of the frame (regions, transforms, layers, scales).
    names : tuple of str
        The object names, indexed by object id.
    camera : Camera
        The camera of the frame.
    view, proj : numpy.ndarray
        World-space view and projection matrices, 4x4: ``clip = proj @ view @ [x, y, z, 1]``.
    color : numpy.ndarray
        The atlas colour, RGBA uint8 [layers, Th, Tw, 4], alpha 255 where an object covers the texel.
    normal : numpy.ndarray or None
        The atlas normals, float32 xyz [layers, Th, Tw, 3].
    depth : numpy.ndarray
        The atlas window depth, float32 [layers, Th, Tw], 1.0 where empty.
    id : numpy.ndarray
        The object id per atlas texel, int32 [layers, Th, Tw], -1 where empty.
    std_color, std_depth, std_id : numpy.ndarray
        The direct render [H, W(, 4)], same conventions.

    Examples
    --------
    >>> import rtta
    >>> cap = rtta.capture(None, size=(320, 240))
    >>> x, y, w, h = cap.atlas_rect[cap.index("piston_1")]  # its region, border included
    """

    records: Records
    names: tuple[str, ...]
    camera: Camera
    view: np.ndarray
    proj: np.ndarray
    color: np.ndarray
    normal: np.ndarray | None
    depth: np.ndarray
    id: np.ndarray
    std_color: np.ndarray
    std_depth: np.ndarray
    std_id: np.ndarray

    @property
    def viewport(self) -> tuple[int, int]:
        return self.records.viewport

    @property
    def border(self) -> int:
        return self.records.border

    @property
    def visible(self) -> np.ndarray:
        return self.records.visible

    @property
    def viewport_rect(self) -> np.ndarray:
        """[n, 4] x0, y0, x1, y1: each object's clipped projected bounds, in pixels."""
        return self.records.viewport_rect

    @property
    def atlas_rect(self) -> np.ndarray:
        """[n, 4] x, y, w, h: each object's atlas region in texels, border included."""
        return self.records.atlas_rect

    @property
    def layer(self) -> np.ndarray:
        return self.records.layer

    @property
    def scale(self) -> np.ndarray:
        """Atlas texels per viewport pixel (1 unless the atlas was too small)."""
        return self.records.scale

    def index(self, obj: str | int) -> int:
        """The id of an object given by name or id (names as `rtta info` lists them)."""
        if isinstance(obj, (int, np.integer)):
            if not 0 <= obj < len(self.names):
                raise RttaError(f"object id {obj} out of range 0..{len(self.names) - 1}")
            return int(obj)
        if obj in self.names:
            return self.names.index(obj)
        close = difflib.get_close_matches(obj, self.names, n=4, cutoff=0.5)
        raise RttaError(f"no object named '{obj}'" + (f"; did you mean {', '.join(close)}?" if close else ""))

    def region(self, obj: str | int) -> dict[str, np.ndarray]:
        """The object's atlas region (border included) of each atlas image; empty if not visible."""
        oid = self.index(obj)
        if not self.visible[oid]:
            return {k: np.zeros((0, 0, *v.shape[3:]), v.dtype) for k, v in self._atlas().items()}
        x, y, w, h = (int(v) for v in self.atlas_rect[oid])
        return {k: v[self.layer[oid], y : y + h, x : x + w].copy() for k, v in self._atlas().items()}

    def amodal(self, obj: str | int) -> dict[str, np.ndarray]:
        """The object's amodal images mapped back to the viewport [H, W(, C)] (nearest texel),
        empty (colour 0, depth 1, id -1) outside it: the whole object, occluded parts too.
        Row 0 is the bottom row, as in the other arrays."""
        return map_back(self._atlas(), self.records, self.index(obj))

    def _atlas(self) -> dict[str, np.ndarray]:
        parts = {"color": self.color, "depth": self.depth, "id": self.id}
        if self.normal is not None:
            parts["normal"] = self.normal
        return parts


def empty_atlas() -> dict[str, np.ndarray]:
    """The atlas arrays of a frame in which nothing is visible (no layer)."""
    return {
        "color": np.zeros((0, 0, 0, 4), np.uint8),
        "normal": np.zeros((0, 0, 0, 3), np.float32),
        "depth": np.ones((0, 0, 0), np.float32),
        "id": np.full((0, 0, 0), -1, np.int32),
    }
