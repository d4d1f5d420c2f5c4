"""The part tree the object panel shows: groups and objects in the file's order, which
groups are open, the name filter, and the rows that are visible now.

Plain numpy, no imgui (tested directly). Nodes are in depth-first pre-order, so a group's
subtree is the slice [node, end[node]) and its objects are `order[first[node]:last[node]]`;
counts over a subtree (highlighted, hidden) are differences of cumulative sums, so a frame
costs O(visible rows) however many objects the scene has.
"""

from __future__ import annotations

import numpy as np

OPEN_ROWS = 100  # a tree opens level by level while it shows at most this many rows


class PartTree:
    def __init__(self, names: list[str], paths: list[tuple[str, ...]] | None) -> None:
        self.names = names
        labels, depth, obj, end = [], [], [], []
        order: list[int] = []
        stack: list[tuple[tuple[str, ...], int]] = []  # open groups: (path, node)
        groups_of = [tuple(p) for p in paths] if paths is not None else [()] * len(names)
        by_path: dict[tuple[str, ...], list[int]] = {}
        for oid, path in enumerate(groups_of):
            by_path.setdefault(path, []).append(oid)
        children: dict[tuple[str, ...], list[tuple[str, ...]]] = {}
        for path in by_path:
            for k in range(len(path)):
                kids = children.setdefault(path[:k], [])
                if path[: k + 1] not in kids:
                    kids.append(path[: k + 1])

        def visit(path: tuple[str, ...]) -> None:
            if path:
                stack.append((path, len(labels)))
                labels.append(path[-1])
                depth.append(len(path) - 1)
                obj.append(-1)
                end.append(0)
            for oid in by_path.get(path, []):
                labels.append(names[oid])
                depth.append(len(path))
                obj.append(oid)
                end.append(len(labels))
                order.append(oid)
            for kid in children.get(path, []):
                visit(kid)
            if path:
                _, node = stack.pop()
                end[node] = len(labels)

        visit(())
        self.labels = labels
        self.depth = np.asarray(depth, np.int32)
        self.obj = np.asarray(obj, np.int64)
        self.end = np.asarray(end, np.int64)
        self.order = np.asarray(order, np.int64)
        is_obj = self.obj >= 0
        counts = np.concatenate([[0], np.cumsum(is_obj)])
        self.first, self.last = counts[:-1], counts[self.end]
        self.row_of = np.full(len(names), -1, np.int64)
        self.row_of[self.obj[is_obj]] = np.flatnonzero(is_obj)
        self.parent = np.full(len(labels), -1, np.int64)
        for node in np.flatnonzero(~is_obj)[::-1]:  # innermost groups first
            kids = np.arange(node + 1, int(self.end[node]))
            self.parent[kids[self.parent[kids] < 0]] = node
        self._rows_key: tuple | None = None
        self._rows = np.zeros(0, np.int64)
        self.open: set[int] = set()
        # where the panel drew the rows on screen, its toolbar's buttons and the opacity sliders
        # (x0, y0, x1, y1) by node or label, for the tests to click (viewer/tree.py fills them)
        self.rects: dict[int, tuple[float, ...]] = {}
        self.sliders: dict[int, tuple[float, ...]] = {}
        self.buttons: dict[str, tuple[float, ...]] = {}
        self.open_levels()

    def open_levels(self, rows: int = OPEN_ROWS) -> None:
        """Open the groups level by level from the top while at most `rows` rows show."""
        groups = np.flatnonzero(self.obj < 0)
        for d in range(int(self.depth[groups].max()) + 1 if groups.size else 0):
            before = set(self.open)
            self.open |= {int(n) for n in groups[self.depth[groups] == d]}
            if d > 0 and len(self.rows()) > rows:
                self.open = before
                break

    @property
    def has_groups(self) -> bool:
        return bool((self.obj < 0).any())

    def members(self, node: int) -> np.ndarray:
        """Object ids below a node (the object itself for an object row)."""
        return self.order[self.first[node] : self.last[node]]

    def counts(self, ids: set[int]) -> np.ndarray:
        """Per node, how many of its objects are in `ids` (cumulative sums over the order)."""
        mask = np.zeros(len(self.names), bool)
        if ids:
            mask[[i for i in ids if 0 <= i < len(self.names)]] = True
        cs = np.concatenate([[0], np.cumsum(mask[self.order])])
        return cs[self.last] - cs[self.first]

    def matches(self, text: str) -> np.ndarray | None:
        """bool per node: the node is an object whose name contains `text`, or a group with one."""
        f = text.strip().lower()
        if not f:
            return None
        hit = np.array([f in n.lower() for n in self.names], bool)
        cs = np.concatenate([[0], np.cumsum(hit[self.order])])
        return (cs[self.last] - cs[self.first]) > 0

    def rows(self, text: str = "") -> np.ndarray:
        """Nodes shown now: closed groups hide their subtrees; a filter shows the matching
        objects and the groups above them, open."""
        key = (text.strip().lower(), frozenset(self.open))
        if key == self._rows_key:
            return self._rows
        match = self.matches(text)
        out, node, n = [], 0, len(self.labels)
        while node < n:
            if match is not None and not match[node]:
                node = int(self.end[node]) if self.obj[node] < 0 else node + 1
                continue
            out.append(node)
            closed = self.obj[node] < 0 and node not in self.open and match is None
            node = int(self.end[node]) if closed else node + 1
        self._rows_key, self._rows = key, np.asarray(out, np.int64)
        return self._rows

    def reveal(self, oid: int) -> int:
        """Open every group above object `oid`; its node."""
        node = int(self.row_of[oid])
        p = int(self.parent[node])
        while p >= 0:
            self.open.add(p)
            p = int(self.parent[p])
        return node
