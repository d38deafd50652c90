"""Evaluation of condition expressions (docs/grammar.md, Conditions)."""
from __future__ import annotations

import operator
from collections.abc import Callable, Mapping
from typing import Any

from citygen.errors import RulesetError
from citygen_split.ast import Attr, Binary, Const, Expr, Unary, Var

_ARITH: dict[str, Callable[[float, float], float]] = {"+": operator.add, "-": operator.sub, "*": operator.mul,
                                                      "/": operator.truediv}
_COMPARE: dict[str, Callable[[Any, Any], bool]] = {"==": operator.eq, "!=": operator.ne, "<": operator.lt,
                                                   "<=": operator.le, ">": operator.gt, ">=": operator.ge}


def evaluate(expr: Expr, env: Mapping[str, Any], attributes: Mapping[str, Any], rule: str = "?") -> Any:
    """Value of ``expr``; ``env`` holds the variables, ``attributes`` the footprint attributes for ``attr()``."""
    if isinstance(expr, Const):
        return expr.value
    if isinstance(expr, Var):
        return env[expr.name]
    if isinstance(expr, Attr):
        value = attributes.get(expr.key)
        return "" if value is None else str(value)
    if isinstance(expr, Unary):
        value = evaluate(expr.operand, env, attributes, rule)
        return (not value) if expr.op == "not" else -_number(value, rule)
    if isinstance(expr, Binary):
        if expr.op in ("and", "or"):
            left = bool(evaluate(expr.left, env, attributes, rule))
            if left == (expr.op == "or"):  # short circuit
                return left
            return bool(evaluate(expr.right, env, attributes, rule))
        left = evaluate(expr.left, env, attributes, rule)
        right = evaluate(expr.right, env, attributes, rule)
        if expr.op in _ARITH:
            a, b = _number(left, rule), _number(right, rule)
            if expr.op == "/" and b == 0:
                raise RulesetError(f"division by zero in a condition of rule {rule}", where=expr.loc, plugin="split",
                                   hint="guard the division, e.g. 'face_width > 0 and 1 / face_width < 0.5'")
            return _ARITH[expr.op](a, b)
        return _compare(expr.op, left, right)
    raise TypeError(f"not an expression: {expr!r}")


def _number(value: Any, rule: str) -> float:
    if isinstance(value, str):
        converted = _as_number(value)
        if converted is None:
            raise RulesetError(f"rule {rule}: {value!r} is not a number", plugin="split",
                               hint="arithmetic needs numbers; compare strings with == or !=")
        return converted
    return float(value)


def _as_number(text: str) -> float | None:
    try:
        return float(text)
    except ValueError:
        return None


def _compare(op: str, left: Any, right: Any) -> bool:
    """Compare; a string meeting a number is read as a number, and is unequal to it when it is not one."""
    if isinstance(left, str) != isinstance(right, str):
        left = _as_number(left) if isinstance(left, str) else float(left)
        right = _as_number(right) if isinstance(right, str) else float(right)
        if left is None or right is None:
            return op == "!="
    return _COMPARE[op](left, right)
