"""Plausibility: is a facade layout one an author would accept, not merely a valid partition?

:func:`check_partition` says whether terminals tile the face and :func:`citygen.request.check_request` whether the
building's constraints hold; neither notices a window 0.19 m wide, a shop 0 m tall, a door that is a 0.5 m hatch or
a storey whose windows vanished. :func:`check_plausible` does, against documented, configurable
:class:`PlausibilityRules`, and returns :class:`Finding` objects (an empty list: plausible). Every ruleset kind holds
its candidates to it (a layout with findings is not "solved"), and the building builder checks again before
geometry, so an implausible facade falls back through the scene's chain with a warning instead of being built.

The rules (defaults in brackets; a scene's ``[plausibility]`` table overrides them, see docs/scene.md):

* ``zero-size``: no labelled terminal narrower or lower than ``min_extent`` [0.01 m];
* ``small-opening``: openings at least ``min_size[label]`` wide and tall [window 0.3 x 0.3, door 0.7 x 1.9,
  shop 0.8 x 1.2, balcony 0.6 x 0.3 m];
* ``short-door`` / ``floating-door``: doors at least ``door_min_height`` [1.9 m] tall and within ``door_step``
  [0.3 m] of the floor line they stand on;
* ``sliver``: no labelled terminal thinner than ``sliver`` [0.05 m] unless its label is in ``thin_labels`` (sill,
  frame, molding, ledge, cornice, deco);
* ``empty-storey``: with a request, an upper storey without openings while most other upper storeys have some
  (storeys dropped or their windows relabelled), and storeys whose openings' rows are more than
  ``storey_range[1]`` times the requested storey height apart;
* ``relabelled``: a generator that turned openings into wall to save a layout says so in ``meta["relabelled"]``.
"""
from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, fields, replace
from typing import Any

import numpy as np

from citygen.errors import SceneError
from citygen.layout import FacadeLayout, Region, remembered
from citygen.request import FacadeRequest

#: Labels of openings: what a storey is recognised by.
OPENING_LABELS = frozenset({"window", "door", "shop", "balcony"})


@dataclass(frozen=True)
class PlausibilityRules:
    """The thresholds of :func:`check_plausible` (metres)."""

    min_extent: float = 0.01
    min_size: Mapping[str, tuple[float, float]] = field(default_factory=lambda: {
        "window": (0.3, 0.3), "door": (0.7, 1.9), "shop": (0.8, 1.2), "balcony": (0.6, 0.3)})
    door_min_height: float = 1.9
    door_step: float = 0.3
    sliver: float = 0.05
    thin_labels: frozenset[str] = frozenset({"sill", "frame", "molding", "ledge", "cornice", "deco"})
    storey_range: tuple[float, float] = (0.5, 1.6)

    @classmethod
    def from_mapping(cls, data: Mapping[str, Any], where: str = "[plausibility]") -> PlausibilityRules:
        """Rules from a scene's ``[plausibility]`` table: any field by name; ``min_size`` as ``{label = [w, h]}``,
        ``thin_labels`` and ``storey_range`` as lists."""
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(data) - known)
        if unknown:
            raise SceneError(f"unknown plausibility rule(s) {', '.join(unknown)}", where=where,
                             hint=f"known rules: {', '.join(sorted(known))}")
        rules, changes = cls(), {}
        for key, value in data.items():
            try:
                changes[key] = _coerced(key, value, getattr(rules, key))
            except (TypeError, ValueError) as exc:
                raise SceneError(f"plausibility rule {key} = {value!r}: {exc}", where=where,
                                 hint="numbers are metres; min_size is a table of [width, height] pairs by label"
                                 ) from None
        return replace(rules, **changes)


def _coerced(key: str, value: Any, default: Any) -> Any:
    def metres(v: Any) -> float:
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not 0 <= float(v) < math.inf:
            raise ValueError("not a finite number >= 0")
        return float(v)

    if key == "min_size":
        if not isinstance(value, Mapping):
            raise TypeError("not a table")
        sizes = dict(default)
        for label, pair in value.items():
            if not isinstance(pair, (list, tuple)) or len(pair) != 2:
                raise ValueError(f"{label}: not a [width, height] pair")
            sizes[str(label)] = (metres(pair[0]), metres(pair[1]))
        return sizes
    if key == "thin_labels":
        if not isinstance(value, (list, tuple)) or not all(isinstance(v, str) for v in value):
            raise TypeError("not a list of labels")
        return frozenset(value)
    if key == "storey_range":
        if not isinstance(value, (list, tuple)) or len(value) != 2:
            raise ValueError("not a [low, high] pair")
        low, high = metres(value[0]), metres(value[1])
        if not low <= 1.0 <= high:
            raise ValueError("low must be <= 1 <= high")
        return (low, high)
    return metres(value)


DEFAULT_RULES = PlausibilityRules()


@dataclass(frozen=True)
class Finding:
    """One implausibility: a rule ``code``, what is wrong, and the terminal it concerns (if one)."""

    code: str
    message: str
    region: Region | None = None

    def __str__(self) -> str:
        return f"{self.code}: {self.message}"


def check_plausible(layout: FacadeLayout, request: FacadeRequest | None = None,
                    rules: PlausibilityRules = DEFAULT_RULES) -> list[Finding]:
    """Findings against ``rules`` for ``layout`` (as an answer to ``request``, when given); empty = plausible.

    Costs O(terminals) with numpy over :attr:`FacadeLayout.leaf_rects`; at most a few findings per rule are
    listed (with a count), so a degenerate layout of thousands of terminals reads in a few lines.
    """
    rules = DEFAULT_RULES if rules == DEFAULT_RULES else rules  # (a scene's default rules: the generator's)
    return remembered(layout, "plausible", (request, rules), lambda: _findings(layout, request, rules))


def _findings(layout: FacadeLayout, request: FacadeRequest | None, rules: PlausibilityRules) -> list[Finding]:
    if not len(layout.leaf_rects):
        return []
    x, y, w, h = layout.leaf_rects.T
    lines = np.asarray(request.floor_lines if request is not None else (0.0,), dtype=float)
    findings = _terminal_findings(layout, x, y, w, h, lines, rules) if _suspect(layout, y, w, h, lines, rules) \
        else []
    if request is not None:
        findings += _storeys(layout, y, h, request, rules)
    relabelled = int(layout.meta.get("relabelled", 0) or 0)
    if relabelled:
        findings.append(Finding("relabelled", f"{relabelled} opening(s) were relabelled wall by the generator"))
    return findings


def _suspect(layout: FacadeLayout, y: np.ndarray, w: np.ndarray, h: np.ndarray, lines: np.ndarray,
             rules: PlausibilityRules) -> bool:
    """Whether a terminal rule may report a terminal: every such rule but the floating door's asks for ``w < a or
    h < b`` with limits by label, so one comparison with each label's largest limits, and the floating-door test
    on the doors alone, rule most layouts out at once."""
    names, codes = layout.leaf_labels
    known = _LIMITS.get((names, id(rules)))
    if known is None or known[0] is not rules:
        if len(_LIMITS) > 256:
            _LIMITS.clear()
        known = _LIMITS[names, id(rules)] = (rules, _limits(names, rules))
    limit_w, limit_h = known[1][codes].T
    if np.any((w < limit_w) | (h < limit_h)):
        return True
    if "door" not in names:
        return False
    door_y = y[codes == names.index("door")]  # (as :func:`_terminal_findings`' floating-door rule)
    below = lines[np.clip(np.searchsorted(lines, door_y + 1e-6, side="right") - 1, 0, None)]
    return bool(np.any(door_y - below > rules.door_step + 1e-6))


#: ``(labels, id(rules)) -> (rules, limits)``: the limits of :func:`_limits`, per label set and rules met (layouts
#: of one ruleset share their labels).
_LIMITS: dict[tuple[tuple[str | None, ...], int], tuple[PlausibilityRules, np.ndarray]] = {}


def _limits(names: tuple[str | None, ...], rules: PlausibilityRules) -> np.ndarray:
    """Per label, the largest width and height below which a per-terminal rule reports a terminal (an ``(n, 2)``
    array; -inf for no label)."""
    limits = []
    for name in names:
        if not name:
            limits.append((-math.inf, -math.inf))
            continue
        thin = -math.inf if name in rules.thin_labels else rules.sliver - 1e-6
        low_w, low_h = (v - 1e-6 for v in rules.min_size.get(name, (-math.inf, -math.inf)))
        door = rules.door_min_height - 1e-6 if name == "door" else -math.inf
        limits.append((max(rules.min_extent, thin, low_w), max(rules.min_extent, thin, low_h, door)))
    return np.array(limits, dtype=float).reshape(-1, 2)


def _terminal_findings(layout: FacadeLayout, x: np.ndarray, y: np.ndarray, w: np.ndarray, h: np.ndarray,
                       lines: np.ndarray, rules: PlausibilityRules) -> list[Finding]:
    """The findings of the rules on single terminals (zero-size, small-opening, short- and floating-door, sliver),
    at most three listed per rule and label."""
    labelled = layout.label_mask(bool)  # (None and "" are no label)
    zero = labelled & ((w < rules.min_extent) | (h < rules.min_extent))
    size = lambda r: f"{r.w:.2f} x {r.h:.2f} m at x={r.x:.2f}, y={r.y:.2f}"  # noqa: E731
    rows: list[tuple[str, np.ndarray, Callable[[Region], str]]] = [
        ("zero-size", zero, lambda r: f"{r.label} {r.symbol} is {size(r)}")]
    for label, (min_w, min_h) in rules.min_size.items():
        small = layout.label_mask(lambda n, a=label: (n or "") == a) & ~zero & ((w < min_w - 1e-6) | (h < min_h - 1e-6))
        rows.append(("small-opening", small,
                     lambda r, a=min_w, b=min_h: f"{r.label} {r.symbol} is {size(r)} (at least {a:g} x {b:g} m)"))
    doors = layout.label_mask(lambda n: n == "door") & ~zero
    rows.append(("short-door", doors & (h < rules.door_min_height - 1e-6),
                 lambda r: f"door {r.symbol} is {r.h:.2f} m tall (at least {rules.door_min_height:g} m)"))
    below = lines[np.clip(np.searchsorted(lines, y + 1e-6, side="right") - 1, 0, None)]
    rows.append(("floating-door", doors & (y - below > rules.door_step + 1e-6),
                 lambda r: f"door {r.symbol} starts {r.y - _floor_below(lines, r.y):.2f} m above its floor "
                           f"(at most {rules.door_step:g} m)"))
    thin = layout.label_mask(lambda n: (n or "") in rules.thin_labels)
    sliver = labelled & ~zero & ~thin & (np.minimum(w, h) < rules.sliver - 1e-6)
    rows.append(("sliver", sliver, lambda r: f"{r.label} {r.symbol} is {size(r)} (thinner than {rules.sliver:g} m)"))
    findings: list[Finding] = []
    for code, mask, describe in rows:
        hits = np.flatnonzero(mask)
        findings += [Finding(code, describe(layout.leaves[i]), layout.leaves[i]) for i in hits[:3].tolist()]
        if hits.size > 3:
            findings.append(Finding(code, f"... and {hits.size - 3} more"))
    return findings


def _floor_below(lines: np.ndarray, y: float) -> float:
    k = int(np.searchsorted(lines, y + 1e-6, side="right")) - 1
    return float(lines[max(k, 0)])


def _storeys(layout: FacadeLayout, y: np.ndarray, h: np.ndarray, request: FacadeRequest,
             rules: PlausibilityRules) -> list[Finding]:
    """Upper storeys without openings where most have some, and opening rows too far apart."""
    lines = np.asarray(request.floor_lines, dtype=float)
    if lines.size < 3:
        return []
    opening = layout.label_mask(lambda n: (n or "") in OPENING_LABELS)
    mid = y + h / 2
    band = np.searchsorted(lines, mid, side="right") - 1
    counts = np.bincount(band[opening & (band >= 0) & (band < lines.size - 1)], minlength=lines.size - 1)
    upper = counts[1:]
    if upper.size < 2 or np.count_nonzero(upper) * 2 <= upper.size:
        return []
    findings = [Finding("empty-storey", f"storey {k} ({lines[k]:.2f}-{lines[k + 1]:.2f} m) has no openings while "
                                        f"{np.count_nonzero(upper)} of {upper.size} upper storeys have some")
                for k in (np.flatnonzero(upper == 0) + 1).tolist()]
    rows = np.unique(np.round(y[opening & (band >= 1)], 2))
    if rows.size >= 2:
        pitch = np.diff(rows)
        storey = float(np.max(np.diff(lines[1:])))
        for k in np.flatnonzero(pitch > rules.storey_range[1] * storey + 1e-6)[:3].tolist():
            findings.append(Finding("storey-height", f"opening rows at y={rows[k]:.2f} and {rows[k + 1]:.2f} m are "
                                                     f"{pitch[k]:.2f} m apart, storeys are {storey:.2f} m"))
    return findings


def plain_wall(request: FacadeRequest, reason: str, findings: list[Finding] | tuple[Finding, ...] = (),
               **meta: Any) -> FacadeLayout:
    """The plain-wall layout a generator returns when it cannot dress ``request`` plausibly: ``meta["fallback"]``
    names why (the builder then tries the scene's fallback ruleset and warns), ``meta["findings"]`` what was
    wrong with the best layout it had."""
    return FacadeLayout(request.width, request.height,
                        Region(0.0, 0.0, request.width, request.height, "Wall", "wall"),
                        meta={**meta, "fallback": reason, "findings": [str(f) for f in findings]})


def summary(findings: list[Finding] | tuple[Finding, ...], limit: int = 3) -> str:
    """The first ``limit`` findings on one line (for warnings and fallback reasons)."""
    text = "; ".join(str(f) for f in findings[:limit])
    return text + (f"; ... ({len(findings) - limit} more)" if len(findings) > limit else "")
