"""Sharing network rows between the searches of a direction solve (NetworkMemo) is exact."""
from pathlib import Path

import numpy as np
from citygen_layers.align import Budget, NetworkMemo, align
from citygen_layers.candidates import CandidateGenerator, direction_spec
from citygen_layers.model import Counter
from citygen_layers.parser import load
from citygen_layers.solver import _above
from citygen_layers.splits import split_transparent

ROOT = Path(__file__).resolve().parents[2]


def _matrices(path, axis, canvas, mu, count):
    rs = load(path)
    counters = dict(rs.counters)
    counters["entrance"] = Counter("entrance", 0, 0)
    spec = direction_spec(rs, axis, canvas, counters)
    out = []
    for cand in list(CandidateGenerator(rs, spec, mu))[:count]:
        words = tuple(cand.words[r.pattern] for r in spec.rows)
        split, parents = split_transparent(words, canvas)
        out.append((tuple(split), tuple(parents), _above(spec.rows), canvas))
    assert out
    return out


def test_shared_rows_give_the_alignments_and_expansions_of_private_ones():
    matrices = _matrices(ROOT / "benchmarks/data/layers/tonhalle26.layers", "y", 19.0, 0.4, 6)
    matrices += _matrices(ROOT / "rulesets/tenement.layers", "x", 16.0, 3.2, 6)
    memo = NetworkMemo()
    found = 0
    for mu in (0.8, 1.6, 3.2):
        for words, parents, above, canvas in matrices:
            private, shared = Budget(3000, 1e18), Budget(3000, 1e18)
            expected = align(words, above, canvas, mu, private, parents)
            assert align(words, above, canvas, mu, shared, parents, memo=memo) == expected
            assert shared.used == private.used
            found += expected is not None
    assert found >= 8
    rows = len(memo.rows)
    words, parents, above, _ = matrices[0]
    align(words, above, 19.0, 3.2, Budget(3000, 1e18), parents, memo=memo)
    assert len(memo.rows) == rows                  # a repeated matrix builds no new row


def test_rows_are_keyed_by_their_index_and_upper_rows():
    words, parents, above, _ = _matrices(ROOT / "rulesets/tenement.layers", "x", 16.0, 3.2, 1)[0]
    memo = NetworkMemo()
    align(words, above, 16.0, 3.2, Budget(3000, 1e18), parents, memo=memo)
    flipped = np.ascontiguousarray(above.T)
    budget, private = Budget(3000, 1e18), Budget(3000, 1e18)
    assert (align(words, flipped, 16.0, 3.2, budget, parents, memo=memo) ==
            align(words, flipped, 16.0, 3.2, private, parents))
    assert budget.used == private.used


def test_cut_network_keeps_exactly_the_edges_within_the_cutoff_in_order():
    """Columns with Phi > mu + 1e-9 are not built by the searches' networks (no path within mu can take one)."""
    from citygen_layers.align import _Words

    for words, parents, above, _ in _matrices(ROOT / "benchmarks/data/layers/tonhalle26.layers", "y", 19.0, 0.4, 2):
        full, cut = _Words(words, above, parents), _Words(words, above, parents, cutoff=0.8 + 1e-9)
        states = [tuple(0 for _ in words)]
        states += [nxt for _, _, _, _, nxt in full.edges(states[0])]
        dropped = 0
        for state in states:
            kept = [e for e in full.edges(state) if e[0] <= 0.8 + 1e-9]
            assert cut.edges(state) == kept
            dropped += len(full.edges(state)) - len(kept)
        assert dropped > 0


def test_rows_are_found_by_letter_identity_only_for_words_the_memo_keeps():
    """Rows are looked up by the identities of their letters first. Freed letters' ids are reused by new
    letters, so only the ids of the words the memo keeps alive may be keys; equal words made of other letter
    objects still share the row (through the equality key)."""
    import random

    from citygen_layers.words import Letter

    rng = random.Random(3)
    memo = NetworkMemo()
    above = np.array([[False, False], [True, False]])
    for _ in range(50):
        words = tuple(tuple(Letter(s, rng.choice((0.5, 1.0, 1.5)), opaque=s == "A") for s in w)
                      for w in ("ABAB", "CDC"))
        private = align(words, above, 4.0, 1.0, Budget(3000, 1e18))
        assert align(words, above, 4.0, 1.0, Budget(3000, 1e18), memo=memo) == private
        rows = len(memo.rows)
        copies = tuple(tuple(Letter(x.symbol, x.size, opaque=x.opaque) for x in w) for w in words)
        assert align(copies, above, 4.0, 1.0, Budget(3000, 1e18), memo=memo) == private
        assert len(memo.rows) == rows
    assert all(key[1] == tuple(map(id, row.word)) for key, row in memo.by_ids.items())
