"""cProfile for the replay benchmarks (``--profile``): a run's function calls, which do not depend on the
machine's load, and its top functions by own time."""
from __future__ import annotations

import cProfile
import pstats
from collections.abc import Callable
from typing import TypeVar

T = TypeVar("T")


def profiled(run: Callable[[], T], top: int) -> T:
    """``run()`` under cProfile: prints its function calls and its ``top`` functions by own time; returns its
    result."""
    profile = cProfile.Profile()
    profile.enable()
    result = run()
    profile.disable()
    stats = pstats.Stats(profile)
    print(f"function calls: {stats.total_calls} ({stats.prim_calls} primitive)")
    stats.sort_stats("tottime").print_stats(top)
    return result
