"""Canonical text of a grammar: ``parse(format_grammar(g)) == g`` for every grammar ``g``."""
from __future__ import annotations

import re

from citygen_split.ast import (
    Attr, Binary, Body, Case, Choice, Const, Expr, Floors, Grammar, Grid, Item, Rename, Repeat, RepeatABA,
    SimpleBody, Size, Split, SymSplit, Terminal, Unary, Var,
)

_BARE = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
_PREC = {"or": 1, "and": 2, "not": 3, "==": 4, "!=": 4, "<": 4, "<=": 4, ">": 4, ">=": 4, "+": 5, "-": 5,
         "*": 6, "/": 6, "neg": 7}


def format_grammar(grammar: Grammar) -> str:
    """Pragmas (@name, @size, @start) then one rule per paragraph line, in the grammar's order."""
    lines = []
    if grammar.name is not None:
        lines.append(f"@name {_string(grammar.name)}")
    if grammar.size is not None:
        lines.append(f"@size {number(grammar.size[0])} {number(grammar.size[1])}")
    lines.append(f"@start {grammar.start}")
    lines.append("")
    for rule in grammar.rules:
        lines.append(f"{rule.symbol} --> {format_body(rule.body, ' ' * (len(rule.symbol) + 5))}")
    return "\n".join(lines) + "\n"


def number(value: float) -> str:
    """Shortest text that parses back to ``value`` exactly."""
    text = repr(float(value))
    return text[:-2] if text.endswith(".0") else text


def _string(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


def format_size(size: Size) -> str:
    prefix = {"abs": "", "rel": "'", "float": "~"}[size.kind]
    return prefix + number(size.value)


def _items(items: tuple[Item, ...] | list[Item]) -> str:
    return " | ".join(f"{format_size(i.size)}: {i.symbol}" for i in items)


def format_body(body: Body, indent: str = "    ") -> str:
    """One rule body; alternatives of case / stochastic rules go on their own lines, indented by ``indent``."""
    if isinstance(body, Case):
        parts = [f"case {format_expr(c)}: {_simple(b)}" for c, b in body.branches]
        if body.otherwise is not None:
            parts.append(f"else: {_simple(body.otherwise)}")
        return f"\n{indent}".join(parts)
    if isinstance(body, Choice):
        parts = [f"{number(p)}%: {_simple(b)}" for p, b in body.alternatives]
        if body.otherwise is not None:
            parts.append(f"else: {_simple(body.otherwise)}")
        return ("each " if body.each else "") + f"\n{indent}".join(parts)
    return _simple(body)


def _simple(body: SimpleBody) -> str:
    if isinstance(body, Rename):
        return body.symbol
    if isinstance(body, Split):
        return f"split({body.axis}) {{ {_items(body.items)} }}"
    if isinstance(body, Repeat):
        return f"repeat({body.axis}) {{ {_items(body.items)} }}"
    if isinstance(body, SymSplit):
        return f"symsplit({body.axis}) {{ {_items(body.items)} }}"
    if isinstance(body, RepeatABA):
        return f"repeatABA({body.axis}) {{ {_items([body.a, body.b])} }}"
    if isinstance(body, Floors):
        sel = " | ".join(f"{'*' if i.floor is None else i.floor}: {i.symbol}" for i in body.items)
        return f"floors {{ {sel} }}"
    if isinstance(body, Grid):
        cols = " | ".join(format_size(s) for s in body.cols)
        rows = " | ".join(format_size(s) for s in body.rows)
        cells = " / ".join(" ".join(row) for row in body.cells)
        return f"grid {{ cols: {cols} ; rows: {rows} ; {cells} }}"
    if isinstance(body, Terminal):
        args = [body.label or "none"]
        if body.depth:
            args.append(f"depth: {number(body.depth)}")
        if body.material is not None:
            bare = _BARE.match(body.material) and body.material[0].islower()
            args.append(f"material: {body.material if bare else _string(body.material)}")
        if body.asset is not None:
            args.append(f"asset: {_string(body.asset)}")
        return f"terminal({', '.join(args)})"
    raise TypeError(f"not a rule body: {body!r}")


def format_expr(expr: Expr, parent: int = 0) -> str:
    """An expression with the parentheses its precedence needs."""
    if isinstance(expr, Const):
        if isinstance(expr.value, bool):
            return "true" if expr.value else "false"
        if isinstance(expr.value, str):
            return _string(expr.value)
        text = number(expr.value)
        return f"({text})" if text.startswith("-") else text
    if isinstance(expr, Var):
        return expr.name
    if isinstance(expr, Attr):
        return f"attr({_string(expr.key)})"
    if isinstance(expr, Unary):
        prec = _PREC["not"] if expr.op == "not" else _PREC["neg"]
        text = f"not {format_expr(expr.operand, prec)}" if expr.op == "not" else f"-{format_expr(expr.operand, prec)}"
        return f"({text})" if prec < parent else text
    if isinstance(expr, Binary):
        prec = _PREC[expr.op]
        # left-associative: the right operand needs parentheses at equal precedence; comparisons never chain
        left = format_expr(expr.left, prec + (1 if prec == 4 else 0))
        right = format_expr(expr.right, prec + 1)
        text = f"{left} {expr.op} {right}"
        return f"({text})" if prec < parent else text
    raise TypeError(f"not an expression: {expr!r}")
