"""Base-colour textures of loaded meshes, each stored once however many objects use it."""

from __future__ import annotations

import hashlib

import numpy as np

from ..errors import reason


class TextureTable:
    """Collects textures as uint8 RGBA arrays with row 0 at v = 0 (OpenGL's convention, which
    trimesh's texture coordinates follow); `of(mesh)` gives (uv or None, index or -1)."""

    def __init__(self) -> None:
        self.images: list[np.ndarray] = []
        self._by_object: dict[int, int] = {}
        self._by_digest: dict[bytes, int] = {}
        self._keep: list = []  # the images keyed by id() stay alive while loading
        self._failed: set[int] = set()
        self.notes: list[str] = []  # textures that could not be decoded (their objects keep their colour)

    def of(self, mesh) -> tuple[np.ndarray | None, int]:
        visual = getattr(mesh, "visual", None)
        uv = getattr(visual, "uv", None)
        image = base_color_image(getattr(visual, "material", None))
        if image is None or uv is None:
            return None, -1
        uv = np.asarray(uv, np.float64)
        if uv.shape != (len(mesh.vertices), 2) or not np.isfinite(uv).all():
            return None, -1
        index = self._index(image)
        return (uv.astype(np.float32), index) if index >= 0 else (None, -1)

    def _index(self, image) -> int:
        if id(image) in self._by_object:
            return self._by_object[id(image)]
        if id(image) in self._failed:
            return -1
        try:
            rgba = to_rgba(image)
        except Exception as exc:  # truncated or damaged data found while decoding
            self._failed.add(id(image))
            self._keep.append(image)
            name = image.info.get("file_path") or getattr(image, "filename", "") or "an embedded image"
            self.notes.append(
                f"texture '{name}' cannot be decoded ({reason(exc)}); objects using it keep their material colour"
            )
            return -1
        digest = hashlib.sha1(rgba.tobytes() + str(rgba.shape).encode()).digest()
        if digest not in self._by_digest:
            self._by_digest[digest] = len(self.images)
            self.images.append(rgba)
        self._by_object[id(image)] = self._by_digest[digest]
        self._keep.append(image)
        return self._by_digest[digest]


def base_color_image(material):
    """The material's base-colour image (glTF PBR) or diffuse image (OBJ), or None."""
    if material is None:
        return None
    for name in ("baseColorTexture", "image"):
        image = getattr(material, name, None)
        if image is not None and hasattr(image, "size") and min(image.size) > 0:
            return image
    return None


def to_rgba(image) -> np.ndarray:
    """PIL image (any mode: L, LA, P, RGB, RGBA, I;16 ...) -> uint8 [h, w, 4], row 0 = bottom."""
    if image.mode in ("I", "I;16", "I;16B", "F"):  # 16-bit or float grey: scale to 8 bits
        from PIL import Image

        a = np.asarray(image, np.float64)
        a = a * (255.0 / a.max()) if a.max() > 0 else a
        image = Image.fromarray(np.clip(np.round(a), 0, 255).astype(np.uint8), "L")
    rgba = np.asarray(image.convert("RGBA"), np.uint8)
    return np.ascontiguousarray(rgba[::-1])
