"""3DXML (Dassault: CATIA, SolidWorks) through trimesh, with the sub-assembly tree trimesh
flattens into its node names ('part#id:id:...', the ids of the path from the root product
to the geometry) recovered from the file's product structure: the groups are the names of
the products (Reference3D) along that path. 3DXML stores millimetres, Z up."""

from __future__ import annotations

import zipfile
from pathlib import Path

import numpy as np
from lxml import etree

from ...errors import RttaError, reason
from ..files import PARTS_HINT, max_objects
from ..precheck import ZIP_ERRORS
from . import Assembly, check_archive, hidden
from .trimesh_io import as_scene


def read(path: Path) -> Assembly:
    import trimesh

    check_archive(path)
    products = _products(path)
    try:
        loaded = trimesh.load(str(path), file_type="3dxml", force="scene", process=False)
    except Exception as exc:  # trimesh raises many types for corrupt files
        raise RttaError(f"cannot read 3DXML file ({reason(exc)})", path) from None
    loaded = as_scene(loaded, path)
    out = Assembly(unit="mm", up_axis="z")
    graph = loaded.graph
    hiders: dict[str, None] = {}  # parts placed by a singular transform (trimesh keeps no other nodes)
    for node in graph.nodes_geometry:
        transform, geom = graph[node]
        mesh = loaded.geometry.get(geom)
        if not isinstance(mesh, trimesh.Trimesh) or not len(mesh.faces):
            continue
        name, _, ids = str(node).partition("#")
        chain = ids.split(":") if ids else []
        groups = tuple(products[i] for i in chain[:-3] if i in products)
        m = np.asarray(transform, np.float64)
        if hidden.singular(m):
            hiders[name or str(geom)] = None
            continue
        v = np.asarray(mesh.vertices, np.float64) @ m[:3, :3].T + m[:3, 3]
        out.add(name or str(geom), v, mesh.faces, _color(mesh), groups)
    hidden.note_hidden(list(hiders), len(out.names), path, out.warnings)
    return out


def _products(path: Path) -> dict[str, str]:
    """Reference3D id -> name, from the product structure the manifest names."""
    try:
        with zipfile.ZipFile(path) as z:
            root = etree.fromstring(z.read("Manifest.xml"), etree.XMLParser(resolve_entities=False, no_network=True))
            main = root.find("{*}Root")
            if main is None or not main.text:
                raise KeyError("the manifest names no Root")
            doc = etree.fromstring(
                z.read(main.text.strip()), etree.XMLParser(resolve_entities=False, no_network=True, huge_tree=True)
            )
    except (KeyError, AttributeError, etree.XMLSyntaxError, *ZIP_ERRORS) as exc:  # a damaged member too
        raise RttaError(f"cannot read 3DXML file (no readable product structure: {str(exc)[:120]})", path) from None
    _check_paths(doc, path)
    return {r.get("id", ""): r.get("name") or r.get("id", "") for r in doc.iter("{*}Reference3D")}


def _check_paths(doc, path: Path) -> None:
    """The product structure is a graph (a Reference3D instanced by several): trimesh places
    one part per path from the root to a representation, all of them listed (2^40 from 40
    references each holding the next twice). Counted here first, per reference once: more
    parts than a file of this size may make, or a cycle, is an error."""
    structure = doc.find("{*}ProductStructure")
    root = structure.get("root") if structure is not None else None
    children: dict[str, list[str]] = {}
    for inst in [*doc.iter("{*}Instance3D"), *doc.iter("{*}InstanceRep")]:
        parent, child = inst.findtext("{*}IsAggregatedBy"), inst.findtext("{*}IsInstanceOf")
        if parent and child:
            children.setdefault(parent.strip(), []).append(child.strip())
    reps = {r.get("id", "") for r in doc.iter("{*}ReferenceRep")}
    limit, paths, open_ = max_objects(path), {}, set()
    stack: list[tuple[str | None, bool]] = [(root, False)]
    while stack:  # depth first without recursion; (node, True): its children are counted
        node, counted = stack.pop()
        if counted:
            open_.discard(node)
            paths[node] = min(limit + 1, (node in reps) + sum(paths[c] for c in children.get(node or "", [])))
        elif node in open_:  # reached again below itself
            raise RttaError("3DXML product structure has a cycle (a reference that holds itself)", path)
        elif node not in paths:
            open_.add(node)
            stack += [(node, True)] + [(c, False) for c in children.get(node or "", [])]
    if paths.get(root, 0) > limit:
        raise RttaError(
            f"3DXML product structure places over {limit:,} parts (references instanced many times over; {PARTS_HINT})",
            path,
        )


def _color(mesh) -> list[float] | None:
    visual = mesh.visual
    if getattr(visual, "kind", None) != "face":
        return None
    c = np.asarray(visual.main_color, np.float64).reshape(-1)[:4] / 255.0
    return [*c[:3], c[3] if c.size > 3 else 1.0]
