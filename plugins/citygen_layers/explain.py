"""Text account of a solve (``citygen facade --explain``): candidate words and alignment matrix per direction."""
from __future__ import annotations

from citygen_layers.model import Ruleset
from citygen_layers.solver import DirectionSolution


def _word(letters) -> str:
    return " ".join(x.name if not x.transparent else x.name.lower() if x.name.isupper() else x.name
                    for x in letters) or "ε"


def direction_text(ruleset: Ruleset, sol: DirectionSolution) -> list[str]:
    lines = [f"direction {sol.axis}: canvas {sol.canvas:.3f}, {sol.status}, mu = {sol.mu:.3g}, "
             f"{sol.expansions} ADN expansions"]
    env = ", ".join(f"{k}={v}" for k, v in sorted(sol.candidate.env.items()))
    lines.append(f"  counters: {env or '-'}")
    for matrix in sol.matrices:
        lines.append(f"  alignment group {matrix.group!r}: Omega = {matrix.alignment.error:.3g}, "
                     f"{len(matrix.alignment.columns)} columns")
        for r, row in enumerate(matrix.rows):
            names = ", ".join(ruleset.layers[i].name for i in sorted(row.layers, reverse=True))
            size = sum(x.size for x in matrix.originals[r])
            lines.append(f"    word {row.pattern} [{names}] = {_word(matrix.originals[r])}  (|w| = {size:.3g})")
        cells = [[_word(matrix.words[r][a:b]) if b > a else "ε" for a, b in (col[r] for col in
                  matrix.alignment.columns)] for r in range(len(matrix.rows))]
        widths = [max(len(c[j]) for c in cells) for j in range(len(matrix.alignment.columns))]
        for r, row in enumerate(matrix.rows):
            lines.append(f"    {row.pattern:>10} | " + " | ".join(c.ljust(w) for c, w in zip(cells[r], widths)) + " |")
    for d in sol.diagnostics:
        lines.append(f"  note: {d}")
    return lines


def explain_text(ruleset: Ruleset, sx: DirectionSolution, sy: DirectionSolution) -> str:
    """Transparent letters are shown in lower case (the paper's non-underlined letters)."""
    head = f"layers ruleset {ruleset.name}: {len(ruleset.layers)} layers (top last: " \
           f"{', '.join(layer.name for layer in ruleset.layers)})"
    return "\n".join([head, *direction_text(ruleset, sx), *direction_text(ruleset, sy)])
