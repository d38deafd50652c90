"""Hierarchical segmentation (bao2013 §4) from a FacadeLayout.

A composite whose children already tile it along one axis keeps its structure. Any other composite (a flat list
of labelled rectangles, as annotation importers produce) is segmented into **storeys** first: the horizontal
splitting lines that no rectangle straddles cut the facade into slices; a slice holding an opening at least
:data:`CORE_HEIGHT` tall (a window, door, shop or balcony, not a sign or vent) is a storey's core, and the bands
between two cores belong to the storey above (its sills and floor moldings), the bands below the first core to the
ground storey (``Ground``) and the bands above the last core to the top band (``Top``); the other storeys are
``Storey`` (``Storey_2`` ... for differing ones). Each storey is then cut into **bays** (vertical splitting lines
first), and recursively by guillotine cuts alternating the axis. Symbols come from the layout; regions that share
a symbol must be identical (same size and decomposition), otherwise the later ones get a numbered symbol
(``window_2``). Composites created by the segmentation are named after their content and shared between
identical ones, so repeated storeys and bays get one symbol.
"""
from __future__ import annotations

from dataclasses import dataclass

from citygen.errors import LayoutError
from citygen.layout import FacadeLayout, Region
from citygen.plausible import OPENING_LABELS
from citygen_relayout.model import Symbol

_EPS = 1e-6
_TOL = 1e-3
#: An opening at least this tall (m) makes its slice of the facade a storey's core.
CORE_HEIGHT = 1.0


@dataclass(frozen=True)
class Segmentation:
    """Symbols of a layout's segmentation, its root, and the root's storeys above the ground (repeatable)."""

    symbols: dict[str, Symbol]
    root: str
    storeys: tuple[str, ...] = ()
    gaps: tuple[str, ...] = ()  # the plain wall bands between storeys
    bands: tuple[str, ...] = ()  # the top band


def symbols_from_layout(layout: FacadeLayout, tolerance: float = 1e-3) -> Segmentation:
    """The segmentation of ``layout``: symbols, root and (for a flat layout) the storeys above the ground.

    Regions with the same label and decomposition whose sizes agree within ``tolerance`` (relative) are taken as
    identical and share a symbol: the regularisation of almost-equal regions that bao2013 §4 asks the user for.
    """
    global _TOL
    _TOL = tolerance
    table: dict[str, Symbol] = {}
    signatures: dict[tuple, str] = {}
    region = layout.root
    if not region.is_terminal and _axis(region) is None:
        leaves = [t for t in region.terminals() if t.w > _EPS and t.h > _EPS]
        return _storeys(region, leaves, table, signatures)
    return Segmentation(table, _segment(region, table, signatures, prefer="y", is_root=True))


def _storeys(box: Region, leaves: list[Region], table: dict, signatures: dict) -> Segmentation:
    """The facade as a y-split of storeys (see the module doc); with fewer than two storey cores, plain guillotine
    cuts. Between two cores, the plain wall slice nearest the middle of the gap becomes a ``Gap`` child of its
    own (the spandrel that keeps the storey pitch while the top band shares the top floor), else the storeys part
    at the splitting line nearest the middle."""
    lo, hi = box.y, box.y + box.h
    edges = [lo, *_cuts(leaves, lo, hi, "y"), hi]
    slices = [(a, b, [r for r in leaves if a - _EPS <= r.y and r.y + r.h <= b + _EPS])
              for a, b in zip(edges, edges[1:])]
    cores = [(a, b) for a, b, inside in slices
             if any(r.label in OPENING_LABELS and r.h >= CORE_HEIGHT - _EPS for r in inside)]
    if len(cores) < 2:
        return Segmentation(table, _guillotine(box, leaves, table, signatures, "y", box.symbol))
    parts: list[tuple[float, float, str]] = []  # (bottom, top, role)
    start = lo
    for (_, top), (bottom, _) in zip(cores, cores[1:]):
        middle = (top + bottom) / 2
        walls = [(a, b) for a, b, inside in slices if top - _EPS <= a and b <= bottom + _EPS and len(inside) == 1
                 and inside[0].label == "wall" and inside[0].w >= box.w - _EPS]
        if walls:
            a, b = min(walls, key=lambda ab: abs((ab[0] + ab[1]) / 2 - middle))
            parts += [(start, a, "storey"), (a, b, "gap")]
            start = b
        else:
            cut = min((e for e in edges if top - _EPS <= e <= bottom + _EPS), key=lambda e: abs(e - middle))
            parts.append((start, cut, "storey"))
            start = cut
    if hi - cores[-1][1] > _EPS:
        parts += [(start, cores[-1][1], "storey"), (cores[-1][1], hi, "top")]
    else:
        parts.append((start, hi, "storey"))
    kids, roles = [], []
    for k, (a, b, role) in enumerate(parts):
        part = Region(box.x, a, box.w, b - a, "S")
        inside = [r for r in leaves if a - _EPS <= r.y and r.y + r.h <= b + _EPS]
        if role == "gap":
            leaf = inside[0]
            kids.append(_register(Symbol("Gap", (box.w, b - a), leaf.label, leaf.depth, leaf.material, leaf.asset),
                                  table))
        else:
            name = {"top": "Top"}.get(role, "Ground" if k == 0 else "Storey")
            kids.append(_guillotine(part, inside, table, signatures, "x", name))
        roles.append(role)
    root = _register(Symbol(box.symbol, (box.w, box.h), None, 0.0, None, None, "y", tuple(kids)), table)

    def having(role: str, skip_first: bool = False) -> tuple[str, ...]:
        return tuple(dict.fromkeys(c for k, (c, r) in enumerate(zip(kids, roles))
                                   if r == role and (k or not skip_first)))
    return Segmentation(table, root, having("storey", skip_first=True), having("gap"), having("top"))


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
