"""The fast paths of grammar search give what the full candidate lists give."""
from pathlib import Path

import numpy as np
import pytest

from citygen_inverse.actions import CostModel, _repeated_runs, region_actions
from citygen_inverse.cmp import import_cmp
from citygen_inverse.regions import LayoutIndex
from citygen_inverse.search import GrammarSearch

from .helpers import random_layout

DATA = Path(__file__).resolve().parents[1] / "data" / "inverse"


def _layouts():
    yield from (import_cmp(f) for f in sorted(DATA.glob("*.xml"))[:2])
    yield from (random_layout(np.random.default_rng(s), depth=5) for s in range(6))


@pytest.mark.parametrize("model", [CostModel(), CostModel(split=0.5, repeat=0.1, lambda2=3.0)])
def test_best_only_candidates_are_the_first_least_heuristic_of_the_full_list(model):
    for layout, periodic in ((layout, periodic) for layout in _layouts() for periodic in (False, True)):
        index = LayoutIndex([layout], periodic=periodic)
        search = GrammarSearch(index, model)
        search.run("adp", 30, seed=3)  # visits many regions
        for sig in list(search._actions):
            full = region_actions(index, sig, search.sym, model)
            best = region_actions(index, sig, search.sym, model, best_only=True)
            assert len(best) == 1
            greedy = int(np.argmin(full.heuristic)) if full.greedy is None else full.greedy  # (grids: the finest)
            assert best[0] == full[greedy] and best.greedy in (None, 0)
            assert all(full.kids(k) == tuple(c for c, _ in full[k].children) for k in range(len(full)))


def test_search_run_again_with_another_method_matches_a_fresh_search():
    layout = random_layout(np.random.default_rng(7), depth=5)
    reused = GrammarSearch(LayoutIndex([layout], periodic=True))
    greedy = reused.run("greedy")
    again = reused.run("adp", 200, seed=1)
    fresh = GrammarSearch(LayoutIndex([layout], periodic=True)).run("adp", 200, seed=1)
    assert again.rules == fresh.rules and again.cost == fresh.cost and again.history == fresh.history
    assert greedy.cost >= fresh.cost


def _repeats_apart(atoms, length) -> bool:
    """Some substring of ``length`` atoms occurs twice without overlapping (by definition)."""
    return any(atoms[i:i + length] == atoms[j:j + length]
               for i in range(len(atoms)) for j in range(i + length, len(atoms) - length + 1))


def test_repeated_runs_stop_early_without_losing_a_grouping():
    """``_repeated_runs`` stops at the first length without a repeat: no longer substring repeats either (its
    prefix would), so every grouping of the longer lengths would be empty anyway."""
    rng = np.random.default_rng(0)
    for _ in range(400):
        m, kinds = int(rng.integers(2, 24)), int(rng.integers(1, 5))
        atoms = [(int(a), 1) for a in rng.integers(0, kinds, m)]
        apart = [_repeats_apart(atoms, length) for length in range(2, m // 2 + 1)]
        assert apart == sorted(apart, reverse=True)  # True ... True False ... False
        assert bool(_repeated_runs(atoms)) == any(apart)


@pytest.mark.parametrize("model", [CostModel(), CostModel(split=0.5, repeat=0.1, lambda2=3.0)])
def test_greedy_visiting_groupings_by_bound_costs_what_the_full_candidate_lists_cost(model):
    """A greedy run looks up the pieces of a grouping only when its bound on H can still win (its pieces are
    looked up in another order, so other boxes represent signatures): the grammar costs what the first of least
    H over every region's full candidate list costs, with the lookups in the order of the full lists."""
    for layout in _layouts():
        greedy = GrammarSearch(LayoutIndex([layout], periodic=True), model).run("greedy")
        full = GrammarSearch(LayoutIndex([layout], periodic=True), model)
        assert greedy.cost == full.iterate(full._greedy, 0)[1]


@pytest.mark.parametrize("name, cost", [("cmp_b0002", 171.4999999999999), ("cmp_b0005", 162.0999999999999),
                                        ("cmp_b0009", 154.49999999999994), ("cmp_b0012", 131.89999999999995)])
def test_greedy_cost_on_cmp_fixtures_is_unchanged_by_the_bounded_candidates(name, cost):
    """Greedy costs before the bounded visit of groupings (main de25bf3), to the last bit."""
    assert GrammarSearch(LayoutIndex([import_cmp(DATA / f"{name}.xml")], periodic=True)).run("greedy").cost == cost


def test_repeated_runs_match_their_definition():
    """Per length (while any repeats), per distinct substring in order of first occurrence, the occurrences
    taken left to right without overlap; two or more give the grouping without their inner boundaries, ranked
    by (length - 1)(count - 1), the first 16."""
    rng = np.random.default_rng(1)
    for _ in range(300):
        m = int(rng.integers(1, 30))
        atoms = [(int(a), int(b)) for a, b in zip(rng.integers(0, 3, m), rng.integers(1, 3, m))]
        want = []
        for length in range(2, m // 2 + 1):
            subs = list(dict.fromkeys(tuple(atoms[i:i + length]) for i in range(m - length + 1)))
            row = []
            for s in subs:
                chosen = []
                for i in range(m - length + 1):
                    if tuple(atoms[i:i + length]) == s and (not chosen or i >= chosen[-1] + length):
                        chosen.append(i)
                if len(chosen) >= 2:
                    inner = {i + d for i in chosen for d in range(1, length)}
                    row.append(((length - 1) * (len(chosen) - 1), tuple(k for k in range(1, m) if k not in inner)))
            if not row:
                break
            want += row
        want.sort(key=lambda t: -t[0])
        assert _repeated_runs(atoms) == [keep for _, keep in want[:16]]


@pytest.mark.parametrize("periodic", [False, True])
def test_small_regions_in_plain_python_get_the_candidates_of_the_array_path(periodic, monkeypatch):
    """Regions with few repeated instances inside build their line costs and grouping rows in plain Python
    (``actions.SMALL``): the same candidates, in the same order, as the numpy path."""
    from citygen_inverse import actions
    for layout in _layouts():
        index = LayoutIndex([layout], periodic=periodic)
        search = GrammarSearch(index)
        search.run("adp", 20, seed=1)
        for sig in list(search._actions):
            got = []
            for small in (0, 10 ** 9):
                monkeypatch.setattr(actions, "SMALL", small)
                acts = region_actions(index, sig, search.sym, CostModel())
                got.append((acts.cost, acts.heuristic, list(acts)))
            assert got[0] == got[1]


def test_instances_within_a_box_are_those_inside_it():
    layout = random_layout(np.random.default_rng(11), depth=5)
    index = LayoutIndex([layout], periodic=True)
    sym = GrammarSearch(index).sym
    b = sym.boxes
    for box in [*index.roots, *map(tuple, b[::7].tolist()), (1, 1, 10 ** 9, 10 ** 9)]:
        want = np.flatnonzero((b[:, 0] >= box[0]) & (b[:, 1] >= box[1]) & (b[:, 2] <= box[2]) & (b[:, 3] <= box[3]))
        assert sym.within(box).tolist() == want.tolist()
