"""IFC buildings through ifcopenshell's geometry iterator (world coordinates).

Each product with a body becomes one object named `IfcWall 'name'`, its path the spatial
tree above it (project › site › building › storey, through spatial containment and
aggregation). Openings and spaces are left out (they are voids and volumes, not things).
ifcopenshell reads a truncated file without complaint, so the STEP trailer is checked first.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from ...errors import RttaError, reason
from ...outputs import signals_held
from . import Assembly, unit_name

LEFT_OUT = ("IfcOpeningElement", "IfcSpace")
# the geometry iterator's threads: more than the cores pays (on 2 cores, 10,000 walls took
# 10.1 s with 1 thread, 17.0 with 2, 7.4 with 4, 6.3-8.2 with 8 or 16)
THREADS = min(32, max(8, os.cpu_count() or 1))


def read(path: Path, left_out: tuple[str, ...] = LEFT_OUT) -> Assembly:
    _check_text(path)
    with signals_held():  # a signal during a native module's initialisation crashes it
        import ifcopenshell
        import ifcopenshell.geom
        import ifcopenshell.util.unit

    try:
        model = ifcopenshell.open(str(path))
    except Exception as exc:  # ifcopenshell raises several types for bad files
        raise RttaError(f"cannot read IFC file ({_reason(exc)})", path) from None
    try:
        scale = float(ifcopenshell.util.unit.calculate_unit_scale(model))
    except Exception:
        scale = 1.0
    out = Assembly(unit=unit_name(scale), up_axis="z")
    settings = ifcopenshell.geom.settings()
    settings.set("use-world-coords", True)
    exclude = [e for kind in left_out for e in model.by_type(kind)]
    products = [p for p in model.by_type("IfcProduct") if p.Representation is not None]
    if not [p for p in products if p.is_a() not in left_out]:
        raise RttaError("the IFC file has no products with geometry", path)
    try:
        # (by_type's entities are what exclude takes: ifcopenshell's annotations say otherwise)
        it = ifcopenshell.geom.iterator(settings, model, THREADS, exclude=exclude or None)  # pyright: ignore[reportArgumentType]
        ok = it.initialize()
    except Exception as exc:
        raise RttaError(f"cannot read IFC geometry ({_reason(exc)})", path) from None
    found, memo = [], {}
    while ok:
        shape: Any = it.get()  # a triangulated element: id, geometry (not in ifcopenshell's annotations)
        element = model.by_id(shape.id)
        assert element is not None, "the iterator yields the model's own elements"
        geometry = shape.geometry
        v = np.asarray(geometry.verts, np.float64).reshape(-1, 3) / scale
        f = np.asarray(geometry.faces, np.int64).reshape(-1, 3)
        found.append((tree_path(element, memo), element.id(), label(element), v, f, _color(geometry)))
        ok = it.next()
    for group, _, name, v, f, color in sorted(found, key=lambda t: t[:2]):  # the iterator's threads vary the order
        out.add(name, v, f, color, group)
    return out


def _reason(exc: Exception) -> str:
    return reason(exc)


def _check_text(path: Path) -> None:
    with open(path, "rb") as fh:
        head = fh.read(4096).decode("latin-1").lstrip("\ufeff \r\n\t")
        fh.seek(max(0, path.stat().st_size - 4096))
        tail = fh.read().decode("latin-1")
    if not head.startswith("ISO-10303-21"):
        raise RttaError("not an IFC file (no 'ISO-10303-21;' header; IFC-XML and ifcZIP are not read)", path)
    if "END-ISO-10303-21" not in tail:
        raise RttaError("IFC file is truncated (no 'END-ISO-10303-21;' at its end)", path)


def label(element) -> str:
    """`IfcWall 'name'`, or `IfcWall #id` for an element without a name."""
    name = getattr(element, "Name", None)
    return f"{element.is_a()} '{name}'" if name else f"{element.is_a()} #{element.id()}"


def _group(element) -> str:
    name = getattr(element, "Name", None)
    return str(name) if name else element.is_a()


def tree_path(element, memo: dict | None = None) -> tuple[str, ...]:
    """Names of the spatial elements and aggregates above `element`, project first.

    `memo` (element id -> the path down to and including that element), shared by the
    elements of one file, stops each walk at the first parent already walked: a building's
    thousands of elements sit in a few storeys (a third of the read's time went to walking
    the same storeys up again). Only walks that reach the top are remembered, so a cycle
    of a damaged file gives every element the path it would get alone."""
    import ifcopenshell.util.element as util

    memo = {} if memo is None else memo
    chain, node, seen, above = [], element, {element.id()}, None
    while True:
        parent = util.get_aggregate(node) or _container(node) or _nest(node)
        if parent is None:
            above = ()
            break
        if parent.id() in memo:
            above = memo[parent.id()]
            break
        if parent.id() in seen:  # a cycle: the path stops there
            break
        seen.add(parent.id())
        chain.append(parent)
        node = parent
    path = () if above is None else above
    for parent in reversed(chain):
        path += (_group(parent),)
        if above is not None:
            memo[parent.id()] = path
    return path


def _container(element):
    """ifcopenshell's get_container (the direct spatial container, else that of the nearest
    element above through aggregation, nesting, filling or voiding), walked iteratively: its
    own recursion never ends on a cycle of a damaged file (found by fuzzing, issue 42)."""
    import ifcopenshell.util.element as util

    node, seen = element, set()
    while node is not None and node.id() not in seen:
        seen.add(node.id())
        direct = util.get_container(node, should_get_direct=True)
        if direct is not None:
            return direct
        node = util.get_parent(node)
    return None


def _nest(element):
    """The element a filling (a window in its opening) belongs to, through its opening."""
    for rel in getattr(element, "FillsVoids", None) or ():
        opening = rel.RelatingOpeningElement
        for v in getattr(opening, "VoidsElements", None) or ():
            return v.RelatingBuildingElement
    return None


def _color(geometry) -> list[float] | None:
    """The diffuse colour of the material most faces use (None: the palette)."""
    materials = list(getattr(geometry, "materials", []) or [])
    if not materials:
        return None
    ids = np.asarray(getattr(geometry, "material_ids", []) or [0], np.int64)
    counts = np.bincount(ids[ids >= 0], minlength=len(materials)) if (ids >= 0).any() else [1]
    m = materials[int(np.argmax(counts))]
    d = m.diffuse
    rgb = [d.r(), d.g(), d.b()] if hasattr(d, "r") else list(d)[:3]
    alpha = 1.0 - float(getattr(m, "transparency", 0.0) or 0.0) if getattr(m, "has_transparency", False) else 1.0
    return [float(c) for c in rgb] + [alpha if np.isfinite(alpha) else 1.0]
