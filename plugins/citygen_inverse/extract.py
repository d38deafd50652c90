"""Public API: extract a split grammar from one or several labelled facade layouts (wu2014 §3-§6.1)."""
from __future__ import annotations

import time
from dataclasses import dataclass, replace

from citygen.gcpause import cyclic_gc_paused
from citygen.layout import FacadeLayout
from citygen_inverse.actions import CostModel
from citygen_inverse.emit import GrammarWriter
from citygen_inverse.regions import LayoutIndex
from citygen_inverse.search import GrammarSearch, SearchResult


@dataclass(frozen=True)
class Extraction:
    """An extracted grammar: DSL text (exact and size-independent), Eq. 1 cost, rule count and run time."""

    text: str
    size_independent: str
    cost: float
    rules: int
    seconds: float
    iterations: int
    terminals: int
    method: str
    cpu_seconds: float = 0.0  # process time of index, symmetry detection and search (``seconds`` is wall time)
    bound: float | None = None  # method exact: lower bound on the cost of any grammar over the candidate rules
    optimal: bool = False  # method exact: proven the cheapest over the candidate rules
    stopped: bool = False  # method exact: its integer program was stopped by the time limit

    def verdict(self) -> str:
        """Method exact: what the integer program proved (empty for the other methods)."""
        if self.bound is None:
            return ""
        if self.optimal:
            return "optimal over the candidate rules"
        if self.bound <= 0:
            return "no lower bound: stopped at the time limit before the integer program had one"
        gap = 100 * (1 - self.bound / self.cost) if self.cost > 0 else 0.0
        stop = ", stopped at the time limit" if self.stopped else ""
        return f"lower bound {self.bound:.1f} ({gap:.1f} % below){stop}"


@cyclic_gc_paused()
def extract_grammar(layouts: FacadeLayout | list[FacadeLayout], method: str = "adp", iterations: int = 2000,
                    seed: int = 0, model: CostModel = CostModel(), time_limit: float | None = None,
                    free_extents: bool = True) -> Extraction:
    """Extract one grammar for ``layouts`` (several layouts: joint extraction, wu2014 §6.1 / Fig. 13).

    ``free_extents=False`` restricts shared rules to strictly translational repeats (see ``regions.py``)."""
    layouts = [layouts] if isinstance(layouts, FacadeLayout) else list(layouts)
    wall, cpu = time.perf_counter(), time.process_time()
    index = LayoutIndex(layouts, free_extents, periodic=free_extents)
    search = GrammarSearch(index, model)
    result: SearchResult = search.run(method, iterations, seed, time_limit)
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    writer = GrammarWriter(index, result.rules)
    terminals = int(index.X0.size)
    cost, rules = result.cost, len(result.rules)
    if len(layouts) > 1:  # the written axiom picks a facade: a choice of k renames, priced as `grammar cost` does
        cost, rules = cost + model.split * (len(layouts) - 1) + len(layouts), rules + 1
    header = [f"extracted by citygen grammar extract (wu2014), method {method}, {result.iterations} iterations, "
              f"seed {seed}",
              f"{terminals} terminals; cost {cost:.1f} (split {model.split}, repeat {model.repeat}); {rules} rules"]
    found = Extraction("", "", cost, rules, wall, result.iterations, terminals, method, cpu, _bound(result, cost),
                       result.optimal, result.stopped)
    if found.verdict():
        header.append(f"integer program: {found.verdict()}")
    if len(layouts) > 1:
        header.append(f"joint grammar of {len(layouts)} facades: the axiom picks one")
    exact = writer.text(header)
    independent = writer.text([*header, "size-independent version (wu2014 §5)"], independent=True,
                              floors=len(layouts) == 1)
    return replace(found, text=exact, size_independent=independent)


def _bound(result: SearchResult, cost: float) -> float | None:
    """The search's lower bound moved by what the written grammar adds to the searched one (a joint axiom)."""
    return None if result.bound is None else result.bound + cost - result.cost
