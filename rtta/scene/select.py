"""Objects by name: an object's name, a group of the part tree ('engine/head', or its last
part 'head'; every group of that name), a class of labelled objects ('IfcWall' for
"IfcWall 'name'"), or a glob over names and paths ('head/*', 'IfcWindow*').

One function, `resolve_names`, for the command line and the library alike: an unknown name
is an error that lists close matches.
"""

from __future__ import annotations

import difflib
import fnmatch
from pathlib import Path

from ..errors import RttaError
from .model import Scene

GLOB = set("*?[")
MAX_PATTERN = 1024  # characters of a glob: fnmatch compiles '[' runs in quadratic time (3,200 took 1.2 s)


def full_names(scene: Scene) -> list[str]:
    """'group/.../name' per object (its name alone in a flat file)."""
    return ["/".join((*scene.path_of(i), n)) for i, n in enumerate(scene.names)]


def resolve_names(scene: Scene, names: list[str], flag: str, groups: bool = True) -> list[int]:
    """Object ids for names, groups and globs, each id once, in the order given (a group's in
    tree order); an unknown name is an RttaError naming `flag` and listing close matches.
    With groups=False only exact object names are accepted (one id per name)."""
    ids: list[int] = []
    for name in names:
        found = _lookup(scene, name) if groups else ([scene.index(name)] if name in scene.names else [])
        if not found:
            raise RttaError(f"{flag}: {_unknown(scene, name, groups)}")
        ids.extend(found)
    return list(dict.fromkeys(ids))


def _lookup(scene: Scene, name: str) -> list[int]:
    if name in scene.names:
        return [scene.index(name)]
    tree = scene.groups
    if name in tree:
        return list(tree[name])
    short = [g for g in tree if g.rsplit("/", 1)[-1] == name]
    if short:
        return [i for g in short for i in tree[g]]
    kind = [i for i, n in enumerate(scene.names) if n.startswith((f"{name} '", f"{name} #"))]
    if kind:  # a class of labelled objects: 'IfcWall' -> IfcWall 'a', ...
        return kind
    if not GLOB & set(name) or len(name) > MAX_PATTERN:  # a longer one: found by fuzzing (issue 42)
        return []
    hits = [i for i in range(scene.count) if any(fnmatch.fnmatchcase(t, name) for t in _tails(scene, i))]
    return hits


def _tails(scene: Scene, oid: int) -> list[str]:
    """The object's name and its tree path from every group down: 'Storey 2/*' matches the
    objects below any group named 'Storey 2', wherever it sits."""
    parts = (*scene.path_of(oid), scene.names[oid])
    return ["/".join(parts[k:]) for k in range(len(parts))]


def _unknown(scene: Scene, name: str, groups: bool) -> str:
    what = "object or group" if groups and scene.paths is not None else "object"
    pool = scene.names + ([g.rsplit("/", 1)[-1] for g in scene.groups] if groups else [])
    close = (
        difflib.get_close_matches(name, list(dict.fromkeys(pool)), n=4, cutoff=0.5) if len(name) <= MAX_PATTERN else []
    )
    hint = f"; did you mean {', '.join(close)}?" if close else "; `rtta info --tree` lists the objects and groups"
    shown = name if len(name) <= 200 else f"{name[:200]}... ({len(name):,} characters)"
    return f"no {what} named '{shown}' in {Path(scene.source).name}{hint}"
