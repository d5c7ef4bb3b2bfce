"""FEBio's element-data expressions (``FELogElemMath``: ``"=sx+sy+sz"``) read safely: numbers,
the variables named, + - * / and ^ (a power, as FEBio writes it), parentheses and the
functions sqrt, abs, exp, log; anything else is refused in one line. Evaluated on NumPy arrays
(one value per element)."""

from __future__ import annotations

import ast
from collections.abc import Container, Mapping

import numpy as np

from tissuesim.errors import InputError

__all__ = ["names_in", "evaluate"]

_FUNCTIONS = {"sqrt": np.sqrt, "abs": np.abs, "exp": np.exp, "log": np.log}
_BINARY = {
    ast.Add: np.add, ast.Sub: np.subtract, ast.Mult: np.multiply, ast.Div: np.divide,
    ast.Pow: np.power,
}  # fmt: skip


def _tree(expression: str, what: str) -> ast.Expression:
    if not isinstance(expression, str) or not expression.strip():
        raise InputError(f"{what}: give a variable or an expression of variables, not "
                         f"{expression!r}")  # fmt: skip
    try:
        return ast.parse(expression.replace("^", "**"), mode="eval")
    except SyntaxError:
        raise InputError(f"{what}: {expression!r} is not an expression (+ - * / ^, numbers, "
                         "variables, sqrt abs exp log)") from None  # fmt: skip


def names_in(expression: str, allowed: Container[str], what: str) -> list[str]:
    """The variables ``expression`` uses, in order of first use; InputError for a variable not
    in ``allowed`` or an operation the evaluator does not take."""
    names: list[str] = []
    for node in ast.walk(_tree(expression, what)):
        if isinstance(node, ast.Call):
            if not (isinstance(node.func, ast.Name) and node.func.id in _FUNCTIONS) or (
                len(node.args) != 1 or node.keywords
            ):
                raise InputError(f"{what}: {expression!r}: only sqrt, abs, exp, log of one "
                                 "argument are taken")  # fmt: skip
        elif isinstance(node, ast.Name):
            if node.id in _FUNCTIONS:
                continue
            if node.id not in allowed:
                raise InputError(f"{what}: {node.id!r} is not a variable tissuesim logs; it "
                                 f"logs {', '.join(sorted(allowed))}")  # fmt: skip
            if node.id not in names:
                names.append(node.id)
        elif isinstance(node, ast.Constant):
            if isinstance(node.value, bool) or not isinstance(node.value, (int, float)):
                raise InputError(f"{what}: {expression!r}: only numbers are taken as constants")
        elif isinstance(node, ast.BinOp):
            if type(node.op) not in _BINARY:
                raise InputError(f"{what}: {expression!r}: only + - * / ^ are taken")
        elif isinstance(node, ast.UnaryOp):
            if not isinstance(node.op, (ast.UAdd, ast.USub)):
                raise InputError(f"{what}: {expression!r}: only + - * / ^ are taken")
        elif not isinstance(node, (ast.Expression, ast.Load, ast.operator, ast.unaryop)):
            raise InputError(f"{what}: {expression!r}: not a plain arithmetic expression")
    if not names:
        raise InputError(f"{what}: {expression!r} names no variable")
    return names


def evaluate(expression: str, values: Mapping[str, np.ndarray]) -> np.ndarray:
    """The expression on arrays (checked by ``names_in`` first)."""

    def walk(node: ast.AST):
        if isinstance(node, ast.Expression):
            return walk(node.body)
        if isinstance(node, ast.Constant):
            return float(node.value)
        if isinstance(node, ast.Name):
            return np.asarray(values[node.id], dtype=float)
        if isinstance(node, ast.BinOp):
            return _BINARY[type(node.op)](walk(node.left), walk(node.right))
        if isinstance(node, ast.UnaryOp):
            inner = walk(node.operand)
            return -inner if isinstance(node.op, ast.USub) else inner
        if isinstance(node, ast.Call):
            return _FUNCTIONS[node.func.id](walk(node.args[0]))
        raise InputError(f"not a plain arithmetic expression: {expression!r}")

    return walk(_tree(expression, "expression"))
