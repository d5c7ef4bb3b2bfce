"""Safe, vectorised expressions in x, y, z, t for scene files, e.g. "x * sin(t)".

The text is parsed with ``ast`` and only numbers, the variables x, y, z, t (rest coordinates
and time), the constants pi and e, arithmetic (+ - * / ** %), comparisons, ``and``, ``or``,
``not`` (element by element: NumPy's logical_and, logical_or, logical_not), unary minus and
calls of a fixed set of NumPy functions are allowed; anything else (attributes, names,
subscripts, lambdas, imports) is refused before anything runs. Nothing goes through ``eval``
of user text: the checked tree is compiled and run with no builtins and only the names above.
"""

from __future__ import annotations

import ast
from collections.abc import Callable, Sequence

import numpy as np

from tissuesim.errors import SceneError
from tissuesim.validate import real, short

__all__ = ["compile_expression", "compile_named", "compile_vector", "FUNCTIONS"]

FUNCTIONS: dict[str, Callable] = {
    name: getattr(np, name)
    for name in (
        "sin cos tan arcsin arccos arctan arctan2 sinh cosh tanh exp log log10 sqrt abs "
        "sign minimum maximum floor ceil where heaviside clip"
    ).split()
}
FUNCTIONS["min"] = np.minimum
FUNCTIONS["max"] = np.maximum
# Number of arguments each function takes. Extra positional arguments are refused: for a ufunc
# the next one is ``out``, which would write into x, y or z (the caller's rest positions).
ARITY = {name: getattr(fn, "nin", None) for name, fn in FUNCTIONS.items()}
ARITY.update(where=3, clip=3)
CONSTANTS = {"pi": np.pi, "e": np.e}
VARIABLES = ("x", "y", "z", "t")
_ALLOWED = (
    ast.Expression,
    ast.BinOp,
    ast.UnaryOp,
    ast.Compare,
    ast.Call,
    ast.Name,
    ast.Load,
    ast.Constant,
    ast.Add,
    ast.Sub,
    ast.Mult,
    ast.Div,
    ast.Pow,
    ast.Mod,
    ast.USub,
    ast.UAdd,
    ast.Lt,
    ast.LtE,
    ast.Gt,
    ast.GtE,
    ast.Eq,
    ast.NotEq,
    ast.FloorDiv,
    ast.BoolOp,
    ast.And,
    ast.Or,
    ast.Not,
)
#: what and, or, not become: Python's would ask an array for one truth value
_LOGIC = {"_and": np.logical_and, "_or": np.logical_or, "_not": np.logical_not}


class _Logic(ast.NodeTransformer):
    """``a and b`` -> _and(a, b), ``a or b`` -> _or(a, b), ``not a`` -> _not(a)."""

    def visit_BoolOp(self, node: ast.BoolOp) -> ast.AST:
        self.generic_visit(node)
        name = "_and" if isinstance(node.op, ast.And) else "_or"
        out = node.values[0]
        for value in node.values[1:]:
            out = ast.Call(ast.Name(name, ast.Load()), [out, value], [])
        return ast.copy_location(out, node)

    def visit_UnaryOp(self, node: ast.UnaryOp) -> ast.AST:
        self.generic_visit(node)
        if isinstance(node.op, ast.Not):
            call = ast.Call(ast.Name("_not", ast.Load()), [node.operand], [])
            return ast.copy_location(call, node)
        return node


class _FloatLiterals(ast.NodeTransformer):
    def visit_Constant(self, node: ast.Constant) -> ast.Constant:
        if isinstance(node.value, int) and not isinstance(node.value, bool):
            return ast.copy_location(ast.Constant(float(node.value)), node)
        return node


def _checked_code(text: str, where: str, variables: Sequence[str]):
    """The compiled, checked tree of an expression in ``variables`` (SceneError otherwise)."""
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError as exc:
        raise SceneError(f"{where}: cannot parse expression {short(text)}: {exc.msg}") from None
    except (RecursionError, MemoryError):
        raise SceneError(
            f"{where}: expression {short(text)} is too long or too deeply nested"
        ) from None
    called = {id(n.func) for n in ast.walk(tree) if isinstance(n, ast.Call)}
    for node in ast.walk(tree):
        if not isinstance(node, _ALLOWED):
            raise SceneError(
                f"{where}: {type(node).__name__} is not allowed in expression {short(text)}; use "
                f"numbers, {', '.join(variables)}, pi, e, arithmetic, comparisons, and, or, "
                f"not and functions {', '.join(sorted(FUNCTIONS))}"
            )
        if isinstance(node, ast.Constant) and not isinstance(node.value, (int, float)):
            raise SceneError(f"{where}: only numeric constants are allowed in {short(text)}")
        if isinstance(node, ast.Compare) and len(node.ops) > 1:
            raise SceneError(
                f"{where}: chained comparison in {short(text)}; write e.g. 0 < x and x < 1"
            )
        if isinstance(node, ast.Call):
            if not (isinstance(node.func, ast.Name) and node.func.id in FUNCTIONS):
                name = getattr(node.func, "id", ast.unparse(node.func))
                raise SceneError(
                    f"{where}: unknown function {short(name)} in {short(text)}; "
                    f"allowed: {', '.join(sorted(FUNCTIONS))}"
                )
            name = node.func.id
            if node.keywords:
                raise SceneError(
                    f"{where}: keyword argument {short(node.keywords[0].arg)} of {name}() is not "
                    f"allowed in {short(text)}; pass arguments by position"
                )
            if len(node.args) != ARITY[name]:
                raise SceneError(
                    f"{where}: {name}() takes {ARITY[name]} argument(s), got {len(node.args)} "
                    f"in {short(text)}"
                )
        if isinstance(node, ast.Name) and node.id not in (*variables, *CONSTANTS, *FUNCTIONS):
            raise SceneError(
                f"{where}: unknown name {short(node.id)} in {short(text)}; variables are "
                f"{', '.join(variables)} and constants pi, e"
            )
        if isinstance(node, ast.Name) and node.id in FUNCTIONS and id(node) not in called:
            raise SceneError(
                f"{where}: {node.id!r} is a function: call it, e.g. {node.id}(x), in {short(text)}"
            )
    # Integer literals become floats so that "9**9**9" overflows at once instead of running
    # Python's unbounded integer power.
    try:
        tree = ast.fix_missing_locations(_Logic().visit(_FloatLiterals().visit(tree)))
        code = compile(tree, f"<{where}>", "eval")
    except (RecursionError, MemoryError):
        raise SceneError(f"{where}: expression {short(text)} is too deeply nested") from None

    return code


def compile_expression(text: str | float | int, where: str) -> Callable:
    """A function f(X (k, d), t) -> (k,) from an expression; ``where`` names it in errors."""
    if isinstance(text, bool) or not isinstance(text, (str, int, float)):
        raise SceneError(f"{where}: expected a number or an expression string, got {short(text)}")
    if not isinstance(text, str):
        value = real(text, where)
        return lambda X, t: np.full(X.shape[0], value)
    code = _checked_code(text, where, VARIABLES)

    def f(X: np.ndarray, t: float) -> np.ndarray:
        X = np.array(X, dtype=float)  # a copy: nothing here may write into the caller's array
        names = {**CONSTANTS, **FUNCTIONS, **_LOGIC, "t": float(t)}
        for i, v in enumerate(VARIABLES[:3]):
            names[v] = X[:, i] if i < X.shape[1] else np.zeros(X.shape[0])
        try:
            with np.errstate(all="ignore"):
                out = eval(code, {"__builtins__": {}}, names)  # checked tree, restricted names
            return np.broadcast_to(np.asarray(out, dtype=float), (X.shape[0],))
        except (ArithmeticError, ValueError, TypeError) as exc:
            raise SceneError(f"{where}: evaluating {short(text)} failed: {exc}") from None

    return f


def compile_vector(items: Sequence, dim: int, where: str) -> Callable:
    """f(X (k, d), t) -> (k, d) from ``dim`` expressions or numbers."""
    if isinstance(items, (str, int, float)) or len(items) != dim:
        raise SceneError(
            f"{where}: expected a list of {dim} numbers or expressions (one per axis), "
            f"got {short(items)}"
        )
    parts = [compile_expression(item, f"{where}[{i}]") for i, item in enumerate(items)]

    def f(X: np.ndarray, t: float) -> np.ndarray:
        return np.stack([p(X, t) for p in parts], axis=1)

    return f


def compile_named(text: str, variables: Sequence[str], where: str, real: bool = True):
    """(f, used): an expression of the named ``variables`` (any names, e.g. FEBio's logged
    ``sx``, ``sy``), checked as ``compile_expression``'s, as f(values: name -> array) -> array,
    and the variables it uses in order of first use; ``real`` False lets complex values
    through (a complex-step derivative)."""
    if not isinstance(text, str) or not text.strip():
        raise SceneError(f"{where}: expected an expression string, got {short(text)}")
    code = _checked_code(text, where, tuple(variables))
    used = list(dict.fromkeys(n.id for n in ast.walk(ast.parse(text.strip(), mode="eval"))
                              if isinstance(n, ast.Name) and n.id in variables))  # fmt: skip

    def f(values) -> np.ndarray:
        names = {**CONSTANTS, **FUNCTIONS, **_LOGIC}
        kind = float if real else None
        names.update({k: np.asarray(values[k], dtype=kind) for k in used})
        try:
            with np.errstate(all="ignore"):
                return np.asarray(eval(code, {"__builtins__": {}}, names), dtype=kind)
        except (ArithmeticError, ValueError, TypeError) as exc:
            raise SceneError(f"{where}: evaluating {short(text)} failed: {exc}") from None

    return f, used
