"""What a dataset says about each object of a scene: its name, its path in the part tree and
its category (`--category-by name|group|ifc-class`)."""

from __future__ import annotations

import re

from ..errors import RttaError
from ..scene.model import Scene

CATEGORY_BY = ("name", "group", "ifc-class")
_IFC = re.compile(r"^(Ifc[A-Za-z0-9]+)\b")
_NUMBERED = re.compile(r"[\s_.#:-]*\d+$")


def object_paths(scene: Scene) -> list[str]:
    """Each object's path in the file's part tree where the scene keeps one (`Scene.paths`),
    else its name (the flat scenes of today's loader)."""
    paths = getattr(scene, "paths", None)
    if paths is not None and len(paths) == scene.count:
        return [str(p) for p in paths]
    return list(scene.names)


def group_of(path: str, name: str) -> str:
    """The object's group: the parent of its path in the part tree, or, in a flat scene, its
    name without a trailing number (`bolt_3`, `bolt.004` and `bolt 12` are all `bolt`)."""
    if "/" in path.strip("/"):
        return path.strip("/").rsplit("/", 1)[0]
    return _NUMBERED.sub("", name) or name


def ifc_class(name: str) -> str | None:
    """`IfcWall` of an object named `IfcWall 'Wall-01'` (the BIM loaders' names), else None."""
    m = _IFC.match(name)
    return m.group(1) if m else None


def object_meta(scene: Scene, category_by: str = "name") -> list[dict]:
    """Per object id: {"name", "path", "category"}. With ifc-class, objects without a class
    are "unclassified"; a scene where no object has one is an error."""
    if category_by not in CATEGORY_BY:
        raise RttaError(f"--category-by must be one of {', '.join(CATEGORY_BY)}, got '{category_by}'")
    paths = object_paths(scene)
    if category_by == "name":
        cats = list(scene.names)
    elif category_by == "group":
        cats = [group_of(p, n) for p, n in zip(paths, scene.names, strict=True)]
    else:
        classes = [ifc_class(n) for n in scene.names]
        if not any(classes):
            raise RttaError("--category-by ifc-class: no object is named by an IFC class (IfcWall ...)", scene.source)
        cats = [c or "unclassified" for c in classes]
    return [{"name": n, "path": p, "category": c} for n, p, c in zip(scene.names, paths, cats, strict=True)]
