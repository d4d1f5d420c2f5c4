"""USD (.usd, .usda, .usdc, .usdz) through usd-core: every Mesh prim is an object, its prim
path the tree; instances are expanded (instance proxies, named after the innermost instance
prim by rtta.scene.readers.usd_names; PointInstancers' instances by
rtta.scene.readers.usd_instancers); the stage's metersPerUnit and upAxis are kept. Every
value is read at one time code, the stage's start time code (else its values' earliest), and
prims are drawn by purpose: `default` and `render`, never `guide`, `proxy` only where no
`render` part is drawn (rtta.scene.readers.usd_stage says why). Layers the file refers to
(sublayers, references, payloads) must lie in its folder: no absolute paths, no URLs. What
the instances expand to is counted per prototype before any is expanded, and bounded as the
other readers' node walks are (rtta.scene.files.max_objects, WALK_PER_OBJECT). A value
usd-core cannot read (a damaged binary layer) is one short line."""

from __future__ import annotations

import codecs
import re
from functools import partial
from pathlib import Path

import numpy as np

from ...errors import RttaError, reason
from ...outputs import signals_held
from ..batch import fans
from ..files import PARTS_HINT, WALK_PER_OBJECT, max_objects
from ..precheck import check_size
from . import Assembly, check_archive, hidden, native_output, unit_name, usd_instancers, usd_names, usd_stage

MAX_LAYERS = 256


class _Unreadable(Exception):
    """An attribute whose value usd-core cannot read (a damaged layer); the message names it."""


def read(path: Path) -> Assembly:
    with signals_held():  # a signal during a native module's initialisation crashes it
        from pxr import Tf, Usd  # pyright: ignore[reportAttributeAccessIssue]  (usd-core's stubs lack Tf)

    if path.suffix.lower() == ".usdz":
        check_archive(path)
    layer_bytes = _check_layers(path)
    with native_output() as said:
        try:
            stage = Usd.Stage.Open(str(path))
        except Exception as exc:  # pxr.Tf.ErrorException and others
            stage, said = None, [*said, _error_text(exc)]
    if stage is None:
        raise RttaError(f"cannot read USD file ({_short(chr(10).join(said))})", path)
    try:
        return _read(stage, path, layer_bytes)
    except _Unreadable as exc:
        raise RttaError(str(exc), path) from None
    except Tf.ErrorException as exc:
        raise RttaError(f"cannot read the USD stage ({_short(_error_text(exc))})", path) from None


def _read(stage, path: Path, layer_bytes: int) -> Assembly:
    """The stage's meshes, its instances' and its PointInstancers' expanded, in world space,
    at the time and of the purposes rtta.scene.readers.usd_stage chooses."""
    from pxr import Usd, UsdGeom

    time = usd_stage.read_time(stage)
    _check_expansion(stage, path, layer_bytes)
    out = Assembly(
        unit=unit_name(float(UsdGeom.GetStageMetersPerUnit(stage))),
        up_axis="z" if UsdGeom.GetStageUpAxis(stage) == UsdGeom.Tokens.z else "y",
    )
    cache = UsdGeom.XformCache(time)
    known: dict = {}  # prototype prim path -> (points, triangles, colour): read once for all its instances
    drawn = usd_stage.Drawn()  # the parts and hiders, until it is known whether proxies are drawn
    ctx = usd_instancers.Context(cache, partial(_mesh_of, known=known, time=time), _get, time, out.warnings, path)
    names = usd_names.Names(ctx.mesh_of, _get, time)
    prims = iter(Usd.PrimRange.Stage(stage, Usd.TraverseInstanceProxies(Usd.PrimDefaultPredicate)))
    for prim in prims:  # not pruned by purpose: a child's own purpose wins over its parent's
        if prim.IsA(UsdGeom.PointInstancer):
            prims.PruneChildren()  # its prototypes are drawn through it (Hydra culls its children)
            if UsdGeom.Imageable(prim).ComputeVisibility(time) != UsdGeom.Tokens.invisible:
                _instanced(prim, ctx, drawn)
            continue
        if not prim.IsA(UsdGeom.Mesh) or UsdGeom.Imageable(prim).ComputeVisibility(time) == UsdGeom.Tokens.invisible:
            continue
        purpose = usd_stage.purpose(prim)
        if purpose == usd_stage.GUIDE:
            continue
        v, f, color = (
            _mesh_of(prim, known, time)
            if prim.IsInstanceProxy()
            else (*_mesh(UsdGeom.Mesh(prim), time), _color(prim, time))
        )
        if not len(f):
            continue
        m = np.array(cache.GetLocalToWorldTransform(prim), np.float64)  # row vectors: p @ M
        if hidden.singular(m.T):
            drawn.hider(_hider(prim, cache), purpose)
            continue
        name, groups = names(prim)
        drawn.add(purpose, name, v @ m[:3, :3] + m[3, :3], f, color, groups)
    drawn.finish(out, path)
    return out


def _instanced(prim, ctx: usd_instancers.Context, drawn: usd_stage.Drawn) -> None:
    """Add the parts of the PointInstancer `prim` but its guides; an instance whose transform
    is singular is noted as a hider (the instancer's topmost singular prim where its own
    transform is)."""
    world = np.array(ctx.cache.GetLocalToWorldTransform(prim), np.float64)
    flat = bool(hidden.singular(world.T))
    for part in usd_instancers.parts(prim, world, ctx):
        if part.purpose == usd_stage.GUIDE:
            continue
        m = part.matrix
        if hidden.singular(m.T):
            drawn.hider(_hider(prim, ctx.cache) if flat else part.instance, part.purpose)
            continue
        v, f, color = part.mesh
        drawn.add(part.purpose, part.name, v @ m[:3, :3] + m[3, :3], f, color, part.groups)


def _mesh_of(prim, known: dict, time) -> tuple:
    """(points, triangles, colour) of a mesh prim at `time`, read once per prim of a prototype."""
    from pxr import UsdGeom

    key = prim.GetPrimInPrototype().GetPath() if prim.IsInstanceProxy() else prim.GetPath()
    if key not in known:
        known[key] = (*_mesh(UsdGeom.Mesh(prim), time), _color(prim, time))
    return known[key]


def _get(attr, time):
    """The attribute's value at the Usd.TimeCode `time`; _Unreadable, naming it, where
    usd-core cannot read it (pxr.Tf.ErrorException, whose text holds C++ places)."""
    from pxr import Tf  # pyright: ignore[reportAttributeAccessIssue]  (as in read)

    try:
        return attr.Get(time)
    except Tf.ErrorException as exc:
        raise _Unreadable(f"cannot read the value of {attr.GetPath()} ({_short(_error_text(exc))})") from None


def _hider(prim, cache) -> str:
    """The path of the topmost prim above (or at) `prim` whose own transform is singular (a
    zero scale); `prim`'s where only their product is."""
    found, current = prim, prim
    while current and not current.IsPseudoRoot():
        local, _ = cache.GetLocalTransformation(current)
        if hidden.singular(np.array(local, np.float64).T):
            found = current
        current = current.GetParent()
    return found.GetPath().pathString


_TF_ERROR = re.compile(r"\s*Error in '[^']*' at line \d+ in file .*? : '")
_NAMESPACE = re.compile(r"pxrInternal_v[0-9_]*?__pxrReserved__(?:::)?")
_PLACE = re.compile(r"^.*?\.usd[acz]?:(\d+):(\d+):\s*", re.IGNORECASE)


def _error_text(exc: Exception) -> str:
    """str(exc), or the exception's type where usd-core's message holds bytes that are not
    UTF-8 (its __str__ then raises)."""
    try:
        return str(exc)
    except Exception:
        return reason(exc)


def _short(text: str) -> str:
    """usd-core's error text made one short line: its first message that is a cause (not
    'Failed to open layer'), without the C++ function, source file and namespaces, the
    layer's path turned into 'line L, column C' (the error line names the file already)."""
    text = str(text)
    messages = [m.strip().rstrip("'").strip() for m in _TF_ERROR.split(text)[1:]]
    first = next((line.strip() for line in text.splitlines() if line.strip()), "not a USD stage")
    messages = [m for m in messages if m] or [first]
    cause = next((m for m in messages if not m.startswith("Failed to open layer")), messages[0])
    cause = re.sub(r"parse error matching .*? at '", "syntax error at '", cause)  # pegtl's grammar rule: noise
    cause = _PLACE.sub(lambda m: f"line {m.group(1)}, column {m.group(2)}: ", _NAMESPACE.sub("", cause), count=1)
    return re.sub(r"\s+", " ", cause).strip()[:160]


def _check_layers(path: Path) -> int:
    """Refuse layer references that leave the file's folder (checked before the stage composes).
    Returns the bytes of the layers `path` refers to."""
    from pxr import Sdf

    folder = path.resolve().parent
    todo, seen = [path.resolve()], set()
    while todo and len(seen) < MAX_LAYERS:
        current = todo.pop()
        if current in seen or current.suffix.lower() == ".usdz":
            continue
        seen.add(current)
        _check_text(current, path)
        with native_output() as said:
            try:
                layer = Sdf.Layer.FindOrOpen(str(current))
            except Exception as exc:
                layer, said = None, [*said, _error_text(exc)]
        if layer is None:
            if current == path.resolve():
                raise RttaError(f"cannot read USD file ({_short(chr(10).join(said) or 'not a USD layer')})", path)
            raise RttaError(f"layer '{current.name}' it refers to cannot be read", path)
        for asset in layer.GetCompositionAssetDependencies():
            if not asset:  # an internal reference: this layer itself
                continue
            if re.match(r"^[a-zA-Z][a-zA-Z0-9+.-]*:", asset):
                raise RttaError(f"layer reference '{asset}' is a URL; only files next to the scene are read", path)
            target = (current.parent / asset).resolve()
            if Path(asset).is_absolute() or folder not in target.parents:
                raise RttaError(f"layer reference '{asset}' is outside the scene's folder", path)
            if not target.is_file():
                raise RttaError(f"layer reference '{asset}' is missing", path)
            todo.append(target)
    return sum(p.stat().st_size for p in seen - {path.resolve()})


def _check_text(layer: Path, path: Path) -> None:
    """A text layer (#usda) must be UTF-8: usd-core's Python side fails on other bytes with
    a decoding error that names neither the file nor the place. Read in chunks, so a large
    layer is not held twice."""
    decoder = codecs.getincrementaldecoder("utf-8")()
    lines, first = 1, True
    try:
        with open(layer, "rb") as fh:
            while chunk := fh.read(1 << 20):
                if first and not chunk.startswith(b"#usda"):
                    return  # binary (usdc) or not USD: the reader says
                first = False
                pending = len(decoder.getstate()[0])  # bytes of a character cut by the last chunk
                try:
                    decoder.decode(chunk)
                except UnicodeDecodeError as exc:
                    line = lines + chunk.count(b"\n", 0, max(0, exc.start - pending))
                    raise RttaError(
                        f"{_which(layer, path)}not UTF-8 text at line {line} (USDA layers are UTF-8)", path
                    ) from None
                lines += chunk.count(b"\n")
            decoder.decode(b"", final=True)
    except UnicodeDecodeError:
        raise RttaError(f"{_which(layer, path)}not UTF-8 text: it ends inside a character", path) from None
    except OSError:
        return  # unreadable: Sdf says so


def _which(layer: Path, path: Path) -> str:
    return "" if layer == path.resolve() else f"layer '{layer.name}' it refers to is "


def _check_expansion(stage, path: Path, layer_bytes: int) -> None:
    """Refuse a stage whose traversal through its instances would visit more prims, or make
    more parts, vertices or triangles, than a file of its size may (prototypes that instance
    prototypes: ten levels of ten instances each are 10^10 parts in 18 KB). Counted once per
    prototype, innermost first, before any instance is expanded, at the time the stage is
    read at. Prims of every purpose are counted (guides and proxies too): an upper bound on
    what is drawn."""
    objects = max_objects(path, layer_bytes)
    parts, prims, vertices, triangles = _expansion(stage, path)
    if parts > objects or prims > objects * WALK_PER_OBJECT:
        raise RttaError(
            f"the USD stage, its instances expanded, makes {parts:,} parts in {prims:,} prims, over the "
            f"{objects:,} parts or {objects * WALK_PER_OBJECT:,} prims a file of its size may make ({PARTS_HINT})",
            path,
        )
    check_size(vertices, triangles, path, "the USD stage, its instances expanded, has")


def _expansion(stage, path: Path) -> tuple[int, ...]:
    """(parts, prims, vertices, triangles) that reading `stage` through its instance proxies
    meets: each prototype's own, plus its instances' prototypes' times their number."""
    own: dict = {}  # prototype path (or '/') -> (its own counts, {prototype path: instances in it})
    total: dict = {}  # prototype path -> its counts, its instances' included
    stack = [stage.GetPseudoRoot()]
    while stack:
        key = stack[-1].GetPath()
        if key in total:
            stack.pop()
            continue
        if key not in own:
            own[key] = _own_counts(stack[-1])
        counts, inside = own[key]
        waiting = [p for p in inside if p not in total]
        if any(p in own for p in waiting):  # scanned, not summed: a prototype below itself
            raise RttaError("the USD stage's instances hold themselves (a cycle)", path)
        if waiting:
            stack += [stage.GetPrimAtPath(p) for p in waiting]
            continue
        stack.pop()
        total[key] = tuple(c + sum(n * total[p][i] for p, n in inside.items()) for i, c in enumerate(counts))
    return total[stage.GetPseudoRoot().GetPath()]


def _own_counts(root) -> tuple[tuple[int, ...], dict]:
    """`root`'s (parts, prims, vertices, triangles) below it, without entering its instances,
    and how many instances of each prototype it holds: native ones, and a PointInstancer's
    (each instance one prim more; its children are its prototypes, drawn only through it).
    The stage's pseudo-root and a native prototype's root are not counted (traversal meets an
    instance prim, never its prototype's root); a PointInstancer's prototype's root is.
    Values are read at the time the stage is drawn at (usd_stage.read_time, a function of the
    stage alone); every purpose is counted."""
    from pxr import Usd, UsdGeom

    time = usd_stage.read_time(root.GetStage())
    top = root.IsPseudoRoot() or root.IsPrototype()
    parts = prims = vertices = triangles = 0
    inside: dict = {}
    walk = iter(Usd.PrimRange(root) if top else usd_instancers.prototype_range(root, through_instances=False))
    for prim in walk:  # the default predicate: instances are not entered
        prims += 1
        if prim.IsInstance():
            key = prim.GetPrototype().GetPath()
            inside[key] = inside.get(key, 0) + 1
        if prim.IsA(UsdGeom.PointInstancer):
            walk.PruneChildren()
            count, each = usd_instancers.instance_counts(prim, _get, time)
            prims += count
            for key, n in each.items():
                inside[key] = inside.get(key, 0) + n
        elif prim.IsA(UsdGeom.Mesh):
            mesh = UsdGeom.Mesh(prim)
            points, counts, index = (
                _get(a, time)
                for a in (mesh.GetPointsAttr(), mesh.GetFaceVertexCountsAttr(), mesh.GetFaceVertexIndicesAttr())
            )
            parts += 1
            vertices += len(points or ())
            triangles += max(len(index or ()) - 2 * len(counts or ()), 0)
    return (parts, prims - int(top), vertices, triangles), inside


def _mesh(mesh, time) -> tuple[np.ndarray, np.ndarray]:
    """Points and polygons fan-triangulated (USD faces are convex polygons), at `time`."""
    points = _get(mesh.GetPointsAttr(), time)
    counts = _get(mesh.GetFaceVertexCountsAttr(), time)
    index = _get(mesh.GetFaceVertexIndicesAttr(), time)
    if points is None or counts is None or index is None or not len(points):
        return np.zeros((0, 3)), np.zeros((0, 3), np.int64)
    v = np.asarray(points, np.float64).reshape(-1, 3)
    counts = np.asarray(counts, np.int64)
    index = np.asarray(index, np.int64)
    if counts.sum() != len(index) or (counts < 3).any():
        keep = counts >= 3
        starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
        if counts.sum() != len(index):
            return v, np.zeros((0, 3), np.int64)
        counts, starts = counts[keep], starts[keep]
    else:
        starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    return v, index[fans(starts, counts)[1]]


def _color(prim, time) -> list[float] | None:
    from pxr import UsdGeom

    value = _get(UsdGeom.PrimvarsAPI(prim).GetPrimvar("displayColor").GetAttr(), time) if prim else None
    if value is None or not len(value):
        return None
    c = [float(x) for x in value[0]][:3]
    return [*c, 1.0] if np.isfinite(c).all() else None
