"""``citygen relayout MODEL --symbols``: the symbols of a model's segmentation, to write constraints against."""
from __future__ import annotations

from citygen_relayout.model import Model


def symbol_lines(model: Model) -> list[str]:
    """One line per symbol, depth-first from the root (each symbol once, indented by depth): name, label or
    split axis, input size, the size ranges along x and y, how often it occurs, and a composite's children."""
    counts: dict[str, int] = {}

    def count(name: str, times: int) -> None:
        counts[name] = counts.get(name, 0) + times
        for child in model.symbols[name].children:
            count(child, times)

    count(model.root, 1)
    lines = [f"{model.name}: {len(model.symbols)} symbols, {model.terminal_count()} input terminals "
             f"(symbol  label|split  input size  x range  y range  occurrences)"]
    seen: set[str] = set()

    def visit(name: str, depth: int) -> None:
        if name in seen:
            return
        seen.add(name)
        sym = model.symbols[name]
        kind = f"split {sym.split}" if sym.split else (sym.label or "-")
        rx, ry = model.sizes[(name, "x")], model.sizes[(name, "y")]
        line = (f"{'  ' * depth}{name}  {kind}  {sym.extent[0]:.2f} x {sym.extent[1]:.2f} m  "
                f"x {rx.lo:.2f}..{rx.hi:.2f}  y {ry.lo:.2f}..{ry.hi:.2f}  x{counts[name]}")
        if sym.children:
            line += "  : " + " ".join(sym.children)
        lines.append(line)
        for child in dict.fromkeys(sym.children):
            visit(child, depth + 1)

    visit(model.root, 0)
    return lines
