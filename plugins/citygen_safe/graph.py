"""The neighbourhood graph (dang2014 §4) and its conversion back to a decomposition tree by chain collapsing.

Nodes are the leaves of a decomposition tree. A vertical edge ``(i, j)`` joins ``i`` below ``j`` when they share a
piece of horizontal boundary; a horizontal edge ``(i, j)`` joins ``i`` left of ``j`` sharing vertical boundary.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from citygen_safe.leaves import EPS
from citygen_safe.tree import GROUP, X, Y, Node


@dataclass(frozen=True)
class NeighbourhoodGraph:
    """``G = (N, V, H)`` over ``nodes`` (tree leaves); edges as index pairs into ``nodes``."""

    nodes: tuple[Node, ...]
    vertical: frozenset[tuple[int, int]]
    horizontal: frozenset[tuple[int, int]]


def neighbourhood_graph(nodes: tuple[Node, ...]) -> NeighbourhoodGraph:
    r = np.array([(n.x, n.y, n.x + n.w, n.y + n.h) for n in nodes], dtype=float).reshape(-1, 4)
    x0, y0, x1, y1 = (r[:, k] for k in range(4))
    xo = np.minimum(x1[:, None], x1[None, :]) - np.maximum(x0[:, None], x0[None, :]) > EPS
    yo = np.minimum(y1[:, None], y1[None, :]) - np.maximum(y0[:, None], y0[None, :]) > EPS
    vert = np.argwhere((np.abs(y1[:, None] - y0[None, :]) <= EPS) & xo)
    hori = np.argwhere((np.abs(x1[:, None] - x0[None, :]) <= EPS) & yo)
    return NeighbourhoodGraph(nodes, frozenset(map(tuple, vert.tolist())), frozenset(map(tuple, hori.tolist())))


def to_tree(graph: NeighbourhoodGraph) -> Node:
    """Collapse the longest chain (nodes linked one-to-one by edges of one type) into a parent shape until one
    node is left. A graph with no chain left (a pinwheel) is closed by one ``group`` node."""
    nodes = dict(enumerate(graph.nodes))
    edges = {X: {(a, b) for a, b in graph.horizontal}, Y: {(a, b) for a, b in graph.vertical}}
    fresh = len(nodes)
    while len(nodes) > 1:
        chain, split = _longest_chain(nodes, edges)
        if not chain:
            members = tuple(i for n in nodes.values() for i in n.leaves)
            xs = [n.x for n in nodes.values()]
            ys = [n.y for n in nodes.values()]
            x1 = max(n.x + n.w for n in nodes.values())
            y1 = max(n.y + n.h for n in nodes.values())
            return Node(min(xs), min(ys), x1 - min(xs), y1 - min(ys), GROUP, (), members)
        parts = [nodes.pop(k) for k in chain]
        children = tuple(c for p in parts for c in (p.children if p.split == split else (p,)))
        first, last = parts[0], parts[-1]
        w = last.x + last.w - first.x if split == X else first.w
        h = last.y + last.h - first.y if split == Y else first.h
        nodes[fresh] = Node(first.x, first.y, w, h, split, children, tuple(i for p in parts for i in p.leaves))
        members = set(chain)
        for kind in (X, Y):
            edges[kind] = {(fresh if a in members else a, fresh if b in members else b) for a, b in edges[kind]}
            edges[kind] = {(a, b) for a, b in edges[kind] if a != b}
        fresh += 1
    return next(iter(nodes.values()))


def _longest_chain(nodes: dict[int, Node], edges: dict[str, set[tuple[int, int]]]) -> tuple[list[int], str]:
    best: tuple[list[int], str] = ([], X)
    for split in (Y, X):
        out: dict[int, list[int]] = {}
        inc: dict[int, list[int]] = {}
        for a, b in edges[split]:
            out.setdefault(a, []).append(b)
            inc.setdefault(b, []).append(a)
        link = {a: bs[0] for a, bs in out.items() if len(bs) == 1 and len(inc.get(bs[0], ())) == 1}
        starts = set(link) - set(link.values())
        for start in sorted(starts):
            chain = [start]
            while chain[-1] in link:
                chain.append(link[chain[-1]])
            if len(chain) > len(best[0]):
                best = (chain, split)
    return best
