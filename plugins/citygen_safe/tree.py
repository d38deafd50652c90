"""The decomposition tree (dang2014 §3): recursive x/y splits recovered from a facade's leaf shapes.

Our layouts arrive as partitions (a CMP import is one flat list of terminals), so the guillotine cuts are
recovered top-down: a node is split along y at every line no leaf crosses (floors first), else along x; a block
that no single cut separates (a pinwheel of four or more shapes) becomes one ``group`` node whose members are
treated as one leaf by the optimisation (they are scaled together, see docs/safe.md).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from citygen_safe.leaves import EPS, Facade, Leaf

X, Y, GROUP = "x", "y", "group"


@dataclass(frozen=True)
class Node:
    """A facade shape of the tree: a rectangle, its split (``x``, ``y``, ``group`` or None for a leaf) and
    children in split order (left to right, bottom to top). ``leaves`` are the leaf indices below it."""

    x: float
    y: float
    w: float
    h: float
    split: str | None
    children: tuple[Node, ...]
    leaves: tuple[int, ...]

    @property
    def is_leaf(self) -> bool:
        return self.split is None or self.split == GROUP

    def walk(self):
        stack = [self]
        while stack:
            node = stack.pop()
            yield node
            stack.extend(reversed(node.children))


def decompose(facade: Facade) -> Node:
    """The decomposition tree of ``facade`` (y cuts tried before x cuts at every node)."""
    arr = np.array([(f.x, f.y, f.w, f.h) for f in facade.leaves], dtype=float).reshape(-1, 4)
    return _node(arr, np.arange(len(facade.leaves)), facade.leaves)


def _cuts(lo: np.ndarray, hi: np.ndarray) -> list[np.ndarray]:
    """Groups of indices separated by lines that no interval ``[lo, hi]`` crosses, in increasing order."""
    order = np.argsort(lo, kind="stable")
    reach = np.maximum.accumulate(hi[order])
    breaks = np.flatnonzero(lo[order][1:] >= reach[:-1] - EPS) + 1
    return np.split(order, breaks)


def _node(arr: np.ndarray, idx: np.ndarray, leaves: tuple[Leaf, ...]) -> Node:
    sub = arr[idx]
    x0, y0 = float(sub[:, 0].min()), float(sub[:, 1].min())
    x1, y1 = float((sub[:, 0] + sub[:, 2]).max()), float((sub[:, 1] + sub[:, 3]).max())
    if len(idx) == 1:
        return Node(x0, y0, x1 - x0, y1 - y0, None, (), (int(idx[0]),))
    for split, axis in ((Y, 1), (X, 0)):
        groups = _cuts(sub[:, axis], sub[:, axis] + sub[:, axis + 2])
        if len(groups) > 1:
            children = tuple(_node(arr, idx[np.sort(g)], leaves) for g in groups)
            return Node(x0, y0, x1 - x0, y1 - y0, split, children,
                        tuple(i for c in children for i in c.leaves))
    return Node(x0, y0, x1 - x0, y1 - y0, GROUP, (), tuple(int(i) for i in idx))


def common_parent(root: Node, members: set[int]) -> Node:
    """The deepest node whose subtree holds every leaf in ``members``."""
    node = root
    while True:
        inner = [c for c in node.children if members <= set(c.leaves)]
        if not inner:
            return node
        node = inner[0]
