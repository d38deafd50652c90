"""FacadeLayout: the one representation every ruleset kind produces and every consumer reads.

A layout is a face-local rectangle ``width x height`` (metres, origin bottom-left, x right, y up) holding a tree
of :class:`Region`. Terminal regions (no children) carry the semantic ``label`` that geometry, previews and the
inverse tools use. Within one ``layer`` the terminal regions partition the rectangle exactly (checked by
:func:`check_partition`). Layer-stack layouts carry one subtree per layer; other kinds use ``layer=None``.

The JSON form (``schema_version`` 1) is documented in ``docs/layout-json.md``.
"""
from __future__ import annotations

import functools
import itertools
import json
import math
import operator
import reprlib
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import MISSING, dataclass, field, fields, replace
from typing import Any

import numpy as np

from citygen.errors import LayoutError

SCHEMA_VERSION = 1

#: Labels with a meaning to geometry and validators. Plugins may use others; they render as wall.
LABELS = ("wall", "window", "door", "balcony", "sill", "cornice", "pillar", "shop", "blind", "deco", "molding",
          "roof", "ledge", "frame", "glass")

#: Labels of openings and attachments that belong to one floor and must not straddle a floor line.
FLOOR_BOUND_LABELS = frozenset({"window", "door", "balcony", "sill", "blind", "shop"})
#: Metres a region may stand out of (or into) its wall: the rulesets' and layouts' depths are refused beyond it.
MAX_DEPTH = 100.0


@dataclass(frozen=True)
class Region:
    """An axis-aligned rectangle of a layout.

    ``depth`` is the offset along the face normal in metres (negative = recessed). ``label is None`` on a
    terminal means a transparent region that produces no geometry (used by layer stacks).

    ``key`` is an optional hint from the generator: regions of one building's layouts with the same non-None key
    have identical subtrees relative to their origins (a grammar that derives a subtree once and places copies
    says so). Geometry uses it to find repeated modules without hashing every copy; it is not part of equality
    or of the JSON form.
    """

    x: float
    y: float
    w: float
    h: float
    symbol: str
    label: str | None = None
    depth: float = 0.0
    material: str | None = None
    asset: str | None = None
    layer: str | None = None
    children: tuple[Region, ...] = ()
    key: int | None = field(default=None, compare=False, repr=False)

    @classmethod
    def fast(cls, x: float, y: float, w: float, h: float, symbol: str, **kw: Any) -> Region:
        """``Region(x, y, w, h, symbol, **kw)`` without the frozen dataclass's per-field ``object.__setattr__``
        (2.5-4x faster; equal in every respect), for generators that make thousands of regions per facade."""
        region = object.__new__(cls)
        region.__dict__.update(_REGION_DEFAULTS, x=x, y=y, w=w, h=h, symbol=symbol, **kw)
        return region

    @staticmethod
    def template(symbol: str, **kw: Any) -> dict[str, Any]:
        """The fields of ``Region(0, 0, 0, 0, symbol, **kw)``, for :meth:`stamped`."""
        return {**_REGION_DEFAULTS, "x": 0.0, "y": 0.0, "w": 0.0, "h": 0.0, "symbol": symbol, **kw}

    @classmethod
    def stamped(cls, template: dict[str, Any], x: float, y: float, w: float, h: float) -> Region:
        """``Region(x, y, w, h, symbol, **kw)`` from ``template(symbol, **kw)``: twice as fast again as
        :meth:`fast` (no keyword dicts), for the thousands of regions of a few kinds a layer stack makes."""
        region = object.__new__(cls)
        fields_ = region.__dict__
        fields_.update(template)
        fields_["x"] = x
        fields_["y"] = y
        fields_["w"] = w
        fields_["h"] = h
        return region

    @property
    def is_terminal(self) -> bool:
        return not self.children

    def terminals(self) -> Iterator[Region]:
        """Terminal regions below (or equal to) this one, depth-first, left-to-right as stored."""
        stack = [self]
        while stack:
            region = stack.pop()
            if region.children:
                stack.extend(reversed(region.children))
            else:
                yield region

    def translated(self, dx: float, dy: float) -> Region:
        return replace(self, x=self.x + dx, y=self.y + dy,
                       children=tuple(c.translated(dx, dy) for c in self.children))

    def mirrored(self, width: float) -> Region:
        """This region and its subtree reflected across the vertical line ``x = width / 2`` (x runs the other way);
        children keep their order (a layer stack's root lists its layers bottom first)."""
        return replace(self, x=width - self.x - self.w, children=tuple(c.mirrored(width) for c in self.children))

    def moved(self, dx: float, dy: float) -> Region:
        """:meth:`translated`, made lazily: an inner region's copy makes its children (copies moved alike) when
        they are first read, so a generator that repeats a subtree pays one object per copy until a consumer walks
        into it. Every other field is shared; ``x + dx`` is the same float either way."""
        fields_ = self.__dict__.copy()
        fields_["x"] = self.x + dx
        fields_["y"] = self.y + dy
        if fields_.get("children", True):  # (an inner region, or a moved copy not yet walked)
            fields_.pop("children", None)
            fields_[_MOVED] = (self, dx, dy)
        copy = object.__new__(Region)
        object.__setattr__(copy, "__dict__", fields_)
        return copy

    def to_json(self) -> dict[str, Any]:
        data: dict[str, Any] = {"x": self.x, "y": self.y, "w": self.w, "h": self.h, "symbol": self.symbol}
        if self.label is not None:
            data["label"] = self.label
        if self.depth:
            data["depth"] = self.depth
        for key in ("material", "asset", "layer"):
            value = getattr(self, key)
            if value is not None:
                data[key] = value
        if self.children:
            data["children"] = [c.to_json() for c in self.children]
        return data

    @classmethod
    def from_json(cls, data: Mapping[str, Any], path: str = "root", source: str | None = None) -> Region:
        """The region tree of a layout JSON object; ``path`` (``root.children[2]``) and ``source`` (the file)
        name a malformed region in the :class:`LayoutError`."""
        def fail(problem: str) -> LayoutError:
            return LayoutError(f"region {path} {problem}", where=source,
                               hint="each region needs finite numeric x, y, w, h (w, h >= 0), a symbol string, "
                                    "and optional string label, material, asset, layer (docs/layout-json.md)")
        if not isinstance(data, Mapping):
            raise fail(f"is {type(data).__name__}, not a JSON object")
        numbers = {}
        for key in ("x", "y", "w", "h", "depth"):
            value = data.get(key, 0.0 if key == "depth" else None)
            if value is None and key != "depth":
                raise fail(f"has no {key}")
            if isinstance(value, bool) or not isinstance(value, (int, float)) \
                    or not math.isfinite(_as_float(value)):
                raise fail(f"has {key} = {reprlib.repr(value)}, not a finite number")
            numbers[key] = float(value)
        if numbers["w"] < 0 or numbers["h"] < 0:
            raise fail(f"has a negative size {numbers['w']:g} x {numbers['h']:g}")
        if abs(numbers["depth"]) > MAX_DEPTH:
            raise fail(f"has depth = {numbers['depth']:g} m, beyond +-{MAX_DEPTH:g} m")
        texts = {}
        for key in ("symbol", "label", "material", "asset", "layer"):
            value = data.get(key)
            if value is not None and not isinstance(value, str):
                raise fail(f"has {key} = {reprlib.repr(value)}, not a string")
            texts[key] = value
        children = data.get("children", [])
        if not isinstance(children, list):
            raise fail(f"has children = {reprlib.repr(children)}, not a list")
        return cls(**numbers, symbol=texts["symbol"] or texts["label"] or "Region", label=texts["label"],
                   material=texts["material"], asset=texts["asset"], layer=texts["layer"],
                   children=tuple(cls.from_json(c, f"{path}.children[{i}]", source) for i, c in enumerate(children)))


#: The field of a lazily moved copy (:meth:`Region.moved`) naming ``(original, dx, dy)`` until its children exist.
_MOVED = "_moved_from"


class _Children:
    """``Region.children``: a field like the others (kept in the region's ``__dict__``, which wins over this
    non-data descriptor), except in a lazily moved copy, whose children are made here on first read."""

    def __get__(self, region: Region | None, owner: type | None = None) -> tuple[Region, ...]:
        if region is None:
            return ()
        fields_ = region.__dict__
        moved = fields_.get(_MOVED)
        if moved is None:
            return ()
        original, dx, dy = moved
        children = tuple(c.moved(dx, dy) for c in original.children)
        fields_["children"] = children
        fields_.pop(_MOVED, None)
        return children


Region.children = _Children()  # type: ignore[assignment]  (the dataclass keeps its default, ())


def unwalked(region: Region) -> tuple[Region, float, float] | None:
    """``(original, dx, dy)`` of a lazily moved copy whose children are not made yet (:meth:`Region.moved`): its
    children are the original's, each moved by ``(dx, dy)``; else None."""
    return region.__dict__.get(_MOVED)


def is_inner(region: Region) -> bool:
    """Whether ``region`` has children, without making a lazily moved copy's."""
    return bool(region.__dict__.get("children", True))


def _collect_leaves(region: Region, add: Callable[[Region], None]) -> None:
    """``add`` every terminal below ``region`` in tree order (recursion: cheaper than a generator's stack)."""
    for child in region.children:
        if child.children:
            _collect_leaves(child, add)
        else:
            add(child)


def _as_float(value: int | float) -> float:
    """``float(value)``, or inf for an integer too large for a float."""
    try:
        return float(value)
    except OverflowError:
        return math.inf


#: A region's rectangle ``(x, y, w, h)``.
_XYWH = operator.attrgetter("x", "y", "w", "h")
_LABEL = operator.attrgetter("label")
_LAYER = operator.attrgetter("layer")

_REGION_DEFAULTS = {f.name: f.default for f in fields(Region) if f.default is not MISSING}


@dataclass(frozen=True)
class FacadeLayout:
    """A facade layout: the rectangle ``width x height`` and the region tree under ``root``."""

    width: float
    height: float
    root: Region
    meta: Mapping[str, Any] = field(default_factory=dict)

    @functools.cached_property
    def leaves(self) -> tuple[Region, ...]:
        """Terminal regions in tree order, computed once (validators, geometry and repairs all walk them)."""
        if not self.root.children:
            return (self.root,)
        out: list[Region] = []
        _collect_leaves(self.root, out.append)
        return tuple(out)

    @functools.cached_property
    def leaf_sources(self) -> tuple[tuple[Region, ...], np.ndarray]:
        """Terminals standing for all (*sources*, in tree order) and per terminal the index of its source, as a
        read-only int array: a terminal equals its source in every field but ``x`` and ``y``. By default every
        terminal is its own source; a generator that places moved copies of subtrees or terminals
        (:meth:`Region.moved`) hands over its own (the split derivation: one source per distinct terminal, the first
        of its kind), so the checks read labels, layers and materials without walking the copies."""
        index = np.arange(len(self.leaves))
        index.flags.writeable = False
        return self.leaves, index

    @functools.cached_property
    def leaf_labels(self) -> tuple[tuple[str | None, ...], np.ndarray]:
        """The terminals' distinct labels (in order of first appearance) and each terminal's index into them, as a
        read-only int array: the checks test a few labels of a few hundred terminals as array lookups."""
        sources, index = self.leaf_sources
        labels = list(map(_LABEL, sources))
        names = tuple(dict.fromkeys(labels))
        position = {name: k for k, name in enumerate(names)}
        codes = np.fromiter(map(position.__getitem__, labels), dtype=np.intp, count=len(labels))[index]
        codes.flags.writeable = False
        return names, codes

    def label_mask(self, labels: Callable[[str | None], bool]) -> np.ndarray:
        """Which terminals have a label for which ``labels(label)`` holds (a bool array in tree order)."""
        names, codes = self.leaf_labels
        return np.array([bool(labels(n)) for n in names], dtype=bool)[codes] if names else np.zeros(0, bool)

    def terminals(self) -> list[Region]:
        return list(self.leaves)

    def labels(self) -> list[str | None]:
        return [r.label for r in self.leaves]

    @functools.cached_property
    def leaf_rects(self) -> np.ndarray:
        """Terminal rectangles in tree order as a read-only ``(n, 4)`` float array of ``x, y, w, h``, computed once
        (the partition and request checks both read it; a generator may hand it over)."""
        leaves = self.leaves
        rects = np.fromiter(itertools.chain.from_iterable(map(_XYWH, leaves)), dtype=float,
                            count=4 * len(leaves)).reshape(-1, 4)
        rects.flags.writeable = False
        return rects

    def terminal_array(self) -> np.ndarray:
        """Terminal rectangles as an ``(n, 4)`` float array of ``x, y, w, h`` (a copy of :attr:`leaf_rects`)."""
        return self.leaf_rects.copy()

    def count(self, label: str) -> int:
        names, codes = self.leaf_labels
        return int(np.count_nonzero(codes == names.index(label))) if label in names else 0

    def with_meta(self, meta: Mapping[str, Any]) -> FacadeLayout:
        """This layout with ``meta`` instead of its own, keeping the terminal arrays already made (same tree)."""
        out = FacadeLayout(self.width, self.height, self.root, meta)
        known = self.__dict__
        out.__dict__.update({name: known[name] for name in _LEAF_DATA if name in known})
        return out

    def mirrored(self, meta: Mapping[str, Any]) -> FacadeLayout:
        """This layout reflected left to right (:meth:`Region.mirrored`), with ``meta``."""
        return FacadeLayout(self.width, self.height, self.root.mirrored(self.width), meta)

    def to_json(self) -> dict[str, Any]:
        return {"schema_version": SCHEMA_VERSION, "width": self.width, "height": self.height,
                "meta": dict(self.meta), "root": self.root.to_json()}

    def dumps(self) -> str:
        return json.dumps(self.to_json(), indent=1, sort_keys=True)

    @classmethod
    def from_json(cls, data: Mapping[str, Any], source: str = "<layout>") -> FacadeLayout:
        if not isinstance(data, Mapping):
            raise LayoutError(f"a layout is a JSON object, not {type(data).__name__}", where=source,
                              hint="see docs/layout-json.md")
        version = data.get("schema_version")
        if version != SCHEMA_VERSION:
            raise LayoutError(f"unsupported schema_version {version!r}", where=source,
                              hint=f"this citygen reads layout JSON schema_version {SCHEMA_VERSION}")
        size = (data.get("width"), data.get("height"))
        if not all(isinstance(v, (int, float)) and not isinstance(v, bool) and 0 < _as_float(v) < math.inf
                   for v in size):
            raise LayoutError("layout needs a finite positive width and height, got "
                              f"{reprlib.repr(size[0])} x {reprlib.repr(size[1])}", where=source)
        if "root" not in data:
            raise LayoutError("layout has no root region", where=source, hint="see docs/layout-json.md")
        meta = data.get("meta", {})
        if not isinstance(meta, Mapping):
            raise LayoutError(f"layout meta must be a JSON object, got {reprlib.repr(meta)}", where=source)
        return cls(width=float(size[0]), height=float(size[1]), root=Region.from_json(data["root"], source=source),
                   meta=dict(meta))

    @classmethod
    def loads(cls, text: str, source: str = "<layout>") -> FacadeLayout:
        try:
            data = json.loads(text)
            return cls.from_json(data, source)
        except json.JSONDecodeError as exc:
            raise LayoutError(f"not JSON: {exc.msg}", where=f"{source}:{exc.lineno}:{exc.colno}") from exc
        except RecursionError:  # (a mutated or generated file: json and the region tree recurse per level)
            raise LayoutError("layout JSON nested too deeply", where=source,
                              hint="a facade's regions nest a few levels deep; check the file") from None


#: The cached properties of a :class:`FacadeLayout` that depend only on its tree.
_LEAF_DATA = ("leaves", "leaf_sources", "leaf_labels", "leaf_rects")


def check_partition(layout: FacadeLayout, tol: float = 1e-6) -> list[str]:
    """Problems with the partition contract; an empty list means the layout is valid.

    Per layer, terminal regions must have non-negative sizes, lie inside the rectangle, and cover every point of
    it exactly once. ``tol`` is relative to the facade's larger side. Coverage is counted exactly on the grid of
    the regions' own (tolerance-clustered) edge coordinates with a 2-D difference array, so the check costs
    O(n log n + cells), not O(n²).
    """
    problems: list[str] = []
    eps = tol * max(layout.width, layout.height, 1e-9)
    (sources, index), all_rects = layout.leaf_sources, layout.leaf_rects
    symbols = _Symbols(sources, index)
    layers = list(map(_LAYER, sources))
    if layers.count(layers[0]) == len(layers):  # (one layer: most layouts)
        return _layer_partition(layout, layers[0], symbols, all_rects, eps)
    order = {layer: k for k, layer in enumerate(dict.fromkeys(layers))}
    of_leaf = np.array([order[layer] for layer in layers])[index]
    for layer, k in order.items():
        members = np.flatnonzero(of_leaf == k)
        problems += _layer_partition(layout, layer, symbols.subset(members), all_rects[members], eps)
    return problems


@dataclass(frozen=True)
class _Symbols:
    """The symbols of some terminals of a layout, by position, read from their sources (for messages)."""

    sources: Sequence[Region]
    index: np.ndarray

    def __getitem__(self, i: int) -> str:
        return self.sources[self.index[i]].symbol

    def subset(self, members: np.ndarray) -> _Symbols:
        return _Symbols(self.sources, self.index[members])


def _layer_partition(layout: FacadeLayout, layer: str | None, symbols: _Symbols, rects: np.ndarray,
                     eps: float) -> list[str]:
    """:func:`check_partition` of one layer's terminals: their ``symbols`` and rectangles ``rects``."""
    name = f"layer {layer!r}" if layer is not None else "layout"
    x0, y0 = rects[:, 0], rects[:, 1]
    x1, y1 = x0 + rects[:, 2], y0 + rects[:, 3]
    if rects.min() >= -eps and x1.max() <= layout.width + eps and y1.max() <= layout.height + eps:
        # (finite -- a NaN fails every comparison, an infinity one of them --, no negative size, none outside)
        return _coverage(name, symbols, x0, y0, x1, y1, layout.width, layout.height, eps)
    if not np.all(np.isfinite(rects)):
        return [f"{name}: non-finite coordinates"]
    bad = np.flatnonzero((rects[:, 2] < -eps) | (rects[:, 3] < -eps))
    problems = [f"{name}: region {symbols[i]} has negative size {rects[i, 2:]}" for i in bad[:5]]
    outside = np.flatnonzero((x0 < -eps) | (y0 < -eps) | (x1 > layout.width + eps) | (y1 > layout.height + eps))
    problems += [f"{name}: region {symbols[i]} at {rects[i]} leaves the rectangle" for i in outside[:5]]
    if bad.size or outside.size:
        return problems
    return _coverage(name, symbols, x0, y0, x1, y1, layout.width, layout.height, eps)


def _cluster(starts: np.ndarray, ends: np.ndarray, bounds: tuple[float, float],
             eps: float) -> tuple[np.ndarray, np.ndarray]:
    """Snap coordinates to clusters (sorted values, a new cluster after every gap above ``eps``): (cluster
    positions, cluster index of every value as a ``(2, n)`` array: ``starts`` then ``ends``). Every value gets the
    cluster it was sorted into (looking up ``value + eps`` instead put a value exactly ``eps`` below the next
    cluster into that one)."""
    allv = np.concatenate((starts, ends, bounds))
    order = allv.argsort(kind="stable")
    ordered = allv[order]
    new = np.empty(allv.size, dtype=bool)
    new[0] = True
    np.greater(ordered[1:] - ordered[:-1], eps, out=new[1:])
    index = np.empty(allv.size, dtype=np.int64)
    index[order] = new.astype(np.int64).cumsum()
    index -= 1
    return ordered[new], index[: 2 * starts.size].reshape(2, -1)


def _coverage(name: str, symbols: _Symbols, x0: np.ndarray, y0: np.ndarray, x1: np.ndarray,
              y1: np.ndarray, width: float, height: float, eps: float) -> list[str]:
    xs, ix = _cluster(x0, x1, (0.0, width), eps)
    ys, iy = _cluster(y0, y1, (0.0, height), eps)
    nx, ny = len(xs), len(ys)
    if nx * ny > 25_000_000:
        return [f"{name}: {len(x0)} regions on a {nx}x{ny} grid are too irregular to check"]
    stride = ny + 1
    cells = (nx + 1) * stride
    # +1 at each rectangle's (x0, y0) and (x1, y1) corner, -1 at (x1, y0) and (x0, y1)
    diff = (np.bincount((ix * stride + iy).ravel(), minlength=cells)
            - np.bincount((ix[::-1] * stride + iy).ravel(), minlength=cells))
    # (the prefix sums along x summed on the transpose: numpy's cumsum across rows is twice as slow)
    along_y = np.ascontiguousarray(diff.reshape(nx + 1, stride).cumsum(axis=1).T)
    cover = along_y.cumsum(axis=1).T[: nx - 1, : ny - 1]
    if not cover.size or cover.min() == cover.max() == 1:  # (integer counts: exact)
        return []
    problems = []
    holes = np.argwhere(cover == 0)
    if holes.size:
        gx, gy = holes[0]
        area = float(np.sum(np.outer(np.diff(xs), np.diff(ys))[cover == 0]))
        problems.append(f"{name}: regions leave {area:.6g} m2 uncovered, e.g. at x={xs[gx]:.4g}, y={ys[gy]:.4g}")
    over = np.argwhere(cover > 1)
    if over.size:
        gx, gy = over[0]
        hit = np.flatnonzero((ix[0] <= gx) & (ix[1] > gx) & (iy[0] <= gy) & (iy[1] > gy))
        pair = " and ".join(symbols[i] for i in hit[:2].tolist())
        problems.append(f"{name}: regions {pair} overlap at x={xs[gx]:.4g}, y={ys[gy]:.4g}")
    return problems


def remembered(layout: FacadeLayout, check: str, inputs: tuple[Any, ...], compute: Callable[[], list]) -> list:
    """``compute()``, the ``check`` of ``layout`` against ``inputs``, run once per layout and inputs (the same
    objects): a layout is immutable, so the builder's checks after a generator's reuse the generator's result.
    Returns a new list each time."""
    memo = layout.__dict__.setdefault("_checks", [])
    for name, seen, result in memo:
        if name == check and all(a is b for a, b in zip(seen, inputs)):
            return list(result)
    result = compute()
    memo.append((check, inputs, tuple(result)))
    return list(result)


def require_partition(layout: FacadeLayout, where: str = "<layout>", plugin: str | None = None) -> FacadeLayout:
    """Return ``layout`` or raise :class:`LayoutError` listing its partition problems."""
    problems = check_partition(layout)
    if problems:
        raise LayoutError("; ".join(problems[:5]), where=where, plugin=plugin,
                          hint="a ruleset kind must emit terminal regions that tile the face exactly")
    return layout


def hidden_behind(layout: FacadeLayout, cover: Sequence[float] | np.ndarray, tol: float = 1e-6) -> FacadeLayout:
    """``layout`` with every subtree that neighbours hide replaced by one plain wall region: no openings or
    attachments inside a neighbour. ``cover`` holds, for equal bins across the face's width (left to right), the
    height up to which a neighbour stands against it (one value: the whole width); a subtree is hidden when every
    bin its width overlaps is covered up to its top. ``layout`` itself (with its terminal arrays) when nothing is
    hidden.

    One walk over the inner regions reaching below the cover: a region whose top is above the highest cover is
    not hidden, so its bins are looked up only when its top is not (the same test, decided sooner)."""
    cover = np.atleast_1d(np.asarray(cover, dtype=float))
    highest = float(cover.max(initial=0.0))
    if highest <= tol:
        return layout
    step = layout.width / cover.size
    heights = cover.tolist()  # (Python floats: a bin lookup per region visited stays out of numpy)
    ceiling = math.inf if math.isnan(highest) else highest + tol  # (a NaN cover: every region looked up, as ever)
    lowest = highest - tol

    def hidden_to(x0: float, x1: float) -> float:
        k0 = min(max(math.floor(x0 / step + tol), 0), len(heights) - 1)
        k1 = min(max(math.ceil(x1 / step - tol), k0 + 1), len(heights))
        return min(heights[k0:k1])

    def culled(regions: tuple[Region, ...]) -> list[Region]:
        out = []
        for r in regions:
            top = r.y + r.h
            if top <= ceiling and top <= hidden_to(r.x, r.x + r.w) + tol:
                if is_inner(r) or r.label not in (None, "wall") or r.depth:
                    r = Region(r.x, r.y, r.w, r.h, "Wall", "wall")
            elif not (r.y >= lowest or not is_inner(r)):  # (a moved copy above the cover stays unmade)
                children = culled(r.children)
                if not all(map(operator.is_, children, r.children)):
                    r = replace(r, children=tuple(children), key=None)  # (no longer the subtree its key names)
            out.append(r)
        return out
    root = culled((layout.root,))[0]
    return layout if root is layout.root else replace(layout, root=root)


def leaf(x: float, y: float, w: float, h: float, symbol: str, label: str | None, **kw: Any) -> Region:
    """Shorthand for a terminal region."""
    return Region(x=x, y=y, w=w, h=h, symbol=symbol, label=label, **kw)
