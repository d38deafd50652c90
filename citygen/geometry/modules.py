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
instances the bay).
"""
from __future__ import annotations

import functools
import zlib
from collections import Counter
from collections.abc import Iterable
from dataclasses import dataclass

from citygen.layout import Region

CM = 100.0
MIN_TERMINALS = 4
MIN_SAVING = 24


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


class Signatures:
    """Signature and detail flag of every region of some layouts (keyed by ``id(region)``)."""

    def __init__(self, roots: Iterable[Region]) -> None:
        self.sig: dict[int, int] = {}
        self.detail: dict[int, bool] = {}
        self.size: dict[int, int] = {}
        self.counts: Counter[int] = Counter()
        for root in roots:
            self._visit(root)

    def _visit(self, r: Region) -> int:
        children = r.children
        if not children:
            s = hash((1, _code(r.label), _code(r.material), _code(r.layer), round(r.depth * CM), round(r.w * CM),
                      round(r.h * CM)))
            self.detail[id(r)] = (r.label != "wall" and r.label is not None) or r.depth != 0.0
            self.size[id(r)] = 1
        else:
            x, y, visit = r.x, r.y, self._visit
            s = hash((2, round(r.w * CM), round(r.h * CM),
                      *[(visit(c), round((c.x - x) * CM), round((c.y - y) * CM)) for c in children]))
            detail = self.detail
            detail[id(r)] = any([detail[id(c)] for c in children])
            self.size[id(r)] = sum([self.size[id(c)] for c in children])
            self.counts[s] += 1
        self.sig[id(r)] = s
        return s

    def split(self, root: Region) -> tuple[list[Region], list[Region]]:
        """The face's ``(modules, loose terminals)``: maximal repeated subtrees, and every terminal outside them."""
        modules: list[Region] = []
        loose: list[Region] = []
        stack = [root]
        while stack:
            r = stack.pop()
            if not r.children:
                loose.append(r)
                continue
            c, n = self.counts[self.sig[id(r)]], self.size[id(r)]
            if (c >= 2 and n >= MIN_TERMINALS and (c - 1) * n >= MIN_SAVING and self.detail[id(r)]
                    and not any(ch.children and self.counts[self.sig[id(ch)]] > c for ch in r.children)):
                modules.append(r)
            else:
                stack.extend(reversed(r.children))
        return modules, loose
