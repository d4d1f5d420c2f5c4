"""Whole-scene preprocessing (rtta/scene/batch.py) against the per-mesh reference
(preprocess.py), the loader on a generated assembly, and the batch Scene builder."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from rtta.scene import batch
from rtta.scene.generators.assembly import write_assembly
from rtta.scene.loader import load_scene
from rtta.scene.model import from_meshes
from rtta.scene.preprocess import index_vertices, smooth_normals


def _canon(v, f, n, uv) -> np.ndarray:
    """Triangles as rows of corner positions, normals and uvs, sorted: equal meshes give
    equal arrays whatever their vertex order."""
    rows = np.concatenate([v[f].reshape(len(f), 9), n[f].reshape(len(f), 9), uv[f].reshape(len(f), 6)], axis=1)
    return rows[np.lexsort(rows.T[::-1])]


def _parts(count: int, seed: int = 1):
    rng = np.random.default_rng(seed)
    shapes = [
        trimesh.creation.icosphere(1),
        trimesh.creation.box(),
        trimesh.creation.cylinder(0.5, 1, sections=16),
        trimesh.creation.torus(1, 0.3),
        trimesh.creation.cone(0.5, 1, sections=40),
    ]  # its apex: 40 corners
    parts = []
    for i in range(count):
        m = shapes[i % len(shapes)]
        v = np.asarray(m.vertices) * rng.uniform(0.5, 2, 3) + rng.normal(size=3)
        uv = (rng.random((len(v), 2)) if i % 3 == 0 else np.zeros((len(v), 2))).astype(np.float32)
        parts.append((v, np.asarray(m.faces), np.asarray(m.vertex_normals, np.float32), uv))
    return parts


@pytest.mark.parametrize(("chunk", "pairs", "threads"), [(10**7, batch.PAIR_BLOCK, 1), (300, 1, 3)])
def test_batched_preprocessing_matches_each_mesh_alone(monkeypatch, chunk, pairs, threads):
    monkeypatch.setattr(batch, "CHUNK_CORNERS", chunk)  # one pass, or many small ones
    monkeypatch.setattr(batch, "PAIR_BLOCK", pairs)  # corner pairs: big blocks, or one position each
    monkeypatch.setattr(batch, "THREADS", threads)  # passes one after another, or three at once
    parts = _parts(25)
    smooth = np.arange(len(parts)) % 2 == 0
    meshes = batch.Meshes(
        *(np.concatenate([p[k] for p in parts]) for k in (0, 1)),
        np.array([len(p[0]) for p in parts]),
        np.array([len(p[1]) for p in parts]),
        *(np.concatenate([p[k] for p in parts]) for k in (2, 3)),
    )
    out = batch.preprocess(meshes, smooth, 30.0)
    for i, (v, f, n, uv) in enumerate(parts):
        ref = smooth_normals(v, f, uv, 30.0) if smooth[i] else index_vertices(v, f, n, uv)
        vs = slice(out.vstart[i], out.vstart[i] + out.vcount[i])
        got_f = out.faces[out.fstart[i] : out.fstart[i] + out.fcount[i]]
        assert out.vcount[i] == len(ref[0]) and out.fcount[i] == len(ref[1])
        np.testing.assert_allclose(
            _canon(out.vertices[vs], got_f, out.normals[vs], out.uvs[vs]), _canon(*ref), atol=1e-6
        )


def test_unique_rows_is_exact_and_in_first_appearance_order():
    rng = np.random.default_rng(0)
    a = rng.integers(0, 3, (500, 2)).astype(np.float64)
    a[7] = [-0.0, 0.0]  # bitwise distinct from (0, 0)
    first, inverse = batch.unique_rows(a)
    ref = {tuple(r.view(np.uint64)) for r in a}
    assert len(first) == len(ref) and (np.diff(first) > 0).all()
    assert np.array_equal(a[first][inverse].view(np.uint64), a.view(np.uint64))


def test_loader_batches_a_generated_assembly(tmp_path):
    path = write_assembly(tmp_path / "a.glb", 300, seed=3)
    s = load_scene(path)
    assert s.count == 300 and set(s.names) == {f"part{i:06d}" for i in range(300)}
    first, count = s.index_ranges.T
    assert first[0] == 0 and (first[1:] == first[:-1] + count[:-1]).all() and first[-1] + count[-1] == len(s.indices)
    for oid in (0, 123, 299):
        assert (s.object_ids[s.indices[first[oid] : first[oid] + count[oid]]] == oid).all()
    np.testing.assert_allclose(np.linalg.norm(s.normals, axis=1), 1.0, atol=1e-3)
    # the same scene through trimesh and the per-object reference path, object by object
    loaded = trimesh.load(str(path), force="scene", process=False)
    for oid in (0, 57, 299):
        node = s.names[oid]
        m, geom = loaded.graph[node]
        mesh = loaded.geometry[geom]
        world = np.asarray(mesh.vertices) @ np.asarray(m)[:3, :3].T + np.asarray(m)[:3, 3]
        ref = smooth_normals(world, np.asarray(mesh.faces), None, 30.0)
        lo, n = first[oid], count[oid]
        ids = s.indices[lo : lo + n].reshape(-1, 3)
        got = _canon((s.positions + s.origin).astype(np.float64), ids, s.normals, np.zeros((len(s.positions), 2)))
        want = _canon(ref[0], ref[1], ref[2], np.zeros((len(ref[0]), 2)))
        np.testing.assert_allclose(got[:, :9], want[:, :9], atol=1e-5)
        np.testing.assert_allclose(got[:, 9:18], want[:, 9:18], atol=1e-5)


def test_from_meshes_keeps_its_contract():
    parts = [(f"p{i}", v, f, None if i % 2 else n) for i, (v, f, n, _) in enumerate(_parts(6))]
    s = from_meshes(parts, [None, (1, 0, 0, 1)] + [None] * 4)
    assert s.count == 6 and s.vertex_count == sum(len(p[1]) for p in parts)
    np.testing.assert_allclose(s.colors[1], (1, 0, 0, 1))
    np.testing.assert_allclose(s.aabb_min[2], parts[2][1].min(axis=0))
    np.testing.assert_allclose(np.linalg.norm(s.normals, axis=1), 1.0, atol=1e-3)


def test_instancing_in_place_equals_the_copy():
    """instance(consume=True) transforms meshes placed once each in place; the result equals
    the copying path's, and a mesh placed twice (or out of order) still gets copies."""
    parts = _parts(6)
    meshes = batch.Meshes(
        *(np.concatenate([p[k] for p in parts]) for k in (0, 1)),
        np.array([len(p[0]) for p in parts]),
        np.array([len(p[1]) for p in parts]),
        *(np.concatenate([p[k] for p in parts]) for k in (2, 3)),
    )
    meshes.faces = meshes.faces.astype(np.int32)
    rng = np.random.default_rng(4)
    transforms = np.tile(np.eye(4), (6, 1, 1))
    transforms[:, :3, :3] = rng.normal(size=(6, 3, 3))
    transforms[:, :3, 3] = rng.normal(size=(6, 3))

    def copy():
        return batch.Meshes(
            *(None if a is None else a.copy() for a in (meshes.vertices, meshes.faces)),
            meshes.vcount,
            meshes.fcount,
            meshes.normals.copy(),
            meshes.uvs.copy(),
        )

    for mesh_of, shared in ((np.arange(6), True), (np.array([0, 1, 1, 3, 4, 5]), False)):
        want = batch.instance(copy(), mesh_of, transforms)
        source = copy()
        got = batch.instance(source, mesh_of, transforms, consume=True)
        assert (got.vertices is source.vertices) == shared
        for a, b in (
            (got.vertices, want.vertices),
            (got.normals, want.normals),
            (got.faces, want.faces),
            (got.uvs, want.uvs),
        ):
            np.testing.assert_array_equal(a, b)


def test_parallel_passes_stop_at_an_error(monkeypatch):
    """An error (or an interrupt's exception) in the passes cancels those not yet started."""
    import time

    monkeypatch.setattr(batch, "THREADS", 2)
    ran = []

    def job(k):
        ran.append(k)
        if k == 0:
            raise KeyboardInterrupt
        time.sleep(0.01)
        return k

    assert batch.parallel(lambda k: k * 2, list(range(50))) == [2 * k for k in range(50)]
    with pytest.raises(KeyboardInterrupt):
        batch.parallel(job, list(range(200)))
    assert len(ran) < 20
