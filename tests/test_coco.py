"""COCO encoding and merging of `rtta dataset`, without GL: crops to RLE against
pycocotools.mask.encode of the full mask, assembly order, and merge's id rules."""

from __future__ import annotations

import json

import numpy as np
import pytest

from rtta.dataset import coco
from rtta.errors import RttaError

mask = pytest.importorskip("pycocotools.mask")


def _random_crops(rng, h, w, n):
    crops, rects, fulls = [], [], []
    for _ in range(n):
        x, y = int(rng.integers(0, w)), int(rng.integers(0, h))
        cw, ch = int(rng.integers(0, w - x + 1)), int(rng.integers(0, h - y + 1))
        crop = rng.random((ch, cw)) < rng.random()
        full = np.zeros((h, w), np.uint8)
        full[y : y + ch, x : x + cw] = crop
        crops.append(crop)
        rects.append((x, y, cw, ch))
        fulls.append(full)
    return crops, np.array(rects, np.int64).reshape(-1, 4), fulls


def test_crops_encode_exactly_as_pycocotools_encodes_the_full_mask():
    """Every corner case of column-major runs: crops touching the top, bottom, first and last
    pixel, full and empty masks, one-pixel images, runs joining across columns."""
    rng = np.random.default_rng(5)
    checked = 0
    for _ in range(1500):
        h, w = (int(v) for v in rng.integers(1, 11, 2))
        crops, rects, fulls = _random_crops(rng, h, w, int(rng.integers(0, 5)))
        rles, areas, boxes = coco.encode_crops(crops, rects, h, w)
        for full, rle, area, box in zip(fulls, rles, areas, boxes, strict=True):
            ref = mask.encode(np.asfortranarray(full))
            assert rle == {"size": [h, w], "counts": ref["counts"].decode()}
            assert area == full.sum() and np.array_equal(box, mask.toBbox(ref))
            checked += 1
    full = np.ones((4, 3), bool)
    assert (
        coco.encode_crops([full], np.array([[0, 0, 3, 4]]), 4, 3)[0][0]["counts"]
        == mask.encode(np.asfortranarray(full.astype(np.uint8)))["counts"].decode()
    )
    assert checked > 2000


def test_many_masks_in_one_call():
    """pycocotools' area() overflows a uint8 array from 256 masks on (numpy 2); encode_flat splits."""
    crops = [np.ones((1, 1), bool)] * 600
    rects = np.array([[i % 30, i // 30, 1, 1] for i in range(600)])
    _, areas, _ = coco.encode_crops(crops, rects, 20, 30)
    assert len(areas) == 600 and (areas == 1).all()


def _view(image_id, objects, category="c"):
    image = {"id": image_id, "file_name": f"images/s/{image_id:05d}/rgb.png", "width": 4, "height": 3}
    anns = [{"image_id": image_id, "category": f"{category}{o}", "object_id": o, "area": o} for o in objects]
    return {"image": image, "annotations": anns}


def test_assemble_orders_and_numbers():
    views = [_view(3, [2, 0]), _view(1, [5])]
    doc = coco.assemble({"x": 1}, [{"objects": [{"category": "z"}]}], views)
    assert [im["id"] for im in doc["images"]] == [1, 3]
    assert [(a["id"], a["image_id"], a["object_id"]) for a in doc["annotations"]] == [(1, 1, 5), (2, 3, 0), (3, 3, 2)]
    assert [c["name"] for c in doc["categories"]] == ["c0", "c2", "c5", "z"]  # sorted, unused ones kept
    names = {c["id"]: c["name"] for c in doc["categories"]}
    assert all(names[a["category_id"]] == f"c{a['object_id']}" and "category" not in a for a in doc["annotations"])
    assert coco.dumps(doc) == coco.dumps(json.loads(coco.dumps(doc)))


def test_merge_keeps_shard_ids_and_renumbers_collisions(tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    a.mkdir()
    b.mkdir()
    whole = coco.assemble({"run": 1}, [], [_view(1, [0, 1]), _view(2, [1])])
    (a / "s0.json").write_text(coco.dumps(coco.assemble({"run": 1}, [], [_view(1, [0, 1])])))
    (a / "s1.json").write_text(coco.dumps(coco.assemble({"run": 1}, [], [_view(2, [1])])))
    merged = coco.merge([a / "s0.json", a / "s1.json"], a / "all.json")
    assert merged == json.loads(coco.dumps(whole))  # shards of one run: as one run
    # another run whose image ids collide: renumbered, files relative to the output
    (b / "other.json").write_text(coco.dumps(coco.assemble({"run": 2}, [], [_view(1, [7], "d")])))
    joined = coco.merge([a / "s0.json", b / "other.json"], tmp_path / "out" / "x.json")
    assert [im["id"] for im in joined["images"]] == [1, 2]
    assert joined["images"][1]["file_name"] == "../b/images/s/00001/rgb.png"
    assert sorted(a["id"] for a in joined["annotations"]) == [1, 2, 3]
    assert {c["name"] for c in joined["categories"]} == {"c0", "c1", "d7"}
    assert joined["info"]["merged"] == [{"run": 1}, {"run": 2}]
    # the same object of the same image with different content is refused
    (b / "bad.json").write_text(coco.dumps(coco.assemble({}, [], [_view(1, [7], "e")])))
    with pytest.raises(RttaError, match="different content"):
        coco.merge([b / "other.json", b / "bad.json"], b / "m.json")
    (b / "junk.json").write_text("[1, 2]")
    with pytest.raises(RttaError, match="not a COCO annotations file"):
        coco.merge([b / "junk.json"], b / "m.json")


def test_view_files_for_scenes_beyond_16_bit_ids(tmp_path):
    """visible_id.png holds id + 1 in 16 bits; a scene with more objects gets visible_id.npy
    (uint32, id + 1). A failed write leaves no folder in place and no temporary."""
    from PIL import Image

    from rtta.dataset.view import View, view_files, write_view

    ids = np.array([[-1, 0], [70000, 65533]], np.int32)
    view = View(
        rgb=np.zeros((2, 2, 3), np.uint8),
        depth=np.array([[0, 1.5], [2.0, 3.0]], np.float32),
        ids=ids,
        oids=np.zeros(0, np.int64),
        rects=np.zeros((0, 4), np.int64),
        amodal=np.zeros(0, bool),
        visible=np.zeros(0, bool),
        nearest=np.zeros(0),
    )
    write_view(view, tmp_path / "big", "png", 3.0 / 65535, big=True)
    assert np.array_equal(np.load(tmp_path / "big/visible_id.npy"), ids.astype(np.int64) + 1)
    assert view_files("v", "png", True)["visible_id_file"] == "v/visible_id.npy"
    small = View(**{**view.__dict__, "ids": np.array([[-1, 0], [3, 65533]], np.int32)})
    write_view(small, tmp_path / "small", "png", 3.0 / 65535)
    stored = np.asarray(Image.open(tmp_path / "small/visible_id.png"))
    assert stored.dtype == np.uint16 and stored.tolist() == [[0, 1], [4, 65534]]
    steps = np.asarray(Image.open(tmp_path / "small/depth.png")).astype(float)
    assert np.allclose(steps * 3.0 / 65535, view.depth, atol=3.0 / 65535)
    bad = View(**{**view.__dict__, "rgb": np.zeros((2, 2, 7), np.uint8)})  # PIL cannot write it
    with pytest.raises(TypeError):
        write_view(bad, tmp_path / "bad", "png", 1.0)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["big", "small"]
