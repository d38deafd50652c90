"""The shipped grammars derive bit for bit what they derived before the derivation was made faster (issue 24): the
stage's bytes depend on every coordinate, so a faster derivation must do the same floating-point arithmetic."""
from __future__ import annotations

import hashlib
import json

import numpy as np
import pytest

from citygen.request import FaceContext, FacadeRequest
from citygen_split import load
from citygen_split.alternatives import derive_plausible
from citygen_split.derive import _Derivation

from .conftest import REPO

#: A Helsinki demo building's floor lines (a 4.2 m ground floor, four 3.0 m storeys).
LINES = (0.0, 4.220531614362382, 7.22360218612023, 10.226672757878077, 13.229743329635927, 16.232813901393776)

#: The width of the cases whose face carries the entrance.
ENTRANCE_WIDTH = 18.476058724158932

#: sha256 (first 16 hex digits) of the region tree's JSON, as derived by the code before issue 24's changes. The
#: apartment grammar's were renewed when storeys of equal height began to share their floor-invariant subtrees
#: (4 Dec 2026): a storey's copy sits within a bit of a fresh derivation
#: (:func:`test_cached_subtrees_are_fresh_derivations_to_the_last_bit`).
#: The visual audit (4 Dec 2026 night, docs/performance.md) renewed those of the grammars whose rules it changed.
DIGESTS = {
    ("apartment", 18.476058724158932): "e52068a789ed9f0b", ("apartment", 7.3130512): "71ab5c6e50a2b1be",
    ("apartment", 41.92): "30e6faaa1be70d01", ("historic", 18.476058724158932): "f7b59ddcc6780d79",
    ("historic", 7.3130512): "8d8eefb60f7c84f8", ("historic", 41.92): "ad647af2a6f5f694",
    ("house", 18.476058724158932): "5b9dc32d00668d34", ("house", 7.3130512): "28bc6bbbc048d07a",
    ("house", 41.92): "11af87f83280b544", ("office", 18.476058724158932): "a9bd977af0bd80f6",
    ("office", 7.3130512): "79e1191442945f85", ("office", 41.92): "bb8033ad8c948ed2",
    ("cmp_b0002", 18.476058724158932): "5021e98ca4e59afc", ("cmp_b0002", 7.3130512): "257579b22a381348",
    ("cmp_b0002", 41.92): "0b63ea259954c31e",
}


@pytest.mark.parametrize("name, width", sorted(DIGESTS))
def test_regression_shipped_grammars_derive_the_same_coordinates_bit_for_bit(name, width):
    request = FacadeRequest(width=width, height=LINES[-1], floor_lines=LINES, entrance=width == ENTRANCE_WIDTH,
                            corner_widths=(0.5, 0.37), context=FaceContext("way/1", 0, 5, street_facing=True),
                            seed=(2026, "way/1", 0))
    layout = derive_plausible(load(REPO / "rulesets" / f"{name}.grammar"), request).layout
    text = json.dumps(layout.root.to_json(), sort_keys=True)
    assert hashlib.sha256(text.encode()).hexdigest()[:16] == DIGESTS[name, width]


def _flat(region, out):
    out.append((region.symbol, region.label, region.material, region.x, region.y, region.w, region.h))
    for child in region.children:
        _flat(child, out)
    return out


@pytest.mark.parametrize("name", ["apartment", "historic", "house", "office", "cmp_b0002"])
@pytest.mark.parametrize("width", [7.3130512, 18.476058724158932, 41.92])
def test_cached_subtrees_are_fresh_derivations_to_the_last_bit(name, width):
    """A derivation copies the subtree of a symbol, size and floor derived before (across storeys of equal height
    when no condition below it reads ``floor``); the copy is the tree a fresh derivation (the tracing one, which
    caches nothing) makes, each coordinate within one rounding of it."""
    lines = (0.0, 4.25, 7.25, 10.25, 13.25, 16.25)  # (equal storeys: every upper floor is a copy)
    request = FacadeRequest(width=width, height=lines[-1], floor_lines=lines, entrance=width == ENTRANCE_WIDTH,
                            corner_widths=(0.5, 0.37), context=FaceContext("way/1", 0, 5, street_facing=True),
                            seed=(2026, "way/1", 0))
    grammar = load(REPO / "rulesets" / f"{name}.grammar")
    cached, fresh = (_flat(_Derivation(grammar, request, trace=trace).run().root, []) for trace in (False, True))
    assert [r[:3] for r in cached] == [r[:3] for r in fresh]
    got, want = (np.array([r[3:] for r in rows]) for rows in (cached, fresh))
    assert np.abs(got - want).max() <= 2 * np.spacing(np.abs(want).max())  # (a rounding or two at the face's size)
