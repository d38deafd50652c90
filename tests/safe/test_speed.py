"""The preview-speed changes keep results: remembered decomposition trees and the directly assembled KKT matrix."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import scipy.sparse as sp

from citygen_safe import tree
from citygen_safe.leaves import facade_from_layout
from citygen_safe.optimise import KKT_REG, kkt_matrix
from citygen_safe.tree import decompose



def _shape(node):
    return node.x, node.y, node.w, node.h, node.split, node.leaves, tuple(_shape(c) for c in node.children)


def test_remembered_tree_is_the_tree_of_equal_rectangles(cmp_facade):
    tree.TREES.clear()
    first = decompose(cmp_facade)
    relabelled = replace(cmp_facade, leaves=tuple(replace(f, region=replace(f.region, label="wall"))
                                                  for f in cmp_facade.leaves))
    assert decompose(relabelled) is first  # the tree depends on the rectangles only
    tree.TREES.clear()
    assert _shape(decompose(cmp_facade)) == _shape(first)
    assert first.split == "y" and sorted(first.leaves) == list(range(len(cmp_facade.leaves)))


def test_memory_is_bounded_by_cost_first_in_first_out():
    from citygen_safe.memory import Memory

    memory = Memory(12)
    for key in "abcd":
        memory.remember(key, key.upper(), 3)
    memory.remember("e", "E", 3)
    assert "a" not in memory and memory.lookup("e") == "E" and len(memory) == 4
    memory.remember("huge", "H", 4)  # more than a quarter of the capacity: one use would push out the rest
    assert "huge" not in memory and len(memory) == 4
    assert memory.get("b", lambda: "other", len) == "B" and memory.get("f", lambda: "FF", len) == "FF"
    assert "b" not in memory and "c" in memory  # FF costs 2: the oldest, b (3), went to make room


def test_kkt_matrix_equals_the_block_assembly():
    """Regression: the KKT matrix was built by ``sp.bmat``, which cost as much as its factorisation; the direct
    assembly must give the same canonical arrays (unsorted rows and explicit zeros included) so the LU, and so
    every layout, is unchanged to the bit."""
    P = np.array([2.0, 0.5, 8.0, 1.0])
    rows = [{2: 1.0, 0: -1.0}, {1: 0.0, 3: 2.5}, {3: 1.0, 0: 1.0, 2: -0.25}]
    data = [a for r in rows for a in r.values()]
    cols = [k for r in rows for k in r]
    A = sp.csr_matrix((data, cols, [0, 2, 4, 7]), shape=(3, 4))
    ref = sp.bmat([[sp.diags(P + KKT_REG), A.T], [A, -KKT_REG * sp.identity(3)]], format="csc")
    new = kkt_matrix(P, A)
    assert new.has_canonical_format and new.shape == (7, 7)
    for field in ("indptr", "indices", "data"):
        assert np.array_equal(getattr(new, field), getattr(ref, field)), field


def test_floors_are_remembered_for_an_equal_ruleset_text(monkeypatch):
    """A ruleset text edited in the studio (a comment added) parses to an equal facade: its floors are the
    remembered ones, charged at the work they took; a changed switch computes them again."""
    from citygen.request import FacadeRequest
    from citygen_safe import generate
    from citygen_safe.ruleset import parse_ruleset

    from .conftest import ROOT

    path = ROOT / "rulesets" / "cmp_b0035.safe"
    text = path.read_text(encoding="utf-8")
    calls = []
    real = generate.fit_floors
    monkeypatch.setattr(generate, "fit_floors", lambda *a, **k: calls.append(1) or real(*a, **k))
    generate.FLOORS.clear()
    request = FacadeRequest.preview(20.0, 15.0, 3.3)
    first = generate.edit(parse_ruleset(text, str(path), base=path.parent), request)
    again = generate.edit(parse_ruleset(text + "\n# edited\n", str(path), base=path.parent), request)
    assert len(calls) == 1
    assert again.layout.dumps() == first.layout.dumps() and again.work == first.work
    generate.edit(parse_ruleset(text.replace("symmetry on", "symmetry off"), str(path), base=path.parent), request)
    assert len(calls) == 2


def test_jumps_and_merges_are_remembered_by_value(cmp_facade):
    """An equal facade (another parse of the same layout) finds the remembered jump and merge; a facade that
    differs only in a label does not, and its result carries its own label."""
    from citygen.layout import FacadeLayout
    from citygen_safe.jump import JUMPS, MERGED, insert_slab, merge_leaves

    from .conftest import ROOT

    fixed = frozenset({"window", "door"})
    JUMPS.clear()
    MERGED.clear()
    jumped = insert_slab(cmp_facade, (5.0, 6.0), (6.0, 8.0))
    merged, root = merge_leaves(jumped, fixed)
    again = facade_from_layout(FacadeLayout.loads((ROOT / "rulesets" / "cmp_b0035.layout.json").read_text()))
    assert again is not cmp_facade and insert_slab(again, (5.0, 6.0), (6.0, 8.0)) is jumped
    assert merge_leaves(jumped, fixed)[0] is merged and sorted(root.leaves) == list(range(len(merged.leaves)))
    first = cmp_facade.leaves[0]
    other = replace(cmp_facade, leaves=(replace(first, region=replace(first.region, label="deco")),
                                        *cmp_facade.leaves[1:]))
    moved = insert_slab(other, (5.0, 6.0), (6.0, 8.0))
    assert moved is not jumped and moved != jumped
    assert {f.label for f in moved.leaves if f.origin == first.origin} == {"deco"}
    from citygen_safe.generate import FLOORS
    from citygen_safe.memory import forget

    forget()
    assert len(JUMPS) == len(MERGED) == len(tree.TREES) == len(FLOORS) == 0


def test_prepared_problem_is_reused_across_targets_with_the_same_results(cmp_facade):
    """The target-independent part of Eq. 1 is prepared once per facade and tree; sizing at another target with
    it gives exactly what a fresh preparation gives (corner strips included: their rows' sides use the target)."""
    from citygen_safe.grids import auto_specs, detect_grid
    from citygen_safe.optimise import PROBLEMS, optimise_widths

    root = decompose(cmp_facade)
    grids = [g for g in (detect_grid(cmp_facade, s) for s in auto_specs(cmp_facade)) if g]
    corner = {"corners": (0.5, 0.5), "corner_labels": frozenset({"window", "door"})}
    PROBLEMS.clear()
    first = optimise_widths(cmp_facade, root, grids, 18.0, **corner)
    assert len(PROBLEMS) == 1
    again = optimise_widths(cmp_facade, root, grids, 21.0, **corner)
    assert len(PROBLEMS) == 1
    PROBLEMS.clear()
    fresh = optimise_widths(cmp_facade, root, grids, 21.0, **corner)
    assert first.success and again.success and again.facade.width == 21.0
    assert (again.objective, again.facade.leaves, again.dropped) == (fresh.objective, fresh.facade.leaves, fresh.dropped)
    assert min(f.x for f in again.facade.leaves if f.label == "window") >= 0.5 - 1e-6
