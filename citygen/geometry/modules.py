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
import zlib
from collections import Counter
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from citygen.geometry.prototypes import INSTANCED
from citygen.layout import Region, is_inner, unwalked

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
#: :func:`_leaf_of` by (label, material, layer, depth, w, h): a building's terminals come in a few dozen kinds.
_LEAVES: dict[tuple[str | None, str | None, str | None, float, float, float], Info] = {}
_LEAVES_SIZE = 1 << 16
#: By (label, material, layer, depth): the head of a terminal's signature tuple (all but its size), its detail flag
#: and mesh-terminal count. A city's terminals come in a few looks but many sizes (a repeat stretches its tiles to
#: each face's width).
_LOOKS: dict[tuple[str | None, str | None, str | None, float], tuple[tuple[int, ...], bool, int]] = {}


def _leaf_of(r: Region) -> Info:
    """Signature, detail flag, mesh-terminal count (1, or 0 for an instanced element) and terminal count (1) of a
    terminal region (remembered in ``_LEAVES``)."""
    if len(_LEAVES) >= _LEAVES_SIZE:
        _LEAVES.clear()
    look = _LOOKS.get((r.label, r.material, r.layer, r.depth))
    if look is None:
        if len(_LOOKS) >= _LEAVES_SIZE:
            _LOOKS.clear()
        look = _LOOKS[r.label, r.material, r.layer, r.depth] = (
            (1, _code(r.label), _code(r.material), _code(r.layer), round(r.depth * CM)),
            (r.label != "wall" and r.label is not None) or r.depth != 0.0,
            int(r.label is not None and r.label not in INSTANCED))
    head, detail, mesh = look
    result = _LEAVES[r.label, r.material, r.layer, r.depth, r.w, r.h] = (
        hash((*head, round(r.w * CM), round(r.h * CM))), detail, mesh, 1)
    return result


class Signatures:
    """Signature, detail flag, mesh-terminal and terminal counts of the inner regions of some layouts, plus
    signature counts.

    Each subtree is hashed once, bottom-up, in one walk (terminals and keyed copies inline). Regions
    carrying a generator's ``key`` hint (:class:`citygen.layout.Region`) are hashed once per key: later copies
    reuse the first one's results, including the counts of everything inside it.
    """

    def __init__(self, roots: Iterable[Region]) -> None:
        self.info: dict[int, Info] = {}
        self.log: list[int] = []  # signature of every inner region visited or reused, in order
        self.first: dict[int, Region] = {}
        self._keyed: dict[int, tuple[Info, list[int]]] = {}  # key -> first copy's info, log part
        #: id of a hashed inner region -> (index, position of its first terminal among the region's, the copy
        #: hashed in its place: itself or the first of its key) of each of its inner children, last first (the order
        #: :meth:`split` stacks them)
        self._inner: dict[int, list[tuple[int, int, Region]]] = {}
        for root in roots:
            key = root.key
            done = self._keyed.get(key)
            if done is not None:
                self.log.extend(done[1])
            elif root.children:
                self._visit(root)
            elif key is not None:
                self.first[key], self.info[id(root)] = root, _leaf_of(root)
                self._keyed[key] = (self.info[id(root)], [])
        self.counts: Counter[int] = Counter(self.log)
        self._modules, self._walk = self._decide()

    def _visit(self, r: Region) -> Info:
        """Hash the inner region ``r`` (not a copy of a keyed region already hashed) and everything below it."""
        keyed, info, log, first = self._keyed, self.info, self.log, self.first
        x, y = r.x, r.y
        start = len(log)
        content: list[object] = [2, round(r.w * CM), round(r.h * CM)]
        append = content.append
        detail, terminals, leaves = False, 0, 0
        inner: list[tuple[int, int, Region]] = []  # (index, first terminal's position, hashed copy) per inner child
        for c in r.children:
            key = c.key
            done = keyed.get(key)  # (None is never a key of it)
            if done is not None:
                result, below = done
                if below:  # (an inner region logs its own signature at least; a terminal nothing)
                    log.extend(below)
                    inner.append((len(content) - 3, leaves, first[key]))
            elif c.children:
                inner.append((len(content) - 3, leaves, c))
                result = self._visit(c)
            else:
                result = _LEAVES.get((c.label, c.material, c.layer, c.depth, c.w, c.h)) or _leaf_of(c)
                if key is not None:  # (a terminal is never canonical: only its results are reused)
                    keyed[key] = (result, [])
            sig, more, n, k = result
            append((sig, round((c.x - x) * CM), round((c.y - y) * CM)))
            if more:
                detail = True
            terminals += n
            leaves += k
        result = (hash(tuple(content)), detail, terminals, leaves)
        log.append(result[0])
        key = r.key
        if key is not None:
            first[key], keyed[key] = r, (result, log[start:])
        info[id(r)] = result
        inner.reverse()  # (the order :meth:`split` stacks them)
        self._inner[id(r)] = inner
        return result

    def canonical(self, r: Region) -> Region:
        """The copy of ``r`` whose whole subtree was hashed (itself unless it repeats a keyed subtree)."""
        return self.first.get(r.key, r) if r.key is not None else r

    def signature(self, r: Region) -> int:
        """The signature of the inner region ``r``."""
        return self.info[id(self.canonical(r))][0]

    def _decide(self) -> tuple[dict[int, bool], dict[int, list[tuple[int, int, Region]]]]:
        """Per hashed inner region (by id; every copy of it alike): whether it is a module (see the module doc), and
        which of its inner children :meth:`split` must walk into (those that are or hold modules; the rest hold
        loose terminals only)."""
        counts, info, inner = self.counts, self.info, self._inner
        module: dict[int, bool] = {}
        walk: dict[int, list[tuple[int, int, Region]]] = {}
        for hashed, (sig, detail, n, _) in info.items():  # (a region's inner children are hashed before it)
            entries = inner.get(hashed, [])  # (none for a terminal root)
            c = counts[sig]
            module[hashed] = (c >= 2 and n >= MIN_TERMINALS and (c - 1) * n >= MIN_SAVING and detail
                              and not any(counts[info[id(tc)][0]] > c for _, _, tc in entries))
            walk[hashed] = [e for e in entries if module[id(e[2])] or walk[id(e[2])]] if entries else entries
        return module, walk

    def split(self, root: Region) -> tuple[list[tuple[Region, int, int]], np.ndarray]:
        """The face's ``(modules, loose terminals)``: its maximal repeated subtrees, each with the position of its
        first terminal among the face's terminals (tree order) and their count, and the positions of every
        terminal outside them (ascending: tree order).

        The walk visits the inner regions on the way to modules only. Inside a keyed copy it reads the hashed copy's
        results in parallel (``twin``). A lazily moved copy (:meth:`Region.moved`) is walked through its original with the offset
        (``shift``): only the modules found inside it are made as regions.
        """
        if not is_inner(root):
            return [], np.zeros(1, np.intp)
        modules: list[tuple[Region, int, int]] = []
        stack: list[tuple[Region, tuple[float, float] | None, Region, int]] = [(root, None, self.canonical(root), 0)]
        module, info, walk = self._modules, self.info, self._walk
        pop, push = stack.pop, stack.extend
        while stack:
            r, shift, twin, at = pop()
            hashed = id(twin)
            if module[hashed]:
                modules.append((r if shift is None else r.moved(*shift), at, info[hashed][3]))
                continue
            if shift is None:
                lazy = unwalked(r)
                if lazy is not None:
                    r, shift = lazy[0], lazy[1:]
            children = r.children
            push([(children[i], shift, tc, at + offset) for i, offset, tc in walk[hashed]])
        loose = np.ones(info[id(self.canonical(root))][3], dtype=bool)  # (then every module's terminals taken out)
        for _, at, n in modules:
            loose[at:at + n] = False
        return modules, np.flatnonzero(loose)
