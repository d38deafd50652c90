"""Least plausible leaf extents (the QP's lower bounds) and the collapse of wall slabs squeezed to nothing.

The paper bounds every size by ``x > 0``; a squeezed facade then shows shop fronts 0.2 m tall and wall rows
0 m high. Here each leaf's lower bound along the problem's axis comes from :class:`citygen.plausible
.PlausibilityRules`: an opening's ``min_size`` (a door's ``door_min_height``), a thin element's ``min_extent``,
any other labelled element's ``sliver``. A wall may vanish instead: a wall whose *slab* (its ancestor-or-self
that is a child of a cut across this axis, the piece the cut makes) holds only walls is bounded by 1 mm only,
and :func:`collapse` removes such slabs thinner than ``sliver`` after the solve (their extent goes to the
neighbouring slab), so no zero-size row or column and no wall sliver is produced; a wall sharing its slab with
other elements keeps ``sliver``.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import numpy as np

from citygen.plausible import DEFAULT_RULES, PlausibilityRules
from citygen_safe.leaves import EPS, Facade, Leaf
from citygen_safe.tree import GROUP, X, Node

COLLAPSIBLE = frozenset({"wall", None})  #: labels whose slabs may vanish
MIN_SIZE = 1e-3  #: the bound standing for x > 0 (metres)
MARGIN = 1e-4  #: kept above each rule's threshold, so rounding never trips it


def minimum_extents(facade: Facade, root: Node, rules: PlausibilityRules = DEFAULT_RULES) -> np.ndarray:
    """Each leaf's least extent along the problem's axis (widths; heights when ``facade`` is transposed)."""
    axis = 1 if facade.transposed else 0
    mins = np.empty(len(facade.leaves))
    for i, f in enumerate(facade.leaves):
        label = f.label
        if label in rules.min_size:
            m = rules.min_size[label][axis]
            if label == "door" and axis == 1:
                m = max(m, rules.door_min_height)
        elif label in rules.thin_labels:
            m = rules.min_extent
        else:
            m = rules.sliver
        mins[i] = m + MARGIN
    for i in _collapsible(root, facade):
        mins[i] = MIN_SIZE
    return mins


def _collapsible(root: Node, facade: Facade) -> list[int]:
    """Leaves in slabs (children of ``x`` splits) that hold only collapsible labels."""
    out: list[int] = []

    def visit(node: Node) -> None:
        for child in node.children:
            if node.split == X and all(facade.leaves[i].label in COLLAPSIBLE for i in child.leaves):
                out.extend(child.leaves)
            elif child.split is not None and child.split != GROUP:
                visit(child)

    visit(root)
    return out


def node_minimum(root: Node, facade: Facade, mins: np.ndarray) -> dict[int, float]:
    """The least extent of every node (by id): a cut along the axis adds its children's, a transverse one takes
    the largest, a group (scaled as a whole) the scale its tightest member needs."""
    out: dict[int, float] = {}

    def visit(node: Node) -> float:
        if node.split is None:
            m = float(mins[node.leaves[0]])
        elif node.split == GROUP:
            m = node.w * max(float(mins[i]) / max(facade.leaves[i].w, EPS) for i in node.leaves)
        else:
            ms = [visit(c) for c in node.children]
            m = sum(ms) if node.split == X else max(ms)
        out[id(node)] = m
        return m

    visit(root)
    return out


def share(widths: list[float], mins: list[float], total: float) -> list[float]:
    """``total`` over children of natural ``widths``: the change spread evenly, children that would fall below
    their ``mins`` held there and the rest shared by the others (proportionally when ``total`` is below the
    sum of ``mins``, which the QP's bounds rule out)."""
    n = len(widths)
    if total < sum(mins) - 1e-9:
        s = sum(widths)
        return [w * total / s for w in widths] if s > EPS else [total / n] * n
    held: set[int] = set()
    while len(held) < n:
        free = [i for i in range(n) if i not in held]
        delta = (total - sum(mins[i] for i in held) - sum(widths[i] for i in free)) / len(free)
        low = [i for i in free if widths[i] + delta < mins[i]]
        if not low:
            return [mins[i] if i in held else widths[i] + delta for i in range(n)]
        held.update(low)
    extra = (total - sum(mins)) / n  # every child at its least width: the rounding left over, shared
    return [m + extra for m in mins]


def collapse(facade: Facade, root: Node, threshold: float) -> Facade:
    """``facade`` (sized; ``root`` its tree's structure) without slabs of collapsible leaves thinner than
    ``threshold``: each such slab's extent goes to its left neighbour slab (the first slab's to its right one),
    whose leaves on the shared edge grow."""
    leaves = list(facade.leaves)
    gone: set[int] = set()

    def extent(node: Node) -> tuple[float, float]:
        return (min(leaves[i].x for i in node.leaves), max(leaves[i].right for i in node.leaves))

    def visit(node: Node) -> None:
        if node.split is None or node.split == GROUP:
            return
        kids = list(node.children)
        if node.split == X:
            tiny = [k for k, c in enumerate(kids) if all(leaves[i].label in COLLAPSIBLE for i in c.leaves)
                    and extent(c)[1] - extent(c)[0] < threshold]  # (labels first: they rule out most slabs)
            if tiny and len(tiny) < len(kids):
                first = next(k for k in range(len(kids)) if k not in tiny)
                for k in [k for k in tiny if k > first] + [k for k in reversed(tiny) if k < first]:
                    _give(kids, k, set(tiny), extent, leaves)  # leading slabs from the inside out
                    gone.update(kids[k].leaves)
                kids = [c for k, c in enumerate(kids) if k not in set(tiny)]
        for c in kids:
            visit(c)

    visit(root)
    if not gone:
        return facade
    return replace(facade, leaves=tuple(f for i, f in enumerate(leaves) if i not in gone))


def _give(kids: list[Node], k: int, tiny: set[int], extent: Callable[[Node], tuple[float, float]],
          leaves: list[Leaf]) -> None:
    """Grow the nearest kept slab left of ``kids[k]`` (else right of it) over ``kids[k]``'s extent."""
    lo, hi = extent(kids[k])
    left = [j for j in range(k - 1, -1, -1) if j not in tiny]
    if left:
        edge = extent(kids[left[0]])[1]
        for i in kids[left[0]].leaves:
            if abs(leaves[i].right - edge) <= EPS:
                leaves[i] = replace(leaves[i], w=leaves[i].w + (hi - edge))
        return
    right = next(j for j in range(k + 1, len(kids)) if j not in tiny)
    edge = extent(kids[right])[0]
    for i in kids[right].leaves:
        if abs(leaves[i].x - edge) <= EPS:
            leaves[i] = replace(leaves[i], x=lo, w=leaves[i].w + (edge - lo))
