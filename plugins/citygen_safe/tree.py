"""The decomposition tree (dang2014 §3): recursive x/y splits recovered from a facade's leaf shapes.

Our layouts arrive as partitions (a CMP import is one flat list of terminals), so the guillotine cuts are
recovered top-down: a node is split along y at every line no leaf crosses (floors first), else along x; a block
that no single cut separates (a pinwheel of four or more shapes) becomes one ``group`` node whose members are
treated as one leaf by the optimisation (they are scaled together, see docs/safe.md).
"""
from __future__ import annotations

from dataclasses import dataclass

from citygen_safe.leaves import EPS, Facade

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
    boxes = [(f.x, f.y, f.right, f.top) for f in facade.leaves]
    return _node(boxes, list(range(len(boxes))))


def _cuts(boxes: list[tuple[float, float, float, float]], idx: list[int], axis: int) -> list[list[int]]:
    """Groups of ``idx`` separated by lines across ``axis`` that no box crosses, in increasing order (plain
    Python: the nodes are small, numpy's per-call cost dominated)."""
    groups: list[list[int]] = []
    reach = float("-inf")
    for i in sorted(idx, key=lambda i: boxes[i][axis]):
        if not groups or boxes[i][axis] >= reach - EPS:
            groups.append([])
        groups[-1].append(i)
        reach = max(reach, boxes[i][axis + 2])
    return groups


def _node(boxes: list[tuple[float, float, float, float]], idx: list[int]) -> Node:
    x0 = min(boxes[i][0] for i in idx)
    y0 = min(boxes[i][1] for i in idx)
    x1 = max(boxes[i][2] for i in idx)
    y1 = max(boxes[i][3] for i in idx)
    if len(idx) == 1:
        return Node(x0, y0, x1 - x0, y1 - y0, None, (), (idx[0],))
    for split, axis in ((Y, 1), (X, 0)):
        groups = _cuts(boxes, idx, axis)
        if len(groups) > 1:
            children = tuple(_node(boxes, sorted(g)) for g in groups)
            return Node(x0, y0, x1 - x0, y1 - y0, split, children, tuple(i for c in children for i in c.leaves))
    return Node(x0, y0, x1 - x0, y1 - y0, GROUP, (), tuple(idx))


def common_parent(root: Node, members: set[int]) -> Node:
    """The deepest node whose subtree holds every leaf in ``members``."""
    node = root
    while True:
        inner = [c for c in node.children if members <= set(c.leaves)]
        if not inner:
            return node
        node = inner[0]
