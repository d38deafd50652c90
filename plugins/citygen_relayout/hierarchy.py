"""Hierarchical segmentation (bao2013 §4) from a FacadeLayout.

A composite whose children already tile it along one axis keeps its structure. Any other composite (a flat list
of labelled rectangles, as annotation importers produce) is re-segmented by recursive guillotine cuts, preferring
horizontal splitting lines (floors) first, then vertical ones, alternating by level. Symbols come from the layout;
regions that share a symbol must be identical (same size and decomposition), otherwise the later ones get a
numbered symbol (``window_2``). Composites created by the segmentation are named after their content and shared
between identical ones, so repeated floors and columns get one symbol.
"""
from __future__ import annotations

from citygen.errors import LayoutError
from citygen.layout import FacadeLayout, Region
from citygen_relayout.model import Symbol

_EPS = 1e-6
_TOL = 1e-3


def symbols_from_layout(layout: FacadeLayout, tolerance: float = 1e-3) -> tuple[dict[str, Symbol], str]:
    """Symbols of the segmentation of ``layout`` and the root symbol.

    Regions with the same label and decomposition whose sizes agree within ``tolerance`` (relative) are taken as
    identical and share a symbol: the regularisation of almost-equal regions that bao2013 §4 asks the user for.
    """
    global _TOL
    _TOL = tolerance
    table: dict[str, Symbol] = {}
    signatures: dict[tuple, str] = {}
    root = _segment(layout.root, table, signatures, prefer="y", is_root=True)
    return table, root


def _axis(region: Region) -> str | None:
    kids = region.children
    tol = _EPS * max(region.w, region.h, 1.0)
    for axis in ("x", "y"):
        o, s, lo, ext = ((lambda r: r.x), (lambda r: r.w), region.x, region.w) if axis == "x" else \
            ((lambda r: r.y), (lambda r: r.h), region.y, region.h)
        full = all(abs((c.y if axis == "x" else c.x) - (region.y if axis == "x" else region.x)) < tol
                   and abs((c.h if axis == "x" else c.w) - (region.h if axis == "x" else region.w)) < tol
                   for c in kids)
        if not full:
            continue
        pos = lo
        for c in sorted(kids, key=o):
            if abs(o(c) - pos) > tol:
                break
            pos += s(c)
        else:
            if abs(pos - (lo + ext)) < tol:
                return axis
    return None


def _segment(region: Region, table: dict, signatures: dict, prefer: str, is_root: bool = False) -> str:
    if region.is_terminal:
        return _register(Symbol(region.symbol, (region.w, region.h), region.label, region.depth, region.material,
                                region.asset), table)
    axis = _axis(region)
    if axis is None:
        leaves = [t for t in region.terminals() if t.w > _EPS and t.h > _EPS]
        return _guillotine(region, leaves, table, signatures, prefer, region.symbol if is_root else None)
    key = (lambda r: r.x) if axis == "x" else (lambda r: r.y)
    kids = tuple(_segment(c, table, signatures, "x" if axis == "y" else "y")
                 for c in sorted(region.children, key=key) if (c.w if axis == "x" else c.h) > _EPS)
    return _register(Symbol(region.symbol, (region.w, region.h), region.label, region.depth, region.material,
                            region.asset, axis, kids), table)


def _register(sym: Symbol, table: dict[str, Symbol]) -> str:
    name, k = sym.name, 1
    while name in table and not _same(table[name], sym):
        k += 1
        name = f"{sym.name}_{k}"
    if name not in table:
        table[name] = Symbol(name, sym.extent, sym.label, sym.depth, sym.material, sym.asset, sym.split, sym.children)
    return name


def _same(a: Symbol, b: Symbol) -> bool:
    return (a.split, a.children, a.label, a.depth, a.material) == (b.split, b.children, b.label, b.depth, b.material) \
        and all(abs(p - q) <= _TOL * max(p, q, 1e-9) for p, q in zip(a.extent, b.extent))


def _cuts(leaves: list[Region], lo: float, hi: float, axis: str) -> list[float]:
    """Interior splitting lines along ``axis`` that no leaf straddles."""
    spans = sorted(((r.x, r.x + r.w) if axis == "x" else (r.y, r.y + r.h)) for r in leaves)
    cuts, reach = [], lo
    for a, b in spans:
        if a >= reach - _EPS and lo + _EPS < a < hi - _EPS and (not cuts or a > cuts[-1] + _EPS):
            cuts.append(a)
        reach = max(reach, b)
    return cuts


def _guillotine(box: Region, leaves: list[Region], table: dict, signatures: dict, prefer: str,
                name: str | None) -> str:
    if len(leaves) == 1:
        leaf = leaves[0]
        return _register(Symbol(leaf.symbol, (box.w, box.h), leaf.label, leaf.depth, leaf.material, leaf.asset),
                         table)
    for axis in (prefer, "x" if prefer == "y" else "y"):
        lo, hi = (box.x, box.x + box.w) if axis == "x" else (box.y, box.y + box.h)
        cuts = _cuts(leaves, lo, hi, axis)
        if cuts:
            break
    else:
        raise LayoutError(f"region {box.symbol} at {box.x:.3g},{box.y:.3g} has no guillotine cut",
                          hint="the layout needs a hierarchical (splittable) decomposition, bao2013 §4")
    spans = _merge_walls(axis, [lo, *cuts, hi], leaves)
    edges = [spans[0][0], *(b for _, b, _ in spans)]
    kids = []
    for a, b, inside in spans:
        part = Region(a, box.y, b - a, box.h, "S") if axis == "x" else Region(box.x, a, box.w, b - a, "S")
        if len(inside) == 1:
            leaf = inside[0]
            inside = [Region(part.x, part.y, part.w, part.h, leaf.symbol, leaf.label, leaf.depth, leaf.material,
                             leaf.asset)]
        kids.append(_guillotine(part, inside, table, signatures, "x" if axis == "y" else "y", None))
    sizes = tuple(round(b - a, 3) for a, b in zip(edges, edges[1:]))
    other = round(box.h if axis == "x" else box.w, 3)
    sig = (axis, tuple(kids), sizes, other)
    if name is None:
        probe = Symbol("?", (box.w, box.h), None, 0.0, None, None, axis, tuple(kids))
        name = signatures.get(sig) or next((s.name for s in table.values() if _same(s, probe)), None) \
            or f"{'Col' if axis == 'y' else 'Row'}{len(signatures) + 1}"
    signatures.setdefault(sig, name)
    return _register(Symbol(name, (box.w, box.h), None, 0.0, None, None, axis, tuple(kids)), table)


def _merge_walls(axis: str, edges: list[float], leaves: list[Region]) -> list[tuple[float, float, list[Region]]]:
    """Slices between cuts; adjacent slices that are a single plain-wall leaf each become one wall slice."""
    spans: list[tuple[float, float, list[Region]]] = []
    for a, b in zip(edges, edges[1:]):
        inside = [r for r in leaves if (a - _EPS <= (r.x if axis == "x" else r.y)
                                        and (r.x + r.w if axis == "x" else r.y + r.h) <= b + _EPS)]
        plain = len(inside) == 1 and inside[0].label == "wall" and not inside[0].depth
        if plain and spans and len(spans[-1][2]) == 1 and spans[-1][2][0].label == "wall" \
                and not spans[-1][2][0].depth:
            spans[-1] = (spans[-1][0], b, spans[-1][2])
        else:
            spans.append((a, b, inside))
    return spans
