"""Names of the meshes the USD reader (rtta.scene.readers.usd) draws; deterministic, a function
of the stage alone.

A mesh prim is named after itself, in the groups of the prims above it (its path's elements).
A mesh reached through native instances (an instance proxy) is named after the innermost
instance prim above it, the instance of the prototype that holds the mesh (usd-core's
GetPrimInPrototype), as a PointInstancer's instances are (rtta.scene.readers.usd_instancers:
'P_i' for a prototype of one part, else the group P_i of parts 'P_i_<name>'):

- where that instance's prototype draws one part, the part is named after the instance, in
  the groups above the instance: the mesh `geom` of /car/wheel_FL/bolt_3 is 'bolt_3' in
  car/wheel_FL;
- where it draws several, the instance is a group and each of its meshes is
  '<instance>_<mesh name>' in the groups of its own path: /car/wheel_FL/tire is
  'wheel_FL_tire' in car/wheel_FL (the wheel's bolts count among its parts).

The parts a prototype draws are counted once per prototype (keyed by its path), as the reader
would draw it were it the whole stage: its Mesh prims that the reader traverses (active,
defined), not invisible, not guides and with triangles (their meshes read through the reader's
cache, as drawing them does), plus each instance in it its prototype's count and each
PointInstancer in it its instances (invisible ones too); a `proxy` mesh counts only where the
prototype draws no `render` one. A `default` mesh takes the purpose its instance prim passes
down (usd_stage.inherited), as it does when drawn. Counted so, the names are known as each
mesh is met; the count is an upper bound where the stage's proxies are left out for `render`
parts outside the prototype (then its one drawn mesh may be '<instance>_<mesh name>').
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from . import usd_instancers, usd_stage

Counts = tuple[int, int, int]  # a prototype's drawn parts of purpose default, render and proxy
_PURPOSES = (usd_stage.DEFAULT, usd_stage.RENDER, usd_stage.PROXY)


class Names:
    """(name, groups) of each mesh prim the reader draws; `mesh_of` is its (prim -> (vertices,
    triangles, colour)), `get` its ((attribute, time) -> value), `time` the Usd.TimeCode the
    stage is read at."""

    def __init__(self, mesh_of: Callable, get: Callable, time: Any) -> None:
        self.mesh_of, self.get, self.time = mesh_of, get, time
        self.counts: dict = {}  # prototype path -> Counts, its instances' included
        self.scanned: dict = {}  # prototype path -> (its own Counts, its instances: see _scan)

    def __call__(self, prim) -> tuple[str, tuple[str, ...]]:
        if not prim.IsInstanceProxy():
            return prim.GetName(), _groups(prim)
        inside = prim.GetPrimInPrototype().GetPath()  # in the innermost prototype
        owner = prim
        for _ in range(inside.pathElementCount - 1):  # up to the instance of that prototype
            owner = owner.GetParent()
        if not owner.IsInstance() or self.parts(owner) <= 1:
            return owner.GetName(), _groups(owner)
        return f"{owner.GetName()}_{prim.GetName()}", _groups(prim)

    def parts(self, instance) -> int:
        """How many parts the instance prim `instance` draws (the module's docstring says how
        they are counted)."""
        default, render, proxy = _passed(self._counts(instance.GetPrototype()), usd_stage.inherited(instance))
        return default + render + (proxy if not render else 0)

    def _counts(self, root) -> Counts:
        """The Counts of the prototype at `root`, its instances' included: each prototype
        scanned once, innermost first, without recursion (instances nest without a bound)."""
        stack = [root]
        while stack:
            key = stack[-1].GetPath()
            if key in self.counts:
                stack.pop()
                continue
            if key not in self.scanned:
                self.scanned[key] = self._scan(stack[-1])
            own, inside = self.scanned[key]
            waiting = [p for p, _ in inside if p.GetPath() not in self.counts and p.GetPath() not in self.scanned]
            if waiting:
                stack += waiting
                continue
            stack.pop()
            total = list(own)
            for prototype, passed in inside:  # one in a cycle (refused before reading) counts nothing
                for i, n in enumerate(_passed(self.counts.get(prototype.GetPath(), (0, 0, 0)), passed)):
                    total[i] += n
            self.counts[key] = (total[0], total[1], total[2])
        return self.counts[root.GetPath()]

    def _scan(self, root) -> tuple[Counts, list]:
        """The Counts of the prototype at `root` without its instances, and its instances'
        (prototype prim, the purpose its instance prim passes down)."""
        from pxr import Usd, UsdGeom

        own, inside = [0, 0, 0], []
        prims = iter(Usd.PrimRange(root, Usd.PrimDefaultPredicate))  # the reader's, without instance proxies
        for prim in usd_instancers.visible(prims, self.get, self.time):
            if prim.IsA(UsdGeom.PointInstancer):
                prims.PruneChildren()
                own[0] += usd_instancers.instance_counts(prim, self.get, self.time)[0]
                continue
            if prim.IsInstance():
                inside.append((prim.GetPrototype(), usd_stage.inherited(prim)))
            if prim.IsA(UsdGeom.Mesh) and (purpose := usd_stage.purpose(prim)) != usd_stage.GUIDE:
                own[_PURPOSES.index(purpose)] += int(len(self.mesh_of(prim)[1]) > 0)
        return (own[0], own[1], own[2]), inside


def _passed(counts: Counts, passed: str) -> Counts:
    """`counts` of a prototype whose instance prim passes down the purpose `passed` (as
    usd_stage.inherited gives it): its `default` parts take it (left out where it is `guide`)."""
    default, render, proxy = counts
    if passed == usd_stage.GUIDE:
        return 0, render, proxy
    if passed == usd_stage.RENDER:
        return 0, render + default, proxy
    if passed == usd_stage.PROXY:
        return 0, render, proxy + default
    return counts


def _groups(prim) -> tuple[str, ...]:
    """The names of the prims above `prim`, from the root down."""
    return tuple(p for p in prim.GetPath().GetParentPath().pathString.split("/") if p)
