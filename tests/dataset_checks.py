"""Scenes and checks shared by the dataset tests: a nested scene (parts inside closed parts),
and every annotation of a written view against the objects rendered alone (RTT) and STD."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import trimesh
from PIL import Image

from rtta.bench.compare import near_edges
from rtta.renderer.export import world_matrices
from rtta.scene.camera import Camera


def nested_glb(path: Path, copies: int = 3) -> Path:
    """`copies` closed boxes side by side, each holding a smaller box holding a sphere (both
    hidden from every outside view), and a rod through each outer box (partly hidden)."""
    scene = trimesh.Scene()
    upright = trimesh.transformations.rotation_matrix(np.pi / 2, (1, 0, 0))  # the rod along y
    for k in range(copies):
        at = np.array([3.0 * k, 0.0, 0.0])
        parts = {
            "shell": trimesh.creation.box((2.0, 2.0, 2.0)),
            "inner": trimesh.creation.box((1.0, 1.2, 1.0)),
            "core": trimesh.creation.icosphere(2, radius=0.35),
            "rod": trimesh.creation.cylinder(radius=0.12, height=3.2, transform=upright),
        }
        for name, mesh in parts.items():
            mesh.apply_translation(at)
            scene.add_geometry(mesh, node_name=f"{name}_{k}", geom_name=f"{name}_{k}")
    path.write_bytes(scene.export(file_type="glb"))
    return path


def camera_of(image: dict) -> Camera:
    c = image["camera"]
    return Camera(np.array(c["eye"]), np.array(c["target"]), np.array(c["up"]), c["fov_y"], c["near"], c["far"])


def bbox_of(mask: np.ndarray) -> list[float]:
    ys, xs = np.nonzero(mask)
    if not len(xs):
        return [0.0, 0.0, 0.0, 0.0]
    return [float(xs.min()), float(ys.min()), float(xs.max() - xs.min() + 1), float(ys.max() - ys.min() + 1)]


def check_image(renderer, coco, image: dict, root: Path) -> dict:
    """Assert the acceptance for one image of a dataset written for renderer.scene: amodal masks
    equal each object rendered alone except within one pixel of its silhouette; segmentation
    equals visible_id == id of the STD render exactly; areas, boxes and occlusion agree with
    the decoded masks; the RLEs are pycocotools.mask.encode's; depth_order follows the nearest
    depths of the objects alone; view/proj are the renderer's. Returns a summary."""
    from pycocotools import mask as cmask

    size = (image["width"], image["height"])
    camera = camera_of(image)
    view, proj = world_matrices(renderer, camera, size)
    assert np.array_equal(view, np.array(image["camera"]["view"])) and np.array_equal(proj, image["camera"]["proj"])
    std_id = renderer.std(camera, size).read(size, 1)["id"][0][::-1]
    stored = np.asarray(Image.open(root / image["visible_id_file"])).astype(np.int64) - 1
    assert np.array_equal(stored, std_id), "visible_id.png is not STD's id image"
    anns = {a["object_id"]: a for a in coco.loadAnns(coco.getAnnIds(imgIds=[image["id"]]))}
    nearest, band_px = {}, 0
    records = renderer.parameterize(camera, size)

    def consume(oid: int, target) -> None:
        nonlocal band_px
        alone = target.read(size, 1, ("id", "depth"))
        mask = alone["id"][0][::-1] == oid
        band = near_edges(mask)
        a = anns.get(oid)
        if a is None:
            assert not (mask & ~band).any(), f"object {oid} is in view but has no annotation"
            return
        amodal = cmask.decode(a["amodal_segmentation"]).astype(bool)
        wrong = (amodal != mask) & ~band
        assert not wrong.any(), f"object {oid}: amodal mask differs from RTT at {int(wrong.sum())} px"
        band_px += int((amodal != mask).sum())
        nearest[oid] = float(alone["depth"][0].min())

    renderer.rtt(camera, size, np.flatnonzero(records.visible), consume)
    for oid, a in anns.items():
        seg = coco.annToMask(a).astype(bool)
        amodal = cmask.decode(a["amodal_segmentation"]).astype(bool)
        assert np.array_equal(seg, std_id == oid), f"object {oid}: segmentation is not STD's id == {oid}"
        assert not (seg & ~amodal).any(), f"object {oid}: visible pixels outside the amodal mask"
        assert a["area"] == int(seg.sum()) and a["amodal_area"] == int(amodal.sum()) > 0
        assert a["bbox"] == bbox_of(seg) and a["amodal_bbox"] == bbox_of(amodal)
        assert abs(a["occlusion_rate"] - (1 - seg.sum() / amodal.sum())) < 1e-12
        for key, m in (("segmentation", seg), ("amodal_segmentation", amodal)):
            ref = cmask.encode(np.asfortranarray(m.astype(np.uint8)))
            assert a[key] == {"size": [size[1], size[0]], "counts": ref["counts"].decode()}, (oid, key)
        assert a["object_name"] == renderer.scene.names[oid] and a["iscrowd"] == 0
    ranked = sorted(anns.values(), key=lambda a: a["depth_order"])
    assert [a["depth_order"] for a in ranked] == list(range(len(ranked)))
    depths = [nearest.get(a["object_id"], 1.0) for a in ranked]
    assert all(d1 <= d2 + 1e-4 for d1, d2 in zip(depths, depths[1:], strict=False)), "depth_order is not by depth"
    return {
        "annotations": len(anns),
        "hidden": sum(a["area"] == 0 for a in anns.values()),
        "band_px": band_px,
        "amodal_px": sum(a["amodal_area"] for a in anns.values()),
    }


def read_json(path: Path) -> dict:
    return json.loads(Path(path).read_text())
