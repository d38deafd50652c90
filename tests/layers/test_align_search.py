"""The depth-first alignment search (§5.2) is exhaustive over its network: when it completes, its result is the
best path within mu (or None when there is none), so align() does not run the bidirectional search after it."""
import math
import random

import numpy as np
from hypothesis import given, settings, strategies as st

from citygen_layers.align import Budget, _descend, _Words
from citygen_layers.words import Letter


def _random_matrix(rng: random.Random):
    rows = rng.randint(2, 3)
    words = tuple(tuple(Letter(rng.choice("ABC"), rng.choice((0.5, 1.0, 1.5, 2.0)), opaque=rng.random() < 0.3,
                               transparent=rng.random() < 0.15)
                        for _ in range(rng.randint(1, 5))) for _ in range(rows))
    above = np.array([[h > r for r in range(rows)] for h in range(rows)])
    # tight canvases: an alignment is at least as long as its longest word, so the size bound often binds
    canvas = max(sum(x.size for x in w) for w in words) + rng.choice((-0.25, 0.0, 0.25, 0.5))
    return words, above, canvas, rng.choice((0.25, 0.5, 1.0, 2.0))


def _best_path(net: _Words, state, goal, g, size, canvas, mu) -> float:
    """Least error of any path to the goal with error <= mu and size <= canvas + mu (brute force)."""
    if state == goal:
        return g
    best = math.inf
    for phi, _, _, csize, nxt in net.edges(state):
        if g + phi <= mu + 1e-9 and size + csize + net.rest(nxt) <= canvas + mu + 1e-9:
            best = min(best, _best_path(net, nxt, goal, g + phi, size + csize, canvas, mu))
    return best


@settings(max_examples=300, deadline=None)
@given(st.integers(0, 10**9))
def test_completed_depth_first_search_is_optimal_over_its_network(seed):
    words, above, canvas, mu = _random_matrix(random.Random(seed))
    net = _Words(words, above, cutoff=mu + 1e-9)
    goal = tuple(len(w) for w in words)
    found, complete = _descend(net, goal, canvas, mu, Budget(10**6, 1e18), improve=1e6)  # (no anytime cut)
    assert complete
    best = _best_path(net, tuple(0 for _ in words), goal, 0.0, 0.0, canvas, mu)
    if best == math.inf:
        assert found is None
    else:
        assert found is not None and abs(found.error - best) <= 1e-9
        assert found.size <= canvas + mu + 1e-9
