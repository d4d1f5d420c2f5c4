"""`rtta dataset`: amodal segmentation datasets, every part's full mask from one capture per view.

The work is a list of (scene, view) items in a fixed order; `--shard I/N` takes the I-th of N
contiguous slices of it, so any scheduler can run the shards anywhere. Each view is written
into a temporary folder renamed into place, then its annotation part (`parts/<scene>/<view>.json`)
is written atomically: a view is complete exactly when its part exists, so a killed run
restarts where it stopped. annotations.json is assembled from the parts at the end, so shards,
workers and restarts give the same bytes. Layout and fields: docs/datasets.md.
"""

from __future__ import annotations

import glob
import json
import os
import zlib
from contextlib import suppress
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import RttaError, reason
from ..outputs import atomic_write
from ..scene.camera import Camera, orbit_in_range
from ..scene.readers import MAX_COORDINATE, MESHES
from . import coco

FORMAT = "rtta-dataset 1"


@dataclass
class Options:
    """Everything that decides what a dataset holds (saved in dataset.json), and how to run it."""

    scenes: list[str] = field(default_factory=list)  # files, folders or globs; none: the demo
    views: int = 10
    seed: int = 0
    size: tuple[int, int] = (640, 480)
    azimuth: tuple[float, float] = (0.0, 360.0)
    elevation: tuple[float, float] = (10.0, 60.0)
    distance: tuple[float, float] = (1.4, 2.6)  # bounding radii
    fov: tuple[float, float] = (40.0, 60.0)
    cameras: list[dict] | None = None  # explicit cameras (--cameras FILE.json)
    depth: str = "png"
    appearance: bool = False
    category_by: str = "name"
    min_visible: int = 0
    smooth_angle: float = 30.0
    smooth: bool = False
    projection: str = "perspective"  # or 'ortho' (--projection)
    view_file: dict | None = None  # a saved view (rtta.renderer.view_file), one view per scene (--view-file)
    sections: list[str] = field(default_factory=list)  # section plane SPECs (--section; rtta.scene.cutaway)
    caps: str = "solid"  # --caps
    explode: float = 0.0  # --explode


@dataclass
class Run:
    """How one invocation runs (not part of the dataset's identity)."""

    out: Path
    shard: tuple[int, int] = (0, 1)
    workers: int = 1
    keep_going: bool = False
    progress: bool | None = None  # None: a bar when stderr is a terminal
    cache: bool = True  # scenes through the scene cache (rtta.scene.cache)


def expand_scenes(args: list[str]) -> list[str]:
    """Scene files from files, folders (every supported file inside, sorted) and globs
    (sorted); none: the demo. A plain file is taken as named (a missing one fails at loading)."""
    from ..scene.generators.demo import demo_path

    found: list[str] = []
    for arg in args or [str(demo_path())]:
        if any(c in arg for c in "*?["):
            hits = sorted(p for p in glob.glob(arg, recursive=True) if Path(p).is_file())
            if not hits:
                raise RttaError("matches no file", arg)
            found += hits
        elif Path(arg).is_dir():
            try:
                os.listdir(arg)
            except OSError as exc:
                raise RttaError(f"cannot list the folder ({reason(exc)})", arg) from None
            hits = sorted(str(p) for p in Path(arg).rglob("*") if p.suffix.lower() in MESHES and p.is_file())
            if not hits:
                raise RttaError(f"folder holds no scene file ({', '.join(MESHES)})", arg)
            found += hits
        else:
            found.append(arg)
    seen: set[str] = set()
    return [p for p in found if not (os.path.abspath(p) in seen or seen.add(os.path.abspath(p)))]


def scene_keys(paths: list[str]) -> list[str]:
    """A folder name per scene: its file stem (characters outside [A-Za-z0-9._-] become '_'),
    numbered -2, -3... where stems repeat."""
    keys, used = [], set()
    for p in paths:
        stem = "".join(c if c.isalnum() or c in "._-" else "_" for c in Path(p).stem).lstrip(".") or "scene"
        key, n = stem, 1
        while key in used:
            n += 1
            key = f"{stem}-{n}"
        used.add(key)
        keys.append(key)
    return keys


def settings(opts: Options, paths: list[str]) -> dict:
    s = asdict(opts)
    s["scenes"] = [{"key": k, "file": p} for k, p in zip(scene_keys(paths), paths, strict=True)]
    s["views"] = len(opts.cameras) if opts.cameras is not None else opts.views
    s["size"] = list(opts.size)
    for k in ("azimuth", "elevation", "distance", "fov"):
        s[k] = list(s[k])
    if opts.view_file is not None:
        s["views"] = 1
    for k, default in (
        ("projection", "perspective"),
        ("view_file", None),
        ("sections", []),
        ("caps", "solid"),
        ("explode", 0.0),
    ):
        if s[k] == default:
            del s[k]  # the settings of datasets made before these options stay the same
    return s


def camera_for(s: dict, key: str, view: int, center, radius: float, scene=None) -> tuple[Camera, dict]:
    """The view's camera: a saved view's (needs `scene`), explicit (settings' cameras) or drawn
    from the seed, the scene key and the view index alone (so any shard or restart draws the
    same one); also how it was made. Perspective, or orthographic with settings' projection."""
    kind = s.get("projection", "perspective")
    if s.get("view_file") is not None:
        from ..renderer.view_file import parse_view

        orbit = parse_view(s["view_file"]).orbit
        if orbit is None or scene is None:
            raise RttaError("a dataset's saved view needs a camera and the scene")
        return orbit.camera(scene, hidden_ids(s, scene)), {"orbit": [orbit.az, orbit.el], "target": list(orbit.target)}
    if s["cameras"] is not None:
        c = s["cameras"][view]
        if "orbit" in c:
            cam = Camera.orbit(center, radius, *c["orbit"], fov_y=c["fov"], projection=kind)
            return cam, {"orbit": list(c["orbit"])}
        cam = Camera(np.array(c["eye"], float), np.array(c["target"], float), np.array(c["up"], float), c["fov"])
        cam.kind = kind
        return cam.fit_depth(center, radius), {}
    rng = np.random.default_rng([s["seed"], zlib.crc32(key.encode()), view])
    az, el, dist, fov = (float(rng.uniform(*s[k])) for k in ("azimuth", "elevation", "distance", "fov"))
    return Camera.orbit(center, radius, az, el, dist, fov_y=fov, projection=kind), {"orbit": [az, el, dist]}


def hidden_ids(s: dict, scene) -> list[int]:
    """The objects a dataset's saved view hides (none without one)."""
    if s.get("view_file") is None:
        return []
    from ..scene.select import resolve_names

    return resolve_names(scene, s["view_file"].get("hidden", []), "hidden")


def parse_cameras(path: str) -> list[dict]:
    """--cameras FILE.json: a list of {"orbit": [AZ, EL, DIST], "fov": F} (DIST in bounding
    radii) or {"eye": [x, y, z], "target": [x, y, z], "up": [x, y, z], "fov": F} (world units)."""
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise RttaError(f"cannot read cameras ({reason(exc)})", path) from None
    except RecursionError:  # found by fuzzing (issue 42)
        raise RttaError("cannot read cameras (JSON nested too deeply)", path) from None
    if not isinstance(data, list) or not data:
        raise RttaError("cameras must be a non-empty JSON list", path)
    out = []
    for i, c in enumerate(data):
        try:
            fov = float(c.get("fov", 45.0))
            cam: dict[str, Any]  # (JSON: lists of numbers, and the fov)
            if "orbit" in c:
                cam = {"orbit": [float(v) for v in c["orbit"]], "fov": fov}
                ok = len(cam["orbit"]) == 3 and cam["orbit"][2] > 0
            else:
                cam = {k: [float(v) for v in c[k]] for k in ("eye", "target")}
                cam.update(up=[float(v) for v in c.get("up", [0, 1, 0])], fov=fov)
                ok = all(len(cam[k]) == 3 for k in ("eye", "target", "up")) and cam["eye"] != cam["target"]
            ok = ok and 0 < fov < 180 and np.isfinite([v for x in cam.values() for v in np.ravel(x)]).all()
            ok = ok and _in_range(cam)
        except (AttributeError, KeyError, TypeError, ValueError, OverflowError):  # 10**400: found by fuzzing
            ok = False
        if not ok:
            raise RttaError(
                f'camera {i}: expected {{"orbit": [AZ, EL, DIST>0], "fov": F}} or '
                '{"eye": [x,y,z], "target": [x,y,z], "up": [x,y,z], "fov": F} with 0 < F < 180 '
                f"(AZ, EL within ±1e6 degrees, DIST 1e-6 to 1e6 radii, x, y, z within ±{MAX_COORDINATE:.0e})",
                path,
            )
        out.append(cam)
    return out


def _in_range(cam: dict) -> bool:
    """An orbit as --camera takes it; eye and target where scenes may lie (±MAX_COORDINATE:
    beyond, the view's matrices overflow and the eye meets the target in float)."""
    if "orbit" in cam:
        return orbit_in_range(*cam["orbit"])
    return max(abs(v) for k in ("eye", "target") for v in cam[k]) <= MAX_COORDINATE


def items_of(s: dict, shard: tuple[int, int]) -> list[tuple[int, int]]:
    """The shard's (scene, view) items: the I-th of N contiguous slices of all of them."""
    every = [(i, v) for i in range(len(s["scenes"])) for v in range(s["views"])]
    i, n = shard
    return every[len(every) * i // n : len(every) * (i + 1) // n]


def image_id(s: dict, item: tuple[int, int]) -> int:
    return item[0] * s["views"] + item[1] + 1


def part_path(out: Path, key: str, view: int | None = None) -> Path:
    return out / "parts" / (f"{key}.json" if view is None else f"{key}/{view:05d}.json")


def view_dir(key: str, view: int) -> str:
    return f"images/{key}/{view:05d}"


def complete(out: Path, key: str, view: int) -> bool:
    return part_path(out, key, view).is_file() and (out / view_dir(key, view) / "rgb.png").is_file()


def prepare_out(out: Path, s: dict, annotations: str = "annotations.json") -> None:
    """Create `out` or check that it holds a dataset of these same settings; a folder with
    other files in it is never written into, nor one (or an `annotations` file) this user may
    not write."""
    if out.exists() and not out.is_dir():
        raise RttaError("exists and is not a directory", out)
    if not out.parent.is_dir():
        raise RttaError("is not a folder" if out.parent.exists() else "parent directory does not exist", out.parent)
    marker = out / "dataset.json"
    doc = {"format": FORMAT, "settings": s}
    # listed before the marker is looked for: another shard writes nothing but the marker's
    # temporary until its marker is in place, so what the listing saw is then explained
    if out.is_dir() and any(not _marker_temporary(p) for p in list(out.iterdir())) and not marker.exists():
        raise RttaError("is not empty and holds no rtta dataset (dataset.json): choose a new or empty folder", out)
    if not os.access(out if out.exists() else out.parent, os.W_OK | os.X_OK):  # before any work
        raise RttaError("cannot write (Permission denied)", out)
    if (out / annotations).is_file() and not os.access(out / annotations, os.W_OK):
        raise RttaError("is read-only; it will not be replaced", out / annotations)
    made = not out.exists()
    try:
        out.mkdir(exist_ok=True)
        atomic_write(marker, lambda tmp: Path(tmp).write_text(coco.dumps(doc)), overwrite=False)
    except FileExistsError:
        try:
            old = json.loads(marker.read_text(encoding="utf-8"))
        except (OSError, json.JSONDecodeError) as exc:
            raise RttaError(f"cannot read dataset.json ({reason(exc)})", out) from None
        new = json.loads(coco.dumps(doc))
        if old != new:
            theirs = old.get("settings", {}) if isinstance(old, dict) else {}
            diff = [k for k in new["settings"] if theirs.get(k) != new["settings"][k]] or ["format"]
            raise RttaError(
                f"holds a dataset made with other settings ({', '.join(diff[:4])}): "
                "choose another --out, or the same settings to resume",
                out,
            ) from None
    except BaseException:
        if made:  # a full disk: the folder this run made goes again (unless another shard wrote into it)
            with suppress(OSError):
                out.rmdir()
        raise


def _marker_temporary(entry: Path) -> bool:
    """Another shard's dataset.json on its way into place (outputs.atomic_write's temporary):
    shards started together into a new folder see it before the marker, and it is no
    foreign file."""
    return entry.name.startswith(".dataset.json.") and entry.name.endswith(".json") and entry.is_file()


def annotations_name(shard: tuple[int, int]) -> str:
    i, n = shard
    return "annotations.json" if n == 1 else f"annotations-shard-{i}-of-{n}.json"


def assemble(out: Path, s: dict, items: list[tuple[int, int]], name: str) -> tuple[Path, dict]:
    """annotations(-shard-I-of-N).json from the parts of the items' complete views."""
    keys = [sc["key"] for sc in s["scenes"]]
    views = [
        json.loads(part_path(out, keys[i], v).read_text(encoding="utf-8"))
        for i, v in items
        if complete(out, keys[i], v)
    ]
    scenes = [
        json.loads(part_path(out, keys[i]).read_text(encoding="utf-8"))
        for i in sorted({i for i, _ in items})
        if part_path(out, keys[i]).is_file()
    ]
    from .. import __version__

    doc = coco.assemble(
        {
            "description": "rtta dataset: amodal and visible masks of every part",
            "version": f"rtta {__version__}",
            "settings": s,
        },
        scenes,
        views,
    )
    target = out / name
    return atomic_write(target, lambda tmp: Path(tmp).write_text(coco.dumps(doc))), doc
