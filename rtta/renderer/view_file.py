"""Saved views: what a snapshot showed, as a small versioned JSON file that renders it again.

`rtta snapshot --save-view FILE` writes one; `--view-file FILE` (snapshot, export, dataset,
rtta-view) reads it. Version 1 holds (every key but "rtta_view" optional)::

    {
      "rtta_view": 1,
      "camera": {"az": 35.0, "el": 25.0, "distance": 4.1, "target": [0.0, 0.1, 0.0], "fov": 45.0},
      "projection": "perspective",
      "mode": "ghosted-ao",
      "focus": ["piston_1"],
      "hidden": ["cover"],
      "opacity": {"caliper": 0.3},
      "style": {"edge_width": 1, "ao_radius": 6.0, ...},
      "sections": null,
      "explode": null
    }

camera: orbit angles in degrees (about the file's up axis, as --camera), the distance and the
target in world units, up to 1e12 (the camera is rebuilt bit for bit: a view file renders
what its snapshot rendered), the vertical field of view; focus, hidden and opacity name objects or
groups as the flags do; style holds the compositing flags (`options.CORE_STYLE`); sections and
explode hold the cutaway and exploded-view flags (null: none) as `{"planes": [SPEC, ...],
"caps": ..., "scope": ...}` and `{"factor": F, "scope": ...}`. A key version 1 does not know is
refused, and so is a newer version, each with one line naming the file.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..errors import RttaError
from ..outputs import atomic_write, check_file
from ..scene.camera import PROJECTIONS
from ..scene.framing import Orbit
from .options import CORE_STYLE, make_style
from .placing import make_staging
from .snapshot import SNAPSHOT_MODES

VERSION = 1
KEYS = ("rtta_view", "camera", "projection", "mode", "focus", "hidden", "opacity", "style", "sections", "explode")
CAMERA_KEYS = ("az", "el", "distance", "target", "fov")
MAX_BYTES = 1 << 20  # a view file is a few hundred bytes; anything near this is not one


@dataclass
class SavedView:
    """A view as a view file holds it (see the module docstring); `orbit` None: not resolved yet."""

    orbit: Orbit | None = None
    mode: str = "ghosted-ao"
    focus: list[str] = field(default_factory=list)
    hidden: list[str] = field(default_factory=list)
    opacity: dict[str, float] = field(default_factory=dict)
    style: dict[str, Any] = field(default_factory=dict)
    sections: dict | None = None
    explode: dict | None = None

    def to_json(self) -> dict:
        """The version-1 document (the orbit must be resolved)."""
        if self.orbit is None:
            raise ValueError("a view is saved with its camera resolved")
        o = self.orbit
        return {
            "rtta_view": VERSION,
            "camera": {"az": o.az, "el": o.el, "distance": o.distance, "target": list(o.target), "fov": o.fov},
            "projection": o.projection,
            "mode": self.mode,
            "focus": list(self.focus),
            "hidden": list(self.hidden),
            "opacity": dict(self.opacity),
            "style": dict(self.style),
            "sections": self.sections,
            "explode": self.explode,
        }


def read_view(path: str | Path) -> SavedView:
    """The view in `path`; RttaError (naming the file) when it cannot be read or is not a
    version this rtta reads."""
    path = Path(path)
    try:
        with open(path, "rb") as f:
            data = f.read(MAX_BYTES + 1)
    except OSError as exc:
        raise RttaError(f"cannot read the view file ({exc.strerror or exc})", path) from None
    if len(data) > MAX_BYTES:
        raise RttaError(f"is over {MAX_BYTES // 1024} KiB: not a view file", path)
    try:
        doc = json.loads(data.decode("utf-8"), parse_constant=_no_constant)
    except (UnicodeDecodeError, ValueError) as exc:
        raise RttaError(f"is not a JSON view file ({exc})", path) from None
    except RecursionError:  # found by fuzzing (issue 42)
        raise RttaError("is not a view file (JSON nested too deeply)", path) from None
    try:
        return parse_view(doc)
    except ValueError as exc:
        raise RttaError(str(exc), path) from None


def parse_view(doc: Any) -> SavedView:
    """A SavedView from a decoded document; ValueError saying what is wrong."""
    if not isinstance(doc, dict) or "rtta_view" not in doc:
        raise ValueError('not an rtta view file (a JSON object with "rtta_view": 1)')
    version = doc["rtta_view"]
    if not isinstance(version, int) or isinstance(version, bool) or version < 1:
        raise ValueError(f"rtta_view must be a version number, got {version!r}")
    if version > VERSION:
        raise ValueError(f"view file version {version} is newer than this rtta reads ({VERSION}): update rtta")
    unknown = [k for k in doc if k not in KEYS]
    if unknown:
        raise ValueError(f"unknown key {unknown[0]!r} in a version {version} view file (it has {', '.join(KEYS)})")
    view = SavedView()
    if doc.get("camera") is not None:
        view.orbit = _orbit(doc["camera"], doc.get("projection", "perspective"))
    elif doc.get("projection", "perspective") != "perspective":
        raise ValueError("projection needs a camera in the view file")
    view.mode = _choice(doc.get("mode", view.mode), SNAPSHOT_MODES, "mode")
    view.focus = _names(doc.get("focus", []), "focus")
    view.hidden = _names(doc.get("hidden", []), "hidden")
    opacity = doc.get("opacity", {})
    if not isinstance(opacity, dict) or not all(_number(a) and 0.0 <= a <= 1.0 for a in opacity.values()):
        raise ValueError("opacity must map names to numbers in [0, 1]")
    view.opacity = {str(k): float(v) for k, v in opacity.items()}
    style = doc.get("style", {})
    if not isinstance(style, dict):
        raise ValueError("style must be an object")
    for key, value in style.items():
        if key not in CORE_STYLE:
            raise ValueError(f"unknown style key {key!r} (style has {', '.join(CORE_STYLE)})")
        _style_value(key, value)
    view.style = dict(style)
    view.sections = _slot(doc.get("sections"), "sections", {"planes": list, "caps": str, "scope": str})
    view.explode = _slot(doc.get("explode"), "explode", {"factor": (int, float), "scope": str})
    try:  # the values as the flags check them (names need the scene: checked when rendering)
        make_style((), None, **view.style)
        s, e = view.sections or {}, view.explode or {}
        planes, caps, cut_scope = s.get("planes", []), s.get("caps", "solid"), s.get("scope", "all")
        make_staging(planes, caps, cut_scope, e.get("factor", 0.0), e.get("scope", "all"))
    except RttaError as exc:
        raise ValueError(str(exc)) from None
    return view


def write_view(view: SavedView, path: str | Path, inputs=()) -> Path:
    """Write `view` to `path` atomically. An existing file is replaced only when it is a view
    file itself (never a user's other JSON); an input of the run never."""
    return atomic_write(path, view_writer(view, path, inputs))


def view_writer(view: SavedView, path: str | Path, inputs=()) -> Callable[[str], None]:
    """write_view's checks of `path` (RttaError), then what writes `view` (as it is when
    called) into atomic_write's temporary file."""
    path = check_file(path, inputs, suffix=".json", what="--save-view")
    if path.exists():
        try:
            read_view(path)
        except RttaError:
            raise RttaError("exists and is not an rtta view file; --save-view will not replace it", path) from None

    def write(tmp: str) -> None:
        Path(tmp).write_text(json.dumps(view.to_json(), indent=1) + "\n", encoding="utf-8")

    return write


def _orbit(camera: Any, projection: Any) -> Orbit:
    if not isinstance(camera, dict):
        raise ValueError("camera must be an object with az, el, distance, target and fov")
    unknown = [k for k in camera if k not in CAMERA_KEYS]
    missing = [k for k in CAMERA_KEYS if k not in camera]
    if unknown or missing:
        bad = f"unknown key {unknown[0]!r}" if unknown else f"no {missing[0]!r}"
        raise ValueError(f"camera: {bad} (camera has {', '.join(CAMERA_KEYS)})")
    az, el, distance, fov, target = (camera[k] for k in ("az", "el", "distance", "fov", "target"))
    if not all(_number(v) for v in (az, el, distance, fov)) or max(abs(az), abs(el)) > 1e6:
        raise ValueError("camera: az, el, distance and fov must be finite numbers (angles up to 1e6 degrees)")
    if not (isinstance(target, list) and len(target) == 3 and all(_number(v) and abs(v) <= 1e12 for v in target)):
        raise ValueError("camera.target must be three finite numbers [x, y, z], each within 1e12 (world units)")
    if not 0 < distance <= 1e12 or not 1.0 <= fov <= 170.0:
        raise ValueError(f"camera: distance must be in (0, 1e12] and fov in [1, 170], got {distance!r}, {fov!r}")
    projection = _choice(projection, PROJECTIONS, "projection")
    t = (float(target[0]), float(target[1]), float(target[2]))
    return Orbit(float(az), float(el), float(distance), t, float(fov), projection)  # type: ignore[arg-type]


def _slot(value: Any, what: str, fields: dict) -> dict | None:
    if value is None:
        return None
    if not isinstance(value, dict) or any(k not in fields for k in value):
        raise ValueError(f"{what} must be null or an object with {', '.join(fields)}")
    for key, kind in fields.items():
        if key in value and (not isinstance(value[key], kind) or isinstance(value[key], bool)):
            raise ValueError(f"{what}.{key} has the wrong type: {value[key]!r}")
    if "planes" in value and not all(isinstance(p, str) for p in value["planes"]):
        raise ValueError(f"{what}.planes must be a list of section specs (strings)")
    return dict(value)


def _names(value: Any, what: str) -> list[str]:
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise ValueError(f"{what} must be a list of object or group names")
    return list(value)


def _choice(value: Any, choices, what: str) -> str:
    if value not in choices:
        raise ValueError(f"{what} must be one of {', '.join(choices)}, got {value!r}")
    return value


STYLE_KINDS = {  # what each style key holds (options.make_style's keyword arguments)
    "context_opacity": "a number or null",
    "edge_width": "an integer",
    "ao_radius": "a number",
    "ao_strength": "a number",
    "ao_objects": "a name or null",
    "edge_objects": "a name or null",
    "order": "a name or null",
    "halo": "an integer",
}


def _style_value(key: str, value: Any) -> None:
    """ValueError unless `value` is what style key `key` holds (found by the views target:
    a name where a number belongs reached make_style's comparisons as a TypeError)."""
    kind = STYLE_KINDS[key]
    if value is None:
        ok = kind.endswith("or null")
    elif kind.startswith("a name"):
        ok = isinstance(value, str)
    else:
        ok = _number(value) and (kind != "an integer" or isinstance(value, int))
    if not ok:
        raise ValueError(f"style.{key} must be {kind}, got {json.dumps(value)[:40]}")


def _number(v: Any) -> bool:
    try:
        return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
    except OverflowError:  # an integer of 400 digits (found by fuzzing, issue 42)
        return False


def _no_constant(name: str):
    raise ValueError(f"{name} is not a number JSON allows")
