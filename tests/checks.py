"""The two equalities of the core, as functions the GL tests share."""

from __future__ import annotations

import numpy as np

from rtta.bench.compare import crease_limit, depth_mismatch, depth_tolerance, near_edges
from rtta.gl.readback import front_most, map_back


def assert_depth_close(depth, reference, where, ids, what: str) -> None:
    """Depth within tolerance on `where`; the only exceptions allowed lie on depth creases
    (edges between surfaces of one object, where the edge tie-break may pick the other
    triangle) and are rare: see rtta.compare.depth_mismatch."""
    off_crease, on_crease = depth_mismatch(depth, reference, where, ids)
    assert not off_crease, f"{what}: depth differs beyond tolerance at {off_crease} px"
    limit = crease_limit(where)
    assert on_crease <= limit, f"{what}: {on_crease} crease pixels differ in depth (limit {limit})"


def check_frame(renderer, camera, viewport, path: str, rtt_objects=None, excused=None) -> dict:
    """Capture with `path`, then assert (1) every visible object's region mapped back through
    T^-1 equals the object rendered alone (RTT) and (2) STD equals the front-most mapped-back
    depth/id, both except within 1 pixel of a silhouette and, with `excused(front_most, std)`,
    where it says (bool [H, W]). Returns a small summary."""
    records = renderer.capture(camera, viewport, path=path)
    for key in ("transform", "clip_ndc", "scale"):
        assert np.isfinite(getattr(records, key)).all(), key
    tw, th, td = records.atlas_size
    atlas = (
        renderer.atlas.read((tw, th), td)
        if td
        else {"depth": np.ones((0, 1, 1), np.float32), "id": np.full((0, 1, 1), -1, np.int32)}
    )
    atlas = {"depth": atlas["depth"], "id": atlas["id"]}
    std = renderer.std(camera, viewport).read(viewport, 1)
    std_id, std_depth = std["id"][0], std["depth"][0]
    assert np.isfinite(std_depth).all()
    fm = front_most(atlas, records) if td else {"id": np.full_like(std_id, -1), "depth": np.ones_like(std_depth)}
    edge = near_edges(std_id)
    # where two objects' surfaces tie in depth (touching or interpenetrating parts), either id is front-most
    tie = np.abs(fm["depth"] - std_depth) <= depth_tolerance(std_depth, fm["depth"])
    if excused is not None:
        edge = edge | excused(fm, std)
    bad_id = (fm["id"] != std_id) & ~edge & ~tie
    assert not bad_id.any(), f"{path}: STD id differs from front-most atlas id at {int(bad_id.sum())} px"
    both = (std_id >= 0) & (fm["id"] == std_id) & ~edge
    assert_depth_close(fm["depth"], std_depth, both, std_id, f"{path}: STD")
    visible = np.flatnonzero(records.visible)
    objects = visible if rtt_objects is None else np.intersect1d(visible, rtt_objects)
    worst = {"id_px": 0, "depth": 0.0}

    def consume(oid, target):
        alone = target.read(viewport, 1)
        rid, rdepth = alone["id"][0], alone["depth"][0]
        mapped = map_back(atlas, records, oid)
        band = near_edges(rid == oid)
        wrong = (mapped["id"] != rid) & ~band
        assert not wrong.any(), f"{path}: object {oid} atlas id differs from RTT at {int(wrong.sum())} px"
        on = (rid == oid) & (mapped["id"] == oid) & ~band
        assert_depth_close(mapped["depth"], rdepth, on, rid, f"{path}: object {oid}")
        if on.any():
            worst["depth"] = max(worst["depth"], float(np.abs(mapped["depth"] - rdepth)[on].max()))

    renderer.rtt(camera, viewport, objects, consume)
    # objects that RTT shows but the parameterization culled would be holes: none allowed
    leaked = []

    def culled_is_empty(oid, target):
        rid = target.read(viewport, 1)["id"][0]
        count = int(((rid == oid) & ~near_edges(rid == oid)).sum())
        if count:
            leaked.append((oid, count))

    renderer.rtt(camera, viewport, np.flatnonzero(~records.visible), culled_is_empty)
    assert not leaked, f"{path}: culled objects are visible: {leaked}"
    return {"visible": int(records.visible.sum()), "atlas": records.atlas_size, **worst}
