"""Grid cell spans: ``<`` continues the cell to the left, ``v`` the cell below; spanned areas are rectangles."""
from __future__ import annotations


class GridSpanError(ValueError):
    """A grid's cells do not form rectangles; ``row`` and ``col`` locate the offending cell (row 0 = bottom)."""

    def __init__(self, message: str, row: int, col: int) -> None:
        super().__init__(message)
        self.row, self.col = row, col


def merge_cells(cells: tuple[tuple[str, ...], ...]) -> tuple[tuple[str, int, int, int, int], ...]:
    """Regions ``(symbol, col0, row0, col1, row1)`` (end-exclusive) in order of their first cell, bottom row first."""
    owner: list[list[int]] = []
    symbols: list[str] = []
    for r, row in enumerate(cells):
        owner.append([])
        for c, cell in enumerate(row):
            if cell == "<":
                if c == 0:
                    raise GridSpanError("'<' in the first column has no cell to its left to continue", r, c)
                owner[r].append(owner[r][c - 1])
            elif cell == "v":
                if r == 0:
                    raise GridSpanError("'v' in the bottom row has no cell below to continue", r, c)
                owner[r].append(owner[r - 1][c])
            else:
                owner[r].append(len(symbols))
                symbols.append(cell)
    cover: dict[int, list[tuple[int, int]]] = {}
    for r, row in enumerate(owner):
        for c, k in enumerate(row):
            cover.setdefault(k, []).append((r, c))
    regions = []
    for k, symbol in enumerate(symbols):
        rows = [r for r, _ in cover[k]]
        cols = [c for _, c in cover[k]]
        r0, r1, c0, c1 = min(rows), max(rows) + 1, min(cols), max(cols) + 1
        if len(cover[k]) != (r1 - r0) * (c1 - c0):
            hole = next((r, c) for r in range(r0, r1) for c in range(c0, c1) if owner[r][c] != k)
            raise GridSpanError(f"the cells of {symbol} (row {r0 + 1}, column {c0 + 1}) do not form a rectangle "
                                f"(row {hole[0] + 1}, column {hole[1] + 1} belongs to another region)", *hole)
        regions.append((symbol, c0, r0, c1, r1))
    return tuple(regions)
