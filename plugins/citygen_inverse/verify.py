"""Does a grammar regenerate a layout exactly? (wu2014 §3.3: only grammars that describe the input exactly.)"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

import citygen_split
from citygen.layout import FacadeLayout
from citygen.request import FacadeRequest


def mismatches(text: str, layout: FacadeLayout, limit: int = 5, start: str | None = None) -> list[str]:
    """Problems found deriving ``text`` (from the symbol ``start``, default the axiom) at the layout's size:
    terminals of the layout not derived (rectangle and label, tolerance 1e-6 of the facade size) or a different
    terminal count; at most ``limit`` listed."""
    grammar = citygen_split.parse(text, "extracted.grammar")
    if start is not None:
        grammar = replace(grammar, start=start)
    derived = citygen_split.derive(grammar, FacadeRequest.preview(layout.width, layout.height)).terminals()
    given = layout.terminals()
    problems = [] if len(given) == len(derived) else [f"{len(given)} terminals in the layout, {len(derived)} derived"]
    tol = 1e-6 * max(layout.width, layout.height)
    rects = np.array([(t.x, t.y, t.w, t.h) for t in derived]).reshape(-1, 4)
    labels = np.array([str(t.label) for t in derived])
    used = np.zeros(len(derived), dtype=bool)
    for t in given:
        hit = np.flatnonzero(np.all(np.abs(rects - (t.x, t.y, t.w, t.h)) <= tol, axis=1)
                             & (labels == str(t.label)) & ~used)
        if hit.size:
            used[hit[0]] = True
        elif len(problems) < limit:
            problems.append(f"{t.label} at x {t.x:g}, y {t.y:g} ({t.w:g} x {t.h:g} m) is not derived")
    return problems


def joint_mismatches(text: str, layouts: list[FacadeLayout], limit: int = 5) -> list[list[str]]:
    """``mismatches`` per layout of a joint grammar (wu2014 §6.1), whose axiom picks one facade symbol per layout
    (in order): each layout is derived from its own symbol."""
    grammar = citygen_split.parse(text, "extracted.grammar")
    choice = grammar.rule(grammar.start).body
    starts = [body.symbol for _, body in choice.alternatives] + [choice.otherwise.symbol]
    return [mismatches(text, layout, limit, start) for layout, start in zip(layouts, starts, strict=True)]
