"""UsdGeom.PointInstancer for the USD reader (rtta.scene.readers.usd): every instance of a
prototype (a prim subtree that the instancer's `prototypes` relationship names) becomes parts,
placed by UsdGeom.PointInstancer.ComputeInstanceTransformsAtTime (positions, orientations,
scales and the prototype root's own transform) and then by the instancer's own transform;
the ids in invisibleIds and inactiveIds are left out. Every value is read at the time code
the reader reads the stage at (rtta.scene.readers.usd_stage.read_time).

As Hydra draws them: the instancer's children (its prototypes, by convention) are never drawn
in place, and a prototype elsewhere is drawn in place only where the stage draws it anyway
(a `def` prim, not an `over` or a `class`). Inside a prototype every active mesh that is not
invisible (up to the prototype's root) is drawn, and instancers nested in a prototype are
expanded too, their parts placed in each instance of the prototype (at most MAX_DEPTH deep).
Each part has a purpose: its mesh's (UsdGeom.Imageable.ComputePurpose, which inherits through
the prototype's ancestors in the stage), or the instancer's where the mesh's is `default`;
guide meshes are not read, the reader leaves out guide parts and decides on proxy ones.

Names (deterministic; unique while the meshes of a prototype have distinct names): instance i
of prototype P of the instancer /a/I is the part 'P_i' in the group a/I when P makes one part;
else the group a/I/P_i holds P's parts, each 'P_i_<its name in P>' in the groups of the prims
between P and it. A nested instancer's parts are named so inside P, e.g. 'tree_3_leaf_7' in
a/I/tree_3/leaves.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from ...errors import RttaError
from . import native_output, usd_stage

MAX_DEPTH = 32  # instancers nested in prototypes of instancers
CHUNK = 1 << 22  # protoIndices counted this many at a time (np.bincount makes an int64 copy)


class Part(NamedTuple):
    """One part an instancer makes: its name, its groups below the instancer's parent, its
    transform (row vectors, p @ matrix: prototype space to the instancer's, or to the world
    once placed), its mesh (vertices, triangles, colour), the instance it belongs to and its
    purpose (usd_stage.DEFAULT, RENDER or PROXY; GUIDE where its instancer's is)."""

    name: str
    groups: tuple[str, ...]
    matrix: np.ndarray
    mesh: tuple
    instance: str
    purpose: str = usd_stage.DEFAULT


@dataclass
class Context:
    """What expanding the stage's instancers shares: the transform cache, the reader's mesh
    function (prim -> (vertices, triangles, colour)), its `get` ((attribute, time) -> value),
    the Usd.TimeCode the stage is read at, the warnings, the file, and each prototype's parts,
    read once for all its instances (keyed by the prototype and the purpose it inherits)."""

    cache: Any  # UsdGeom.XformCache at `time`
    mesh_of: Callable
    get: Callable
    time: Any  # Usd.TimeCode
    warnings: list[str]
    path: Path
    known: dict = field(default_factory=dict)


def instance_counts(prim, get: Callable, time) -> tuple[int, dict]:
    """How many instances the PointInstancer `prim` makes at the Usd.TimeCode `time` (the
    length of its protoIndices), and how many of them each prototype has (prototype path ->
    count; indices that name no prototype are not counted, as the instancer is then not
    drawn). Invisible and inactive ids are counted: an upper bound."""
    from pxr import UsdGeom

    instancer = UsdGeom.PointInstancer(prim)
    index = get(instancer.GetProtoIndicesAttr(), time)
    if index is None or not len(index):
        return 0, {}
    targets = instancer.GetPrototypesRel().GetTargets()
    index = np.asarray(index)
    counts = np.zeros(len(targets) + 1, np.int64)
    for a in range(0, len(index), CHUNK):
        chunk = index[a : a + CHUNK]
        named = (chunk >= 0) & (chunk < len(targets))
        counts += np.bincount(np.where(named, chunk, len(targets)), minlength=len(targets) + 1)
    inside: dict = {}
    for target, n in zip(targets, counts[:-1].tolist(), strict=True):
        root = prim.GetStage().GetPrimAtPath(target) if n else None
        if root:  # a prototype inside a native instance: counted as the prim of its prototype
            key = root.GetPrimInPrototype().GetPath() if root.IsInstanceProxy() else target
            inside[key] = inside.get(key, 0) + n
    return len(index), inside


def prototype_range(root, through_instances: bool = True):
    """The prims of the prototype at `root`, root first: active and loaded ones, defined or
    not (prototypes often sit under an `over`), through native instances or not."""
    from pxr import Usd

    prims = Usd.PrimIsActive & Usd.PrimIsLoaded
    return Usd.PrimRange(root, Usd.TraverseInstanceProxies(prims) if through_instances else prims)


def parts(prim, world: np.ndarray, ctx: Context) -> Iterator[Part]:
    """The parts of the PointInstancer `prim` whose local-to-world transform is `world`
    (row vectors), placed in the world and grouped under the instancer's path."""
    groups = tuple(p for p in prim.GetPath().pathString.split("/") if p)
    for part in _instances(prim, ctx, 0):
        yield part._replace(groups=groups + part.groups, matrix=part.matrix @ world)


def _instances(prim, ctx: Context, depth: int) -> Iterator[Part]:
    """The parts of the instancer `prim` in its own space, each instance's in turn; a part
    whose purpose is `default` takes the instancer's (as Hydra does)."""
    from pxr import UsdGeom

    instancer = UsdGeom.PointInstancer(prim)
    transforms, keep = _transforms(instancer, ctx)
    if not len(keep):
        return
    targets = instancer.GetPrototypesRel().GetTargets()
    index = np.asarray(ctx.get(instancer.GetProtoIndicesAttr(), ctx.time))
    stage, where, own = prim.GetStage(), prim.GetPath().pathString, usd_stage.purpose(prim)
    prototypes: dict[int, tuple] = {}  # prototype index -> (its root's name, its parts)
    for i in keep.tolist():
        k = int(index[i])
        if k not in prototypes:
            root = stage.GetPrimAtPath(targets[k])
            prototypes[k] = (root.GetName(), _prototype(root, ctx, depth)) if root else ("", [])
        name, inside = prototypes[k]
        label = f"{name}_{i}"
        for part in inside:
            one = len(inside) == 1
            yield Part(
                label if one else f"{label}_{part.name}",
                () if one else (label, *part.groups),
                part.matrix @ transforms[i],
                part.mesh,
                f"{where}/{label}",
                own if part.purpose == usd_stage.DEFAULT else part.purpose,
            )


def _transforms(instancer, ctx: Context) -> tuple[np.ndarray, np.ndarray]:
    """Each instance's transform [N, 4, 4] (the prototype root's own included) and the
    indices of the instances drawn (not in invisibleIds or inactiveIds). usd-core's warnings
    on the instancer's data (an index with no prototype, arrays of the wrong length) become
    the reader's; where it computes no transforms, no instance is drawn."""
    from pxr import UsdGeom

    time, kind = ctx.time, UsdGeom.PointInstancer
    with native_output() as said:
        matrices = instancer.ComputeInstanceTransformsAtTime(time, time, kind.IncludeProtoXform, kind.IgnoreMask)
        mask = instancer.ComputeMaskAtTime(time)
    matrices = np.asarray(matrices, np.float64).reshape(-1, 4, 4)
    keep = np.flatnonzero(np.asarray(mask, bool)) if len(mask) else np.arange(len(matrices))
    keep = keep[keep < len(matrices)]
    reasons = "; ".join(dict.fromkeys(line.rsplit(" -- ", 1)[-1] for line in said))[:200]
    if reasons:
        drawn = "" if len(matrices) else " is not drawn"
        ctx.warnings.append(f"PointInstancer {instancer.GetPath()}{drawn}: {reasons}")
    return matrices, keep


def _prototype(root, ctx: Context, depth: int) -> list[Part]:
    """The parts of the prototype at `root` in its own space, read once for all instances
    that inherit the same purpose (a prototype in native instances under prims of different
    purposes has parts of different purposes)."""
    key = root.GetPrimInPrototype().GetPath() if root.IsInstanceProxy() else root.GetPath()
    key = (key, usd_stage.inherited(root.GetParent()))
    if key not in ctx.known:
        if depth >= MAX_DEPTH:
            raise RttaError(f"the USD stage nests PointInstancers more than {MAX_DEPTH} deep", ctx.path)
        ctx.known[key] = list(_walk(root, ctx, depth))
    return ctx.known[key]


def _walk(root, ctx: Context, depth: int) -> Iterator[Part]:
    """The meshes of the prototype at `root`, and its nested instancers' parts, in file order;
    invisible prims and what lies below them left out, and guide meshes (a purpose of the
    mesh's own is final)."""
    from pxr import UsdGeom

    prims = iter(prototype_range(root))
    for prim in visible(prims, ctx.get, ctx.time):
        if prim.IsA(UsdGeom.PointInstancer):
            prims.PruneChildren()
            below = _below(prim, root)
            matrix = _relative(prim, root, ctx)
            for part in _instances(prim, ctx, depth + 1):
                yield part._replace(groups=(*below, *part.groups), matrix=part.matrix @ matrix)
        elif prim.IsA(UsdGeom.Mesh) and (purpose := usd_stage.purpose(prim)) != usd_stage.GUIDE:
            mesh = ctx.mesh_of(prim)
            if len(mesh[1]):
                yield Part(prim.GetName(), _below(prim, root)[:-1], _relative(prim, root, ctx), mesh, "", purpose)


def visible(prims, get: Callable, time) -> Iterator:
    """The prims of the Usd.PrimRange iterator `prims` but those whose own visibility is
    invisible at `time` and what lies below them (`get`: the reader's (attribute, time) ->
    value). The caller may prune `prims` below a prim while it holds it."""
    from pxr import UsdGeom

    for prim in prims:
        visibility = UsdGeom.Imageable(prim).GetVisibilityAttr()
        if visibility and get(visibility, time) == UsdGeom.Tokens.invisible:
            prims.PruneChildren()
            continue
        yield prim


def _below(prim, root) -> tuple[str, ...]:
    """The names of the prims from below `root` down to `prim` (empty when it is the root)."""
    if prim.GetPath() == root.GetPath():
        return ()
    return tuple(prim.GetPath().MakeRelativePath(root.GetPath()).pathString.split("/"))


def _relative(prim, root, ctx: Context) -> np.ndarray:
    """`prim`'s transform into the space of `root` (whose own transform the instance
    transforms hold), row vectors."""
    if prim.GetPath() == root.GetPath():
        return np.eye(4)
    matrix, _ = ctx.cache.ComputeRelativeTransform(prim, root)
    return np.array(matrix, np.float64)
