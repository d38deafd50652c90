"""Facade modules: repeated subtrees of a building's layouts, instanced as a whole.

A split grammar repeats bays, window columns with their mouldings, whole floors; a relayout repeats its symbols.
Their geometry is the same every time, so it is stored once as a prototype and placed by a PointInstancer -- which
is what keeps a city's stage small (the walls, mouldings and frames around windows are most of its polygons).

Every region gets a *signature*: a 64-bit hash of its size and content in centimetres (terminal: label,
material, layer, depth; inner region: its children's signatures and offsets). Hashes of int tuples do not depend
on ``PYTHONHASHSEED``, so signatures agree across worker processes. A region becomes a module when its signature
occurs at least twice in the building, it holds some detail (not only flat wall), it saves enough geometry to
pay for a prototype (``(count - 1) * terminals >= MIN_SAVING`` with at least ``MIN_TERMINALS`` terminals), and
none of its children repeats more often (then the children are the better modules: a floor of six identical bays
instances the bay). Only *mesh* terminals count (walls, mouldings, cornices...): the stage places a module's
windows, doors and balconies with the building's own instancer (:mod:`citygen.geometry.lift`), so they are
instanced whether or not a module holds them.
"""
from __future__ import annotations

import functools
import itertools
import operator
import zlib
from collections import Counter
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np

from citygen.geometry.prototypes import INSTANCED
from citygen.layout import FacadeLayout, Region, unwalked

CM = 100.0
MIN_TERMINALS = 4
#: Mesh terminals a module must save. Its prototype costs about 30 specs in every layer that uses it (a prim, its
#: looks, its meshes) and a collection in Blender; 60 rather than 24 cut the demo's specs by a quarter for 4.5 %
#: more file (docs/performance.md).
MIN_SAVING = 60


@dataclass(frozen=True)
class ModuleKey:
    """A module prototype: signature, size in centimetres, and the building wall material it was built with."""

    signature: int
    w: int
    h: int
    wall: str

    @property
    def name(self) -> str:
        return f"module_{self.signature & 0xFFFFFFFFFFFF:012x}_{self.w}x{self.h}_{self.wall}"

    @property
    def size(self) -> tuple[float, float]:
        return self.w / CM, self.h / CM

    @property
    def label(self) -> str:
        return "module"


@functools.lru_cache(maxsize=4096)
def _code(text: str | None) -> int:
    return zlib.crc32((text or "").encode("utf-8"))


#: A region's signature, detail flag, mesh-terminal count and terminal count.
Info = tuple[int, bool, int, int]


class Signatures:
    """Signature, detail flag, mesh-terminal and terminal counts of the inner regions of a building's layouts, plus
    signature counts.

    Read from each layout's arrays (:attr:`FacadeLayout.inner`, :attr:`FacadeLayout.leaf_rects`,
    :attr:`FacadeLayout.leaf_sources`): the terminals' signatures and offsets come for a whole layout at once, then
    each listed inner region is hashed once, bottom-up, from its content laid out in one list (its size, then
    ``(signature, dx, dy)`` of each child: terminals known beforehand, inner children filled in as they are
    hashed). Regions carrying a generator's ``key`` hint (:class:`citygen.layout.Region`) are hashed once per key:
    later regions with the key (a moved copy stands for its subtree) reuse the first one's results, including the
    counts of everything inside it. The values are those of a walk of the region tree (``hash`` of the same int
    tuples, the same reuse).
    """

    def __init__(self, layouts: Iterable[FacadeLayout]) -> None:
        self.log: list[int] = []  # signature of every inner region hashed or reused
        #: key -> (first hashed region's info, its log part, its face and index)
        self._keyed: dict[int, tuple[Info, list[int], tuple[_Face, int]]] = {}
        layouts = list(layouts)
        self._forest = _Face.of(layouts)
        #: id(layout) -> its root's index in the forest and the position of its first terminal (None: no regions)
        self._roots = {id(layout): root for layout, root in zip(layouts, self._forest.roots)}
        if self._forest.regions:
            self._hash(self._forest)
        self.counts: Counter[int] = Counter(self.log)

    def _hash(self, f: _Face) -> Info:
        """Hash the listed regions of ``f`` (bottom-up, reusing keyed results); the root's info."""
        keyed, log, keys, content = self._keyed, self.log, f.keys, f.content
        # what each region takes, in tree order: hashed (1), the results of its key's first region (2), its own
        # tree walked (3: a moved copy whose original was not hashed), nothing (0: inside a region of case 2)
        take = [0] * len(keys)
        seen = set()
        k, n = 0, len(keys)
        while k < n:
            key = keys[k]
            if key is not None and (key in seen or key in keyed):
                take[k] = 2
                k = f.after[k]
                continue
            take[k] = 3 if f.original[k] >= 0 else 1
            seen.add(key)
            k += 1
        marks: list[int] = []  # log length before each region in post-order
        result = None
        for k, bounds, first in zip(f.post, f.bounds, f.first_post):
            marks.append(len(log))
            how = take[k]
            if how == 1:
                result = (hash(tuple(content[bounds[0]:bounds[1]])), *f.info[k])
                log.append(result[0])
                if keys[k] is not None:
                    keyed[keys[k]] = (result, log[marks[first]:], (f, k))
                f.info[k] = result
            elif how == 2:
                result, part, _ = keyed[keys[k]]
                log.extend(part)
            elif how == 3:
                result = self._hash(_Face.of([FacadeLayout(1.0, 1.0, f.regions[k])]))
            else:
                continue
            f.sig[k] = result[0]
            slot = f.slot[k]
            if slot >= 0:
                content[slot] = (result[0], f.dx[k], f.dy[k])
        return result

    def _module(self, f: _Face, k: int) -> bool:
        """Whether the hashed inner region ``k`` of ``f`` (and every copy of it) is a module (see the module doc)."""
        decided = f.modules[k]
        if decided is None:
            sig, detail, n, _ = f.info[k]
            c = self.counts[sig]
            decided = f.modules[k] = (
                c >= 2 and n >= MIN_TERMINALS and (c - 1) * n >= MIN_SAVING and detail
                and not any(self.counts[f.sig[tc]] > c for tc in f.kids[k]))
        return decided

    def split(self, layout: FacadeLayout) -> tuple[list[Module], np.ndarray]:
        """The face's ``(modules, loose terminals)``: its maximal repeated subtrees (:data:`Module`: signature,
        rectangle, the position of its first terminal among the face's terminals (tree order) and their count),
        and the positions of every terminal outside them (ascending: tree order).

        The walk visits listed inner regions only, reading the hashed region's results (``twin``) in parallel. A
        moved copy is walked through its original with the offset (``shifts``, applied innermost first: the same
        float additions as the copy's regions).
        """
        face, (root, base, size) = self._forest, self._roots[id(layout)]
        if root < 0:
            return [], np.zeros(1, np.intp)
        modules: list[Module] = []
        keyed = self._keyed
        stack: list[tuple[int, _Face, int, int, tuple[tuple[float, float], ...]]] = [(root, face, root, -base, ())]
        while stack:
            k, twin, tk, at, shifts = stack.pop()
            done = keyed.get(twin.keys[tk])
            if done is not None:
                twin, tk = done[2]
            decided = twin.modules[tk]
            if decided is None:
                decided = self._module(twin, tk)
            if decided:
                r = face.regions[k]
                x, y = r.x, r.y
                for dx, dy in reversed(shifts):
                    x, y = x + dx, y + dy
                modules.append((twin.sig[tk], x, y, r.w, r.h, face.rows[k][0] + at, twin.info[tk][3]))
                continue
            while face.original[k] >= 0:  # (a moved copy: its original's children, moved)
                o = face.original[k]
                shifts += (unwalked(face.regions[k])[1:],)
                at += face.rows[k][0] - face.rows[o][0]
                k = o
            stack.extend(zip(reversed(face.kids[k]), itertools.repeat(twin), reversed(twin.kids[tk]),
                             itertools.repeat(at), itertools.repeat(shifts)))
        loose = np.ones(size, dtype=bool)  # (then every module's terminals taken out)
        for *_, first, n in modules:
            loose[first:first + n] = False
        return modules, np.flatnonzero(loose)


#: A module found by :meth:`Signatures.split`: signature, x, y, w, h, position of its first terminal, their count.
Module = tuple[int, float, float, float, float, int, int]


@dataclass
class _Face:
    """One layout's listed inner regions (:class:`InnerTable`) ready to hash, as Python lists by index.

    ``content`` lays out every hashed region's tuple, one after the other: ``2, w, h`` (cm), then per child in
    order ``(signature, dx, dy)`` (offsets from the region in cm; an inner child's slot filled when it is hashed).
    Per region: key, original (-1: not a moved copy), index after its subtree, ``bounds`` of its content, ``slot``
    of its entry in its parent's (-1: the root), offset from its parent in cm, terminal range; ``post`` lists the
    regions in post-order and ``first_post`` the post-order position where each one's subtree starts. ``info``
    holds the detail flag, mesh-terminal and terminal counts until hashing makes it the region's :data:`Info`;
    ``sig`` and ``modules`` fill while hashing and splitting."""

    regions: tuple[Region, ...]
    keys: list[int | None]
    original: list[int]
    after: list[int]
    content: list[object]
    post: list[int]
    bounds: list[tuple[int, int]]
    first_post: list[int]
    slot: list[int]
    dx: list[int]
    dy: list[int]
    rows: list[list[int]]
    info: list[tuple]
    sig: list[int | None]
    modules: list[bool | None]
    parent: list[int]
    roots: list[tuple[int, int, int]]

    @functools.cached_property
    def kids(self) -> list[list[int]]:
        """The listed inner children of each region, in order."""
        kids: list[list[int]] = [[] for _ in self.regions]
        for k, p in enumerate(self.parent):
            if p >= 0:
                kids[p].append(k)
        return kids

    @classmethod
    def of(cls, layouts: Sequence[FacadeLayout]) -> _Face:
        """The listed regions of ``layouts`` as one forest (each layout's terminals after the previous ones');
        ``roots`` gives per layout its root's index (-1: a terminal root), first terminal and terminal count."""
        tables = [layout.inner for layout in layouts]
        regions = tuple(itertools.chain.from_iterable(t.regions for t in tables))
        n = len(regions)
        counts = [len(layout.leaf_rects) for layout in layouts]
        sizes = [len(t.regions) for t in tables]
        base = np.cumsum([0, *counts[:-1]]).tolist()
        starts = np.cumsum([0, *sizes[:-1]]).tolist()
        roots = [(at if size else -1, rows, count) for at, size, rows, count in zip(starts, sizes, base, counts)]
        if not n:
            return cls((), *([] for _ in range(15)), roots)
        looks = [[_LEAVES.get(look) or _leaf_of(look) for look in map(_LEAF, layout.leaf_sources[0])]
                 for layout in layouts]
        flat = itertools.chain.from_iterable(itertools.chain.from_iterable(looks))
        known = np.fromiter(flat, np.int64, 3 * sum(map(len, looks))).reshape(-1, 3)
        known_base = np.cumsum([0, *map(len, looks[:-1])])
        leaves = known[np.concatenate([layout.leaf_sources[1] + b for layout, b in zip(layouts, known_base)])]
        rects = np.concatenate([layout.leaf_rects for layout in layouts])
        box = np.fromiter(itertools.chain.from_iterable(map(_XYWH, regions)), float, 4 * n).reshape(n, 4)
        shift = np.repeat(starts, sizes)
        parent = np.concatenate([t.parent for t in tables])
        parent = np.where(parent >= 0, parent + shift, -1)
        original = np.concatenate([t.original for t in tables])
        original = np.where(original >= 0, original + shift, -1)
        rows = np.concatenate([t.rows for t in tables]) + np.repeat(base, sizes)[:, None]
        owner = np.concatenate([t.owner + s for t, s in zip(tables, starts)])
        first, end = rows.T
        nodes = np.arange(n)
        # the content: per region not a copy its size, then its terminal children and inner children by position
        kept = np.flatnonzero((owner >= 0) & (original[owner] < 0))  # (children of listed regions, not of copies)
        offset = np.rint((rects[kept, :2] - box[owner[kept], :2]) * CM).astype(np.int64)
        made = np.flatnonzero(original < 0)
        size = np.rint(box[made, 2:] * CM).astype(np.int64)
        header = np.column_stack([np.full(len(made), 2), size]).ravel().tolist()
        items = list(zip(leaves[kept, 0].tolist(), *offset.T.tolist()))
        inner = np.flatnonzero(parent >= 0)
        whose = np.concatenate([np.repeat(made, 3), owner[kept], parent[inner]])
        where = np.concatenate([np.tile([-3, -2, -1], len(made)), kept, first[inner]])
        order = np.lexsort((where, whose))
        content = list(operator.itemgetter(*order.tolist())([*header, *items, *([None] * len(inner))]))
        position = np.empty(len(order), np.intp)
        position[order] = np.arange(len(order))
        slot = np.full(n, -1, np.intp)
        slot[inner] = position[len(header) + len(items):]
        length = np.bincount(whose, minlength=n)
        bounds = np.cumsum(length)
        # post-order: by end, the deepest first; a subtree starts at its first listed descendants' last
        post = np.lexsort((-nodes, end))
        position = np.empty(n, np.intp)
        position[post] = nodes
        breaks = np.flatnonzero(np.append(parent[1:] != nodes[:-1], True))  # (no listed first child)
        first_post = position[breaks[np.searchsorted(breaks, nodes)]]
        up = np.rint((box[:, :2] - box[np.maximum(parent, 0), :2]) * CM).astype(np.int64)
        detail, mesh = np.concatenate([np.zeros((1, 2), np.int64), np.cumsum(leaves[:, 1:], axis=0)]).T
        info = list(zip((detail[end] > detail[first]).tolist(), (mesh[end] - mesh[first]).tolist(),
                        (end - first).tolist()))
        return cls(regions, [r.key for r in regions], original.tolist(),
                   np.searchsorted(first, end).tolist(), content, post.tolist(),
                   list(zip((bounds - length)[post].tolist(), bounds[post].tolist())), first_post[post].tolist(),
                   slot.tolist(), *up.T.tolist(), rows.tolist(), info, [None] * n, [None] * n, parent.tolist(), roots)


_XYWH = operator.attrgetter("x", "y", "w", "h")
#: The fields of a terminal its signature depends on.
_LEAF = operator.attrgetter("label", "material", "layer", "depth", "w", "h")
#: :func:`_leaf_of` by (label, material, layer, depth, w, h): a building's terminals come in a few dozen kinds.
_LEAVES: dict[tuple[str | None, str | None, str | None, float, float, float], tuple[int, int, int]] = {}
_LEAVES_SIZE = 1 << 16


def _leaf_of(look: tuple[str | None, str | None, str | None, float, float, float]) -> tuple[int, int, int]:
    """Signature, detail flag and mesh-terminal count (1, or 0 for an instanced element) of a terminal with the
    fields ``look`` (:data:`_LEAF`; remembered in ``_LEAVES``)."""
    if len(_LEAVES) >= _LEAVES_SIZE:
        _LEAVES.clear()
    label, material, layer, depth, w, h = look
    result = _LEAVES[look] = (
        hash((1, _code(label), _code(material), _code(layer), round(depth * CM), round(w * CM), round(h * CM))),
        int((label != "wall" and label is not None) or depth != 0.0), int(label is not None and label not in INSTANCED))
    return result
