"""The ranking of variations: the paper's distortion E(x) plus plausibility terms (see docs/safe.md).

E(x) (Eq. 1) measures a variation against the facade *after* its jumps, so a jump that cuts a window in half or
fuses two strips into one costs nothing there, and such a variation could outrank the clean resize. Each
*defect* below (counted once per input terminal: copies share it) adds ``DEFECT`` to the cost (on cmp_b0035 one
cut signboard outweighs squeezing five window columns to 1.3 m on an 8.5 m face, E 4-9e4):

* ``cut``: after removal jumps, an element (a labelled terminal that is neither wall nor one of the ``BANDS``
  jumps stretch legitimately) narrower than its input terminal by more than ``CHANGED`` (a removal slab's edge ran
  through it, leaving a remnant); an insertion's copies of the part of an element inside the copied bay are not
  counted (every inserted bay repeats the source bay, remnant included);
* ``fused``: an element wider than its input terminal by more than ``CHANGED`` (copies or remnants merged);
* ``sliver``: an element sized below ``2 x sliver`` although its input terminal is not;
* ``off-centre``: a door whose centre is off the facade's middle by more than ``CENTRED`` of the width when the
  input's door is centred.
"""
from __future__ import annotations

from collections.abc import Mapping

from citygen.plausible import DEFAULT_RULES, PlausibilityRules
from citygen_safe.bounds import COLLAPSIBLE
from citygen_safe.leaves import Facade

DEFECT = 1e5  #: cost of one defect, in units of E(x)
BANDS = frozenset({"sill", "frame", "molding", "ledge", "cornice"})  #: labels a jump stretches with its columns
CHANGED = 0.05  #: relative width change of an element by a jump that counts as cut or fused
CENTRED = 0.02  #: a door within this fraction of the width from the middle is centred


def reference_widths(facade: Facade) -> dict[int, float]:
    """The width of each input terminal (by origin) in a facade without jumps."""
    out: dict[int, float] = {}
    for f in facade.leaves:
        out[f.origin] = max(out.get(f.origin, 0.0), f.w)
    return out


def is_centred(facade: Facade, labels: frozenset[str]) -> bool:
    """Whether every leaf with one of ``labels`` is centred on ``facade`` (and there is one)."""
    found = [f for f in facade.leaves if f.label in labels]
    return bool(found) and all(abs(f.x + 0.5 * f.w - 0.5 * facade.width) <= CENTRED * facade.width for f in found)


def defects(natural: Facade, sized: Facade, reference: Mapping[int, float], centre: frozenset[str],
            removed: bool, rules: PlausibilityRules = DEFAULT_RULES) -> tuple[str, ...]:
    """The defects of a variation, one per kind and input terminal (its copies share it): ``natural`` its facade
    after the jumps (``removed``: some of them removals), ``sized`` after the QP, ``reference`` the input
    terminals' widths, ``centre`` the labels to keep centred."""
    found: dict[tuple[str, int], str] = {}
    for f in natural.leaves:
        if f.label in COLLAPSIBLE or f.label in BANDS or f.origin not in reference:
            continue
        w0 = reference[f.origin]
        if f.w > (1 + CHANGED) * w0 or removed and f.w < (1 - CHANGED) * w0:
            kind = "cut" if f.w < w0 else "fused"
            found.setdefault((kind, f.origin), f"{kind} {f.label} {f.region.symbol} ({w0:.2f} -> {f.w:.2f} m)")
    thin = 2 * rules.sliver
    for f in sized.leaves:
        element = f.label not in COLLAPSIBLE and f.label not in rules.thin_labels
        if element and f.w < thin <= reference.get(f.origin, 0.0):
            found.setdefault(("sliver", f.origin), f"sliver {f.label} {f.region.symbol} ({f.w:.2f} m)")
    for f in sized.leaves:
        if f.label in centre and abs(f.x + 0.5 * f.w - 0.5 * sized.width) > CENTRED * sized.width:
            found.setdefault(("off-centre", f.origin),
                             f"off-centre {f.label} (centre at {f.x + 0.5 * f.w:.2f} of {sized.width:.2f} m)")
    return tuple(found.values())


def penalty(found: tuple[str, ...]) -> float:
    """The plausibility terms of the cost: ``DEFECT`` per defect."""
    return DEFECT * len(found)
