"""USD PointInstancers (rtta.scene.readers.usd_instancers): each instance of a prototype is a
part (a group of parts for a prototype of several meshes) placed by its position, orientation
and scale, the prototype root's and the instancer's transforms; invisible ids are left out;
the prototypes are not drawn in place; names are deterministic; nested instancers are
expanded; instancers too large for the file are refused from their counts in one line. Also:
a value usd-core cannot read is one short line without C++ text."""

from __future__ import annotations

import struct
import time
from pathlib import Path

import numpy as np
import pytest

from rtta.cli.main import main
from rtta.errors import RttaError
from rtta.scene.loader import load_scene

pytest.importorskip("pxr")

CUBE = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], np.float64)
QUADS = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]]
S = 0.5**0.5
# per instance: prototype, position, orientation (w, x, y, z), scale
INSTANCES = [
    (0, (5, 0, 0), (1, 0, 0, 0), (1, 1, 1)),
    (1, (15, 0, 0), (S, 0, 0, S), (2, 2, 2)),  # 90 degrees about z
    (0, (25, 0, 0), (0, 1, 0, 0), (1, 3, 1)),  # 180 degrees about x
    (1, (35, 0, 0), (1, 0, 0, 0), (1, 1, 1)),  # in invisibleIds
    (0, (45, 0, 0), (S, 0, S, 0), (1, 1, 2)),  # 90 degrees about y
]


def _cube(stage, at: str, offset=(0, 0, 0), color=None):
    from pxr import Gf, UsdGeom

    mesh = UsdGeom.Mesh.Define(stage, at)
    mesh.GetPointsAttr().Set([Gf.Vec3f(*(p + offset)) for p in CUBE])
    mesh.GetFaceVertexCountsAttr().Set([4] * 6)
    mesh.GetFaceVertexIndicesAttr().Set([i for q in QUADS for i in q])
    if color:
        mesh.GetDisplayColorAttr().Set([Gf.Vec3f(*color)])
    return mesh


def _scatter(path: Path) -> None:
    """/World (moved by (100, 0, 0)) holds the instancer `scatter` (moved by (0, 50, 0)), whose
    prototypes are `box`, a red unit cube, and `pair` (moved up by 1): the cube `a` and, in
    `arm` (scaled by 2), the cube `b` (moved by (1, 0, 0)); INSTANCES place them."""
    from pxr import Gf, Usd, UsdGeom

    stage = Usd.Stage.CreateNew(str(path))
    UsdGeom.Xform.Define(stage, "/World").AddTranslateOp().Set(Gf.Vec3d(100, 0, 0))
    pi = UsdGeom.PointInstancer.Define(stage, "/World/scatter")
    pi.AddTranslateOp().Set(Gf.Vec3d(0, 50, 0))
    UsdGeom.Scope.Define(stage, "/World/scatter/Prototypes")
    _cube(stage, "/World/scatter/Prototypes/box", color=(1, 0, 0))
    UsdGeom.Xform.Define(stage, "/World/scatter/Prototypes/pair").AddTranslateOp().Set(Gf.Vec3d(0, 0, 1))
    _cube(stage, "/World/scatter/Prototypes/pair/a")
    UsdGeom.Xform.Define(stage, "/World/scatter/Prototypes/pair/arm").AddScaleOp().Set(Gf.Vec3f(2, 2, 2))
    _cube(stage, "/World/scatter/Prototypes/pair/arm/b", offset=(1, 0, 0))
    pi.CreatePrototypesRel().SetTargets(["/World/scatter/Prototypes/box", "/World/scatter/Prototypes/pair"])
    pi.CreateProtoIndicesAttr([k for k, *_ in INSTANCES])
    pi.CreatePositionsAttr([Gf.Vec3f(*p) for _, p, _, _ in INSTANCES])
    pi.CreateOrientationsfAttr([Gf.Quatf(*q) for _, _, q, _ in INSTANCES])
    pi.CreateScalesAttr([Gf.Vec3f(*s) for *_, s in INSTANCES])
    pi.CreateInvisibleIdsAttr([3])
    stage.GetRootLayer().Save()


def _row(translate=(0, 0, 0), quat=(1, 0, 0, 0), scale=(1, 1, 1)) -> np.ndarray:
    """scale, then rotate, then translate, as a 4x4 for row vectors (p @ M)."""
    w, x, y, z = quat
    rot = np.array(  # column vectors
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )
    m = np.eye(4)
    m[:3, :3] = np.diag(scale) @ rot.T
    m[3, :3] = translate
    return m


def _bounds(points: np.ndarray, m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    p = points @ m[:3, :3] + m[3, :3]
    return p.min(axis=0), p.max(axis=0)


def test_point_instances_are_parts_placed_by_their_transforms(tmp_path):
    """Five instances of two prototypes, one invisible: the box's three and the pair's one
    (two parts, grouped), each where its prototype lands under the analytic transforms."""
    path = tmp_path / "scatter.usda"
    _scatter(path)
    s = load_scene(path, cache=False)
    assert s.names == ["box_0", "pair_1_a", "pair_1_b", "box_2", "box_4"], s.names
    assert [s.path_of(i) for i in range(s.count)] == [
        ("World", "scatter"),
        ("World", "scatter", "pair_1"),
        ("World", "scatter", "pair_1", "arm"),
        ("World", "scatter"),
        ("World", "scatter"),
    ]
    instancer = _row((0, 50, 0)) @ _row((100, 0, 0))
    pair = _row((0, 0, 1))  # the prototype root's own transform
    box, a = (CUBE, np.eye(4)), (CUBE, pair)
    b = (CUBE + (1, 0, 0), _row(scale=(2, 2, 2)) @ pair)  # `arm`'s scale, then the root's
    expected = {"box_0": (box, 0), "pair_1_a": (a, 1), "pair_1_b": (b, 1), "box_2": (box, 2), "box_4": (box, 4)}
    for name, ((points, inside), i) in expected.items():
        _, position, quat, scale = INSTANCES[i]
        lo, hi = _bounds(points, inside @ _row(position, quat, scale) @ instancer)
        np.testing.assert_allclose(s.aabb_min[s.index(name)], lo, atol=1e-4, err_msg=name)
        np.testing.assert_allclose(s.aabb_max[s.index(name)], hi, atol=1e-4, err_msg=name)
    assert np.allclose(s.colors[[0, 3, 4], :3], [1, 0, 0])  # the box's displayColor, on every instance
    own = _bounds(CUBE, instancer)  # the box prototype where it is defined: not drawn there
    assert not any(np.allclose(s.aabb_min[i], own[0]) and np.allclose(s.aabb_max[i], own[1]) for i in range(s.count))
    again = load_scene(path, cache=False)
    assert again.names == s.names and again.paths == s.paths


def _nested(path: Path) -> None:
    """A class /C holds the instancer `trees` whose prototype `tree` holds the mesh `trunk`
    and the instancer `leaves` (three of the mesh `leaf`, under an `over`); /a and /b are
    native instances of /C, /b moved by (0, 100, 0). The instancer /bolts draws the mesh
    /Lib/bolt, which sits under an `over` (not drawn in place), twice."""
    from pxr import Gf, Sdf, Usd, UsdGeom

    stage = Usd.Stage.CreateNew(str(path))
    stage.CreateClassPrim("/C")
    trees = UsdGeom.PointInstancer.Define(stage, "/C/trees")
    _cube(stage, "/C/trees/P/tree/trunk")
    leaves = UsdGeom.PointInstancer.Define(stage, "/C/trees/P/tree/leaves")
    _cube(stage, "/C/trees/P/tree/leaves/P/leaf")
    stage.GetPrimAtPath("/C/trees/P/tree/leaves/P").SetSpecifier(Sdf.SpecifierOver)
    leaves.CreatePrototypesRel().SetTargets(["/C/trees/P/tree/leaves/P/leaf"])
    leaves.CreateProtoIndicesAttr([0, 0, 0])
    leaves.CreatePositionsAttr([Gf.Vec3f(0, 0, 2 * k + 2) for k in range(3)])
    trees.CreatePrototypesRel().SetTargets(["/C/trees/P/tree"])
    trees.CreateProtoIndicesAttr([0, 0])
    trees.CreatePositionsAttr([Gf.Vec3f(10 * k, 0, 0) for k in range(2)])
    for k, name in enumerate(("a", "b")):
        x = UsdGeom.Xform.Define(stage, f"/{name}")
        x.GetPrim().GetReferences().AddInternalReference("/C")
        x.GetPrim().SetInstanceable(True)
        x.AddTranslateOp().Set(Gf.Vec3d(0, 100 * k, 0))
    _cube(stage, "/Lib/bolt")
    stage.GetPrimAtPath("/Lib").SetSpecifier(Sdf.SpecifierOver)
    bolts = UsdGeom.PointInstancer.Define(stage, "/bolts")
    bolts.CreatePrototypesRel().SetTargets(["/Lib/bolt"])
    bolts.CreateProtoIndicesAttr([0, 0])
    bolts.CreatePositionsAttr([Gf.Vec3f(0, 0, -10 * k - 10) for k in range(2)])
    stage.GetRootLayer().Save()


def test_nested_instancers_and_instancers_in_native_instances(tmp_path):
    """Two native instances of an instancer of two trees, each a trunk and an instancer of
    three leaves: 16 parts, each in its place; names repeated between /a and /b are numbered."""
    path = tmp_path / "forest.usda"
    _nested(path)
    s = load_scene(path, cache=False)
    assert s.count == 2 * 2 * 4 + 2, s.names
    for base, y in (("a", 0), ("b", 100)):
        for tree in range(2):
            group = (base, "trees", f"tree_{tree}")
            trunk = [i for i in range(s.count) if s.path_of(i) == group]
            leaves = [i for i in range(s.count) if s.path_of(i) == (*group, "leaves")]
            assert len(trunk) == 1 and len(leaves) == 3
            np.testing.assert_allclose(s.aabb_min[trunk[0]], [10 * tree, y, 0], atol=1e-6)
            np.testing.assert_allclose(s.aabb_min[leaves, 2], [2, 4, 6], atol=1e-6)
    assert s.names[:4] == ["tree_0_trunk", "tree_0_leaf_0", "tree_0_leaf_1", "tree_0_leaf_2"]
    bolts = [s.names.index("bolt_0"), s.names.index("bolt_1")]
    np.testing.assert_allclose(s.aabb_min[bolts, 2], [-10, -20])
    assert all(s.path_of(i) == ("bolts",) for i in bolts)


def test_a_broken_instancer_is_a_warning_and_an_invisible_one_draws_nothing(tmp_path):
    """An index naming no prototype: usd-core computes no transforms, so the instancer is not
    drawn, with a warning that says why; an invisible instancer draws nothing; the mesh
    beside them loads."""
    from pxr import Gf, Usd, UsdGeom

    path = tmp_path / "broken.usda"
    stage = Usd.Stage.CreateNew(str(path))
    _cube(stage, "/kept")
    for name in ("bad", "hidden"):
        pi = UsdGeom.PointInstancer.Define(stage, f"/{name}")
        _cube(stage, f"/{name}/P/box")
        pi.CreatePrototypesRel().SetTargets([f"/{name}/P/box"])
        pi.CreateProtoIndicesAttr([0, 3] if name == "bad" else [0, 0])
        pi.CreatePositionsAttr([Gf.Vec3f(5, 0, 0)] * 2)
    UsdGeom.Imageable(stage.GetPrimAtPath("/hidden")).MakeInvisible()
    stage.GetRootLayer().Save()
    s = load_scene(path, cache=False)
    assert s.names == ["kept"]
    assert any("PointInstancer /bad is not drawn: invalid prototype index: 3" in w for w in s.warnings), s.warnings


def _flat_bomb(path: Path, count: int) -> None:
    """One instancer of `count` instances of a triangle, in a binary layer (protoIndices of
    zeros compress to a few bytes per thousand)."""
    from pxr import Gf, Usd, UsdGeom, Vt  # pyright: ignore[reportAttributeAccessIssue]  (usd-core's stubs lack Vt)

    stage = Usd.Stage.CreateNew(str(path))
    pi = UsdGeom.PointInstancer.Define(stage, "/PI")
    mesh = UsdGeom.Mesh.Define(stage, "/PI/P/tri")
    mesh.GetPointsAttr().Set([Gf.Vec3f(0, 0, 0), Gf.Vec3f(1, 0, 0), Gf.Vec3f(0, 1, 0)])
    mesh.GetFaceVertexCountsAttr().Set([3])
    mesh.GetFaceVertexIndicesAttr().Set([0, 1, 2])
    pi.CreatePrototypesRel().SetTargets(["/PI/P/tri"])
    pi.CreateProtoIndicesAttr(Vt.IntArray.FromNumpy(np.zeros(count, np.int32)))
    stage.GetRootLayer().Save()


def _nested_bomb(path: Path, levels: int, fan: int) -> None:
    """The instancer /L has `fan` instances of its prototype L/P/L, an instancer of `fan`
    instances of its own prototype, and so on `levels` deep; the innermost is a triangle."""
    from pxr import Gf, Usd, UsdGeom

    stage = Usd.Stage.CreateNew(str(path))
    at = "/L"
    for _ in range(levels):
        pi = UsdGeom.PointInstancer.Define(stage, at)
        pi.CreatePrototypesRel().SetTargets([f"{at}/P/L"])
        pi.CreateProtoIndicesAttr([0] * fan)
        at += "/P/L"
    mesh = UsdGeom.Mesh.Define(stage, at)
    mesh.GetPointsAttr().Set([Gf.Vec3f(0, 0, 0), Gf.Vec3f(1, 0, 0), Gf.Vec3f(0, 1, 0)])
    mesh.GetFaceVertexCountsAttr().Set([3])
    mesh.GetFaceVertexIndicesAttr().Set([0, 1, 2])
    stage.GetRootLayer().Save()


@pytest.mark.parametrize(
    "name,write,says",
    [
        ("flat.usdc", lambda p: _flat_bomb(p, 20_000_000), "makes 20,000,000 parts in 40,000,00"),
        ("nested.usda", lambda p: _nested_bomb(p, 4, 100), "makes 100,000,000 parts in"),
    ],
)
def test_instancer_bombs_are_refused_in_one_line(tmp_path, capsys, name, write, says):
    """20 million instances in a 20 KB binary layer, and four levels of 100 in 2 KB: refused
    from protoIndices' lengths before any instance is built."""
    path = tmp_path / name
    write(path)
    assert path.stat().st_size < 50_000
    t0 = time.perf_counter()
    assert main(["info", "--no-cache", str(path)]) == 2
    assert time.perf_counter() - t0 < 10
    err = [line for line in capsys.readouterr().err.splitlines() if line.strip()]
    assert len(err) == 1 and err[0].startswith(f"rtta: error: {path}: the USD stage") and says in err[0], err


def test_an_instancer_whose_prototype_holds_it_is_one_line(tmp_path):
    """A prototype that is the instancer's own parent would expand without end."""
    from pxr import Usd, UsdGeom

    path = tmp_path / "loop.usda"
    stage = Usd.Stage.CreateNew(str(path))
    UsdGeom.Xform.Define(stage, "/top")
    pi = UsdGeom.PointInstancer.Define(stage, "/top/pi")
    _cube(stage, "/top/box")
    pi.CreatePrototypesRel().SetTargets(["/top"])
    pi.CreateProtoIndicesAttr([0, 0])
    stage.GetRootLayer().Save()
    with pytest.raises(RttaError, match=r"the USD stage's instances hold themselves \(a cycle\)$"):
        load_scene(path, cache=False)


def test_a_damaged_value_is_one_short_line(tmp_path, capsys):
    """A binary layer whose points array names a value type that does not exist (the type byte
    of its ValueRep changed): usd-core's C++ error, made one line that names the attribute."""
    from pxr import Usd

    path = tmp_path / "damaged.usdc"
    stage = Usd.Stage.CreateNew(str(path))
    _cube(stage, "/m")
    stage.GetRootLayer().Save()
    data = bytearray(path.read_bytes())
    arrays = [  # uint64 ValueReps: array, not inlined, of GfVec3f (type 24) at an offset in the file
        at
        for at in range(len(data) - 8)
        if (rep := struct.unpack_from("<Q", data, at)[0]) >> 56 == 0x80 and (rep >> 48) & 0xFF == 24
        if (rep & (1 << 48) - 1) < len(data)
    ]
    if len(arrays) != 1:
        pytest.skip(f"this usd-core writes the points' ValueRep where the test does not find it: {arrays}")
    data[arrays[0] + 6] = 0xEE
    path.write_bytes(bytes(data))
    assert main(["info", "--no-cache", str(path)]) == 2
    err = [line for line in capsys.readouterr().err.splitlines() if line.strip()]
    assert err == [
        f"rtta: error: {path}: cannot read the value of /m.points (Attempted to unpack unsupported type enum value 238)"
    ]
