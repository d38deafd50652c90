"""The element library of a stage with tile layers: ``<stem>_tiles/elements.usdc``, every element prototype (window,
door, sill, balcony kinds) the city's tiles use, once, with the materials and look sets they bind. A tile layer's
instances of an element reference it (``@./elements.usdc@</Prototypes/<element>>``), so a tile still opens alone
(beside the library) and a building referenced from a tile brings its elements along; the city's elements are
authored and stored once instead of once per tile (the Helsinki demo's tiles held 1,918 element prototypes of 688
kinds), and the instances of an element in every tile share one USD prototype, which an importer converts once
(Blender makes a material of each material of each prototype it imports).

The library's name is fixed, so its publication keeps :mod:`citygen.usd.publish`'s promise (the current root always
composes whole) in two steps: before the new root replaces the old one, the published library holds the union of
both runs' elements (:func:`publish_library`); after, only the new run's (:func:`settle_library`). Same scene and
seed, same library bytes. Two runs writing the same output at the same time may leave one root missing elements
the other run's library settled away: run them one after the other.
"""
from __future__ import annotations

import os
from collections.abc import Iterable, Mapping
from pathlib import Path

from pxr import Sdf, Tf

from citygen.geometry.prototypes import ProtoKey
from citygen.temporaries import temp_prefix
from citygen.usd.author import Author
from citygen.usd.definitions import PROTOTYPES, Definitions, elements, prepare_elements
from citygen.usd.materials import Material
from citygen.usd.publish import export_layer, write_layer

STEM = "elements"


def library_name(suffix: str) -> str:
    """The element library's file name for tile layers of extension ``suffix``."""
    return f"{STEM}{suffix}"


def write_library(path: Path, keys: Iterable[ProtoKey], materials: Mapping[str, Material], uvs: bool,
                  up_axis: str) -> int:
    """Write the element library of ``keys`` (in name order) to ``path``; return the number of prims."""
    layer = Sdf.Layer.CreateAnonymous(path.suffix)  # (crate data for a .usdc: see StageWriter)
    author = Author(layer, uvs, materials, path.parent)
    definitions = Definitions(author)
    store = elements(materials, uvs)
    keys = sorted(set(keys), key=lambda k: k.name)
    prepare_elements(keys, store, materials)
    with Sdf.ChangeBlock():
        layer.defaultPrim = PROTOTYPES.name
        layer.pseudoRoot.SetInfo("metersPerUnit", 1.0)
        layer.pseudoRoot.SetInfo("upAxis", up_axis)
    definitions.pending = [(PROTOTYPES.AppendChild(Tf.MakeValidIdentifier(k.name)), store[k]) for k in keys]
    definitions.author_pending()
    export_layer(layer, path)
    return author.prims


def publish_library(staged: Path, tiles_dir: Path) -> Path | None:
    """Publish the run's library ``staged`` into ``tiles_dir`` before the root is replaced. Where the library
    there holds prototypes this one lacks (the current root's tiles may use them), the union is published and this
    run's own library kept as a temporary in ``tiles_dir``, returned for :func:`settle_library`."""
    target = tiles_dir / staged.name
    extra = _missing(target, staged)
    if not extra:
        os.replace(staged, target)
        return None
    union = Sdf.Layer.OpenAsAnonymous(str(staged))
    old = Sdf.Layer.OpenAsAnonymous(str(target))
    for path in extra:
        Sdf.CopySpec(old, path, union, path)  # (a transient layer: its field order need not be reproducible)
    write_layer(union, target)
    own = tiles_dir / f"{temp_prefix(staged.name)}own{staged.suffix}"
    os.replace(staged, own)
    return own


def settle_library(own: Path | None, target: Path) -> None:
    """After the root was replaced: the library ``target`` holds only the new run's elements (``own``, from
    :func:`publish_library`)."""
    if own is not None:
        os.replace(own, target)


def _missing(target: Path, staged: Path) -> list[Sdf.Path]:
    """The prototypes, look sets and materials of the library ``target`` (if any) that ``staged`` lacks."""
    if not target.is_file():
        return []
    old = Sdf.Layer.OpenAsAnonymous(str(target))
    new = Sdf.Layer.OpenAsAnonymous(str(staged))
    if old is None or new is None:
        return []
    extra = []
    for root in ("Materials", "Looks", PROTOTYPES.name):
        spec = old.GetPrimAtPath(f"/{root}")
        if spec is None:
            continue
        if new.GetPrimAtPath(f"/{root}") is None:
            extra.append(spec.path)
            continue
        extra += [child.path for child in spec.nameChildren if new.GetPrimAtPath(child.path) is None]
    return extra

