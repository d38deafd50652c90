"""What a layer defines once for all its buildings: ``/Materials`` (each material once) and ``/Prototypes`` (each
element kind or module once, authored in batches), and the element prototypes a process prepares for every layer
it writes.

A layer with an element library (a tile layer, see :mod:`citygen.usd.library`) does not hold its element
prototypes: its instances reference the library's (:class:`~citygen.usd.writer.StageWriter`), so the elements of a
city are authored once, not once per tile.
"""
from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass

import numpy as np
from pxr import Sdf

from citygen.geometry.building import MeshData
from citygen.geometry.prototypes import ProtoKey, build_prototype
from citygen.usd.author import Author, MeshArrays, T, tokens
from citygen.usd.bounds import points_bound
from citygen.usd.materials import Material
from citygen.usd.normals import face_normals

PROTOTYPES = Sdf.Path("/Prototypes")


@dataclass
class Prototype:
    """A prototype's meshes, bound and, once a layer authors it, its meshes' :class:`MeshArrays` (prepared in one
    normals batch with the layer's other new prototypes). An element prototype's are a function of its key, the
    material library and ``uvs`` alone, kept for every writer of the process with those (:func:`elements`): tile
    writers would otherwise prepare the same elements again in every tile."""

    label: str
    meshes: list[tuple[str, str, str | None, MeshData]]  # prim name, material, semantic label, mesh
    bound: np.ndarray | None
    arrays: list[MeshArrays] | None = None


#: Element prototypes kept per material library and ``uvs`` (at most this many in all; then the memory starts over).
ELEMENTS_KEPT = 8192
_ELEMENTS: dict[tuple, dict[ProtoKey, Prototype]] = {}


def elements(library: Mapping[str, Material], uvs: bool) -> dict[ProtoKey, Prototype]:
    """This process's prepared element prototypes for ``library`` and ``uvs``."""
    if sum(map(len, _ELEMENTS.values())) > ELEMENTS_KEPT:
        _ELEMENTS.clear()
    return _ELEMENTS.setdefault((tuple(sorted(library.items())), uvs), {})


def prepare_elements(keys: Iterable[ProtoKey], into: dict[ProtoKey, Prototype],
                     library: Mapping[str, Material]) -> None:
    """The :class:`Prototype` of each element kind in ``keys`` not yet ``into`` it: their parts welded in one
    batch."""
    keys = [k for k in dict.fromkeys(keys) if k not in into]
    if not keys:
        return
    parts = [[p for p in build_prototype(key, library) if len(p.quads)] for key in keys]
    welded = iter(MeshData.many_from_quads([p.quads for ps in parts for p in ps]))
    for key, ps in zip(keys, parts):
        meshes = [(p.name, p.material, None, next(welded)) for p in ps]
        into[key] = Prototype(key.label, meshes, meshes_bound([m for *_, m in meshes]))


def prepare_arrays(protos: Iterable[Prototype], author: Author) -> None:
    """The :class:`MeshArrays` of each of ``protos`` that has none yet, their face normals in one batch (``author``:
    any of a writer with the layer's ``uvs`` and materials; the arrays do not depend on the layer)."""
    fresh = [p for p in protos if p.arrays is None]
    kept = [[(m, mat) for _, mat, _, m in p.meshes if len(m.counts)] for p in fresh]
    prepared = iter(author.arrays([m for ms in kept for m in ms], face_normals([m for ms in kept for m, _ in ms])))
    for p, ms in zip(fresh, kept):
        p.arrays = [next(prepared) for _ in ms]


def meshes_bound(meshes: list[MeshData]) -> np.ndarray | None:
    """The bound of the points of ``meshes``."""
    return points_bound(np.concatenate([m.points for m in meshes])) if meshes else None


class Definitions:
    """A layer's ``/Materials`` and ``/Prototypes``."""

    def __init__(self, author: Author) -> None:
        self.author = author
        self.defined: set[str] = set()
        self.materials_root: Sdf.PrimSpec | None = None
        self.protos_root: Sdf.PrimSpec | None = None
        self.pending: list[tuple[Sdf.Path, Prototype]] = []  # prototypes to author, in order of first use

    def define(self, names: Iterable[str]) -> None:
        """``/Materials/<name>`` of each name not yet defined in this layer."""
        for name in names:
            if name not in self.defined:
                if self.materials_root is None:
                    self.materials_root = self.author.prim(self.author.layer, "Materials", "Scope",
                                                           Sdf.SpecifierClass)
                self.author.material(self.materials_root, name)
                self.defined.add(name)

    def author_pending(self) -> None:
        """Author the prototypes added to :attr:`pending` since the last call (the arrays of those new to the
        process prepared first, all in one batch)."""
        if not self.pending:
            return
        author = self.author
        if self.protos_root is None:
            self.protos_root = author.prim(author.layer, PROTOTYPES.name, "", Sdf.SpecifierClass)
        prepare_arrays([p for _, p in self.pending], author)
        with Sdf.ChangeBlock():
            for path, p in self.pending:
                proto = author.prim(self.protos_root, path.name, "Xform")
                author.api(proto, "SemanticsLabelsAPI:class")
                author.attr(proto, "semantics:labels:class", T.TokenArray, tokens(p.label), uniform=True)
                used = sorted({mat for _, mat, _, _ in p.meshes})
                self.define(used)
                looks = author.looks(proto, used) if used else None
                arrays = iter(p.arrays or ())
                for name, mat, label, mesh in p.meshes:
                    if len(mesh.counts):
                        author.mesh(proto, name, next(arrays), looks, mat, label)
        self.pending = []
