"""COCO annotations extended the way amodal datasets extend them: masks to RLE, per-view
parts assembled into one `annotations.json`, and shard files merged with unique ids.

Masks arrive as crops (each object's viewport rectangle), not as full images: scanning a
full-image mask per object costs more than rendering it here (0.16 ms per 640x480 mask in
`pycocotools.mask.encode`, against 1-2 ms per object for the whole RTT baseline, docs/performance/dataset.md),
so the column-major run boundaries of every crop of a view are found in one numpy pass and
pycocotools turns those counts into its compressed RLE strings (`frPyObjects`), area and
boxes. The tests check that every string equals `pycocotools.mask.encode` of the full mask.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np

from ..errors import RttaError, reason

FILE_FIELDS = ("file_name", "depth_file", "visible_id_file")


def _mask_api():
    try:
        from pycocotools import mask
    except ImportError:
        raise RttaError("pycocotools is needed for COCO masks: pip install 'rtta[dataset]'") from None
    return mask


def layout(rects: np.ndarray) -> dict[str, np.ndarray]:
    """The flat layout of crops at `rects` (x, y, w, h: image pixels, y down) that encoding
    reads: per object its columns left to right, each a zero, the column's h pixels top to
    bottom, a zero. Per object `offsets` [N + 1]; per column (C of them) its object
    `col_obj`, its place in the object `col_index` and its start `col_start`; per element its
    column `col` and `row` (-1 and h on the zeros) and whether it is a `pixel`. Per-element
    values are best derived from per-column ones: gathers from small arrays are cheap."""
    rects = np.asarray(rects, np.int64).reshape(-1, 4)
    widths, tall = rects[:, 2], rects[:, 3] + 2
    offsets = np.concatenate(([0], np.cumsum(widths * tall)))
    col_obj = np.repeat(np.arange(len(rects)), widths)
    col_index = np.arange(len(col_obj)) - np.repeat(np.cumsum(widths) - widths, widths)
    col_len = tall[col_obj]
    col_start = offsets[col_obj] + col_index * col_len
    col = np.repeat(np.arange(len(col_obj), dtype=np.int32), col_len)
    row = np.arange(int(offsets[-1]), dtype=np.int64) - col_start[col] - 1
    return {
        "offsets": offsets,
        "col_obj": col_obj,
        "col_index": col_index,
        "col_start": col_start,
        "col": col,
        "row": row,
        "pixel": (row >= 0) & (row < (col_len - 2)[col]),
    }


def flatten(crops: list[np.ndarray], rects: np.ndarray, fill: float = 0) -> np.ndarray:
    """Crops (each [h, w], top row first) into the flat layout (`fill` on the zeros)."""
    rects = np.asarray(rects, np.int64).reshape(-1, 4)
    tall = rects[:, 3] + 2
    offsets = np.concatenate(([0], np.cumsum(rects[:, 2] * tall)))
    dtype = crops[0].dtype if len(crops) else bool
    out = np.full(int(offsets[-1]), fill, dtype)
    for i, crop in enumerate(crops):
        w, t = int(rects[i, 2]), int(tall[i])
        if w and t > 2:
            out[offsets[i] : offsets[i + 1]].reshape(w, t)[:, 1:-1] = crop.T
    return out


def run_counts(flat: np.ndarray, rects: np.ndarray, height: int, width: int) -> list[np.ndarray]:
    """Uncompressed COCO counts (column-major runs, zeros first) of the full-image masks,
    empty outside their rectangles, whose crops `flat` holds (see layout). Work grows with
    the crops' area, not the image's."""
    total = height * width
    rects = np.asarray(rects, np.int64).reshape(-1, 4)
    n = len(rects)
    if not n:
        return []
    tall = rects[:, 3] + 2
    offsets = np.concatenate(([0], np.cumsum(rects[:, 2] * tall)))
    at = np.flatnonzero(np.diff(flat.astype(np.int8))) + 1  # first element of each run (never an object's first)
    obj = np.searchsorted(offsets, at, side="right") - 1
    column, row = np.divmod(at - offsets[obj], tall[obj])
    index = (rects[obj, 0] + column) * height + rects[obj, 1] + row - 1
    # an end at the bottom of a column and a start at the top of the next one are the same place
    same = (index[1:] == index[:-1]) & (obj[1:] == obj[:-1])
    keep = index < total  # a run ending on the last pixel needs no end
    keep[:-1] &= ~same
    keep[1:] &= ~same
    index, obj = index[keep], obj[keep]
    # per object: 0, its transitions, total; the differences are its counts
    bounds = np.searchsorted(obj, np.arange(n + 1))
    full = np.empty(len(index) + 2 * n, np.int64)
    starts = bounds[:-1] + 2 * np.arange(n)
    full[starts] = 0
    full[bounds[1:] + 2 * np.arange(n) + 1] = total
    full[np.arange(len(index)) + 2 * obj + 1] = index
    counts = np.diff(full).astype(np.uint32)
    ends = bounds[1:] + 2 * np.arange(n) + 1
    return [counts[a:b] for a, b in zip(starts.tolist(), ends.tolist(), strict=True)]


def encode_flat(
    flat: np.ndarray, rects: np.ndarray, height: int, width: int
) -> tuple[list[dict], np.ndarray, np.ndarray]:
    """(RLEs as JSON dicts {size, counts}, areas, boxes [x, y, w, h]) of the full-image masks
    whose crops `flat` holds (see layout); compressed, measured and boxed by pycocotools."""
    if not len(np.asarray(rects).reshape(-1, 4)):
        return [], np.zeros(0, np.int64), np.zeros((0, 4))
    mask = _mask_api()
    # uncompressed RLEs (counts a list): pycocotools takes them, its stubs list only compressed ones
    rles = mask.frPyObjects(  # pyright: ignore[reportCallIssue]
        [{"size": [height, width], "counts": c} for c in run_counts(flat, rects, height, width)],  # pyright: ignore[reportArgumentType]
        height,
        width,
    )
    # mask.area sizes a uint8 scratch array by the count (numpy 2 refuses 256 or more): 255 at a time
    areas = np.concatenate([mask.area(rles[k : k + 255]) for k in range(0, len(rles), 255)]).astype(np.int64)
    boxes = mask.toBbox(rles)
    return [{"size": [height, width], "counts": r["counts"].decode("ascii")} for r in rles], areas, boxes


def encode_crops(
    crops: list[np.ndarray], rects: np.ndarray, height: int, width: int
) -> tuple[list[dict], np.ndarray, np.ndarray]:
    """encode_flat of crops given one by one (bool [h, w] each, top row first)."""
    return encode_flat(flatten(crops, rects), rects, height, width)


def dumps(doc: dict) -> str:
    """The one serialisation of every JSON file the dataset writes (byte-stable for a given doc).
    A file name that is not UTF-8 (its bytes stand in as lone surrogates) is written as JSON
    escapes (\\udcXX), so the text stays valid UTF-8 and reads back to the same name."""
    text = json.dumps(doc, separators=(",", ":"), ensure_ascii=False, allow_nan=False)
    return text.encode("utf-8", "backslashreplace").decode("utf-8")


def assemble(info: dict, scenes: list[dict], views: list[dict]) -> dict:
    """One COCO document from per-scene parts (objects with their category names) and per-view
    parts (an image and its annotations, which name their category): categories sorted by
    name with ids 1..K, images by id, annotations by (image, object) with ids 1..N."""
    names = sorted(
        {o["category"] for s in scenes for o in s["objects"]} | {a["category"] for v in views for a in v["annotations"]}
    )
    return _document(info, names, [v["image"] for v in views], [a for v in views for a in v["annotations"]])


def _document(info: dict, names: list[str], images: list[dict], annotations: list[dict]) -> dict:
    category = {name: k + 1 for k, name in enumerate(names)}
    images = sorted(images, key=lambda im: im["id"])
    annotations = sorted(annotations, key=lambda a: (a["image_id"], a["object_id"]))
    out = []
    for k, a in enumerate(annotations):
        entry = {"id": k + 1, "image_id": a["image_id"], "category_id": category[a["category"]]}
        entry.update((key, v) for key, v in a.items() if key not in ("id", "image_id", "category", "category_id"))
        out.append(entry)
    return {
        "info": info,
        "images": images,
        "categories": [{"id": category[n], "name": n, "supercategory": "object"} for n in names],
        "annotations": out,
    }


def read_document(path: Path) -> dict:
    """A COCO file written by `rtta dataset` (checked for the fields merge needs)."""
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise RttaError(f"cannot read annotations ({reason(exc)})", path) from None
    if not isinstance(doc, dict) or not all(
        isinstance(doc.get(k), list) for k in ("images", "annotations", "categories")
    ):
        raise RttaError("not a COCO annotations file (images, annotations, categories)", path)
    return doc


def merge(inputs: list[Path], out: Path) -> dict:
    """Join annotation files (of shards, or of separate runs) into one document whose file
    names are relative to `out`'s folder. An image in several inputs is kept once (it must be
    the same); image ids are kept when they are unique across inputs (shards of one run), else
    renumbered in input order; categories join by name; annotation ids are renumbered."""
    base = out.resolve().parent
    images: dict[str, dict] = {}
    annotations: dict[tuple[str, int], dict] = {}
    infos, names = [], set()
    for path in inputs:
        doc = read_document(path)
        infos.append(doc.get("info", {}))
        category = {c["id"]: c["name"] for c in doc["categories"]}
        names.update(category.values())
        key_of = {}
        for image in doc["images"]:
            image = _rebased(image, path.resolve().parent, base)
            key = image["file_name"]
            if key in images and images[key] != image:
                raise RttaError(f"image {key} appears in several inputs with different content", path)
            images[key] = image
            key_of[image["id"]] = key
        for a in doc["annotations"]:
            name = category[a["category_id"]]
            a = {k: v for k, v in a.items() if k not in ("id", "category_id")} | {"category": name}
            if "appearance" in a:
                a["appearance"] = _rebased(a["appearance"], path.resolve().parent, base, ("file",))
            key = (key_of[a["image_id"]], a["object_id"])
            if key in annotations and {**annotations[key], "image_id": 0} != {**a, "image_id": 0}:
                raise RttaError(
                    f"object {key[1]} of image {key[0]} appears in several inputs with different content", path
                )
            annotations[key] = a
    ids = [im["id"] for im in images.values()]
    if len(set(ids)) != len(ids):
        renumber = {key: k + 1 for k, key in enumerate(images)}
        for key, image in images.items():
            image["id"] = renumber[key]
    for (key, _), a in annotations.items():
        a["image_id"] = images[key]["id"]
    info = infos[0] if all(i == infos[0] for i in infos) else {"description": "merged rtta datasets", "merged": infos}
    return _document(info, sorted(names), list(images.values()), list(annotations.values()))


def _rebased(entry: dict, src: Path, base: Path, fields=FILE_FIELDS) -> dict:
    """A copy of `entry` with its file fields made relative to `base` instead of `src`."""
    entry = dict(entry)
    for f in fields:
        if isinstance(entry.get(f), str):
            entry[f] = Path(os.path.relpath(src / entry[f], base)).as_posix()
    return entry
