"""What the USD reader (rtta.scene.readers.usd) draws of a stage: the one time code it reads
every value at, and the purposes it draws.

Time: the stage's start time code where it authors a time code range (startTimeCode and
endTimeCode, in its root or session layer): the frame usdview opens at. Else
Usd.TimeCode.EarliestTime(): an attribute's first time sample where it has samples, its
default value where it has none. At either time an attribute with both a default value and
time samples gives the samples' value (the default counts only at Usd.TimeCode.Default()), so
an animated export (points and xformOps only time-sampled) is drawn at its first frame.

Purpose (UsdGeom.Imageable.ComputePurpose: a prim's authored purpose, else the one inherited
from the nearest prim above it that authors one, through instance proxies too): `default` and
`render` are drawn, `guide` never, `proxy` only where the stage draws no part of purpose
`render` (a file that ships only proxies still shows them). A PointInstancer's prototype prim
whose purpose is `default` takes the instancer's, as Hydra does. Subtrees are not pruned by
purpose: a prim's own authored purpose wins over its parent's (a `render` mesh under a `guide`
Xform is drawn).
"""

from __future__ import annotations

import math
from pathlib import Path

from . import Assembly, hidden

DEFAULT, RENDER, PROXY, GUIDE = "default", "render", "proxy", "guide"


def read_time(stage):
    """The Usd.TimeCode every value of `stage` is read at (the module's docstring says why)."""
    from pxr import Usd

    start = stage.GetStartTimeCode()
    if stage.HasAuthoredTimeCodeRange() and math.isfinite(start):  # at NaN every value reads as none
        return Usd.TimeCode(start)
    return Usd.TimeCode.EarliestTime()


def purpose(prim) -> str:
    """`prim`'s computed purpose: DEFAULT, RENDER, PROXY or GUIDE (a token the schema does not
    know, which a file may author, as DEFAULT: drawn)."""
    from pxr import UsdGeom

    return _known(str(UsdGeom.Imageable(prim).ComputePurpose()))


def inherited(prim) -> str:
    """The purpose `prim`'s children without an opinion of their own take ('' where none
    above them authors one)."""
    from pxr import UsdGeom

    passed = str(UsdGeom.Imageable(prim).ComputePurposeInfo().GetInheritablePurpose())
    return passed and _known(passed)


def _known(token: str) -> str:
    return token if token in (DEFAULT, RENDER, PROXY, GUIDE) else DEFAULT


class Drawn:
    """The parts a stage draws and the prims whose singular transform hid a mesh, in file
    order, each with its purpose, kept until `finish` knows whether a `render` part is drawn
    (and so whether the `proxy` ones are)."""

    def __init__(self) -> None:
        self.parts: list[tuple[str, tuple]] = []
        self.hiders: dict[str, bool] = {}  # prim path -> whether it hid only proxy meshes

    def add(self, purpose: str, *part) -> None:
        """A part of `purpose`; `part` is Assembly.add's arguments."""
        self.parts.append((purpose, part))

    def hider(self, where: str, purpose: str) -> None:
        self.hiders[where] = self.hiders.get(where, True) and purpose == PROXY

    def finish(self, out: Assembly, path: Path) -> None:
        """Add the parts drawn to `out`, the proxies only where no part is `render`; note the
        hiders of what is drawn."""
        proxies = not any(p == RENDER for p, _ in self.parts)
        for p, part in self.parts:
            if proxies or p != PROXY:
                out.add(*part)
        hiders = [where for where, proxy in self.hiders.items() if proxies or not proxy]
        hidden.note_hidden(hiders, len(out.names), path, out.warnings)
