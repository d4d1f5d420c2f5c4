"""glTF's node graph: every node's local transform (matrix, or translation, rotation and
scale) in whole-array passes, and the walk of a scene's graph (iterative, each path once)
that gives every node with a mesh its world transform, name and ancestors; cycles, graphs
deeper than MAX_DEPTH and graphs of too many paths are errors found before any path is
followed."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...errors import RttaError
from ..files import MAX_OBJECTS_LARGE, PARTS_HINT, WALK_PER_OBJECT
from . import hidden

MAX_DEPTH = 1000  # levels of the node graph


def local_transforms(nodes: list) -> np.ndarray:
    """Every node's local transform [N, 4, 4] (matrix, or T @ R @ S), in whole-array passes."""
    m = np.zeros((len(nodes), 4, 4))
    m[:, [0, 1, 2, 3], [0, 1, 2, 3]] = 1.0
    given = [(i, node["matrix"]) for i, node in enumerate(nodes) if "matrix" in node]
    scaled = [(i, node["scale"]) for i, node in enumerate(nodes) if "scale" in node]
    turned = [(i, node["rotation"]) for i, node in enumerate(nodes) if "rotation" in node]
    moved = [(i, node["translation"]) for i, node in enumerate(nodes) if "translation" in node]
    if scaled:
        rows, values = zip(*scaled, strict=True)
        m[np.array(rows), :3, :3] *= np.array(values, np.float64)[:, None, :]
    if turned:
        rows, values = zip(*turned, strict=True)
        rows = np.array(rows)
        m[rows, :3, :3] = _rotations(np.array(values, np.float64)) @ m[rows, :3, :3]
    if moved:
        rows, values = zip(*moved, strict=True)
        m[np.array(rows), :3, 3] = np.array(values, np.float64)
    if given:
        rows, values = zip(*given, strict=True)
        m[np.array(rows)] = np.array(values, np.float64).reshape(-1, 4, 4).transpose(0, 2, 1)
    return m


def _rotations(q: np.ndarray) -> np.ndarray:
    """Rotation matrices [N, 3, 3] of quaternions (x, y, z, w), normalised; zero ones are identity."""
    n = np.sqrt((q * q).sum(axis=1, keepdims=True))
    with np.errstate(all="ignore"):
        q = np.where(n > 0, q / np.where(n > 0, n, 1.0), [0.0, 0.0, 0.0, 1.0])
    x, y, z, w = q.T
    return np.stack(
        [
            1 - 2 * (y * y + z * z),
            2 * (x * y - z * w),
            2 * (x * z + y * w),
            2 * (x * y + z * w),
            1 - 2 * (x * x + z * z),
            2 * (y * z - x * w),
            2 * (x * z - y * w),
            2 * (y * z + x * w),
            1 - 2 * (x * x + y * y),
        ],
        axis=1,
    ).reshape(-1, 3, 3)


def walk(doc: dict, path: Path, warnings: list[str], limit: int) -> list[tuple[str, int, np.ndarray, tuple]]:
    """(name, mesh, world matrix, ancestors' names) of every node with a mesh, in depth-first
    file order, each path through the graph once. Cycles, graphs deeper than MAX_DEPTH and
    graphs whose paths make more objects than files.max_objects allows are errors (found in
    one pass over the nodes, before any path is followed); a node with several parents is
    drawn under each, with a warning. A node whose transform is singular (a zero scale:
    glTF's way to hide a node) draws nothing, nor does anything below it: one warning names
    those nodes (rtta.scene.readers.hidden)."""
    nodes, scenes = doc.get("nodes", []), doc.get("scenes", [])
    parents = [0] * len(nodes)
    for node in nodes:
        for child in node.get("children", []):
            parents[child] += 1
    roots = scenes[doc.get("scene", 0)].get("nodes", []) if scenes else [i for i, p in enumerate(parents) if p == 0]
    meshes = _measure(nodes, roots, path, limit)
    shared = [i for i, p in enumerate(parents) if p > 1]
    if shared:
        warnings.append(
            f"{len(shared)} node(s) have more than one parent (glTF allows one); each is drawn "
            "under every parent: " + ", ".join(_node_name(nodes, i) for i in shared[:5])
        )
    found: list[tuple[str, int, np.ndarray, tuple]] = []
    local = local_transforms(nodes)
    flat = hidden.singular(local)
    hiders: dict[str, None] = {}  # nodes whose singular transform hid a mesh, in file order
    stack: list[tuple[int, np.ndarray | None, tuple, str | None]] = [(r, None, (), None) for r in reversed(roots)]
    while stack:
        i, parent, tree, hider = stack.pop()
        node = nodes[i]
        world = local[i] if parent is None else parent @ local[i]
        name = _node_name(nodes, i)
        hider = hider or (name if flat[i] else None)
        if "mesh" in node:
            if hider is None:
                found.append((name, node["mesh"], world, tree))
            else:
                hiders[hider] = None
        below = (*tree, name.replace("/", "\u2215"))
        # a subtree without a mesh is not walked: its paths can be 2^levels (found by fuzzing, issue 42)
        stack.extend((c, world, below, hider) for c in reversed(node.get("children", [])) if meshes[c])
    if found:  # products of regular transforms that flatten to float64's precision
        squashed = hidden.singular(np.array([f[2] for f in found]))
        hiders.update((f[0], None) for f, s in zip(found, squashed, strict=True) if s)
        found = [f for f, s in zip(found, squashed, strict=True) if not s]
    hidden.note_hidden(list(hiders), len(found), path, warnings)
    return found


def _measure(nodes: list, roots: list[int], path: Path, limit: int) -> list[int]:
    """Cycle, depth and path-count checks over the nodes reachable from `roots`, iteratively
    (each node once: a graph of shared children is not unfolded to count its paths). Returns
    per node the mesh nodes on all paths below and including it (capped): the walk skips the
    subtrees of none. The paths the walk follows (to a mesh, through any node) are bounded too,
    at WALK_PER_OBJECT per object the file may make."""
    state = [0] * len(nodes)  # 0 new, 1 on the current path, 2 done
    depth = [0] * len(nodes)  # levels below and including the node
    meshes = [0] * len(nodes)  # mesh nodes on all paths below and including it
    walked = [0] * len(nodes)  # paths the walk follows from the node (itself included), 0 without a mesh below
    cap = WALK_PER_OBJECT * limit + 1
    for root in roots:
        stack = [root]
        while stack:
            i = stack[-1]
            if state[i] == 2:
                stack.pop()
                continue
            children = nodes[i].get("children", [])
            if state[i] == 1:
                depth[i] = 1 + max((depth[c] for c in children), default=0)
                meshes[i] = min(int("mesh" in nodes[i]) + sum(meshes[c] for c in children), 10 * MAX_OBJECTS_LARGE)
                walked[i] = min(1 + sum(walked[c] for c in children), cap) if meshes[i] else 0
                state[i] = 2
                stack.pop()
                continue
            state[i] = 1
            for c in children:
                if state[c] == 1:
                    raise RttaError(
                        f"glTF node graph has a cycle: node {c} ('{_node_name(nodes, c)}') is its own ancestor", path
                    )
                if state[c] == 0:
                    stack.append(c)
    if max((depth[r] for r in roots), default=0) > MAX_DEPTH:
        raise RttaError(f"glTF node graph is deeper than {MAX_DEPTH} levels", path)
    total = sum(meshes[r] for r in roots)
    if total > limit:
        raise RttaError(
            f"glTF node graph has {total:,} or more node paths to meshes (at most {limit:,} objects "
            f"for a file of its size; {PARTS_HINT})",
            path,
        )
    steps = sum(walked[r] for r in roots)
    if steps > WALK_PER_OBJECT * limit:
        raise RttaError(
            f"glTF node graph has {steps:,} or more node paths to walk to its meshes (at most "
            f"{WALK_PER_OBJECT * limit:,} for a file of its size; {PARTS_HINT})",
            path,
        )
    return meshes


def _node_name(nodes: list, i: int) -> str:
    name = nodes[i].get("name")
    return name if isinstance(name, str) and name else str(i)
