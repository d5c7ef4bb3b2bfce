"""A strain-energy density as a SymPy expression, and its derivatives (``EnergyLaw``'s algebra).

The text of psi is parsed with ``ast`` and turned into SymPy by walking the checked tree: only
numbers, names, arithmetic (+ - * / **), unary minus and calls of ``FUNCTIONS`` are allowed,
and nothing of the user's text goes through ``eval`` (SymPy's own ``parse_expr`` does, so it is
not used). A Python callable is called once with SymPy objects for its arguments instead.

The variables psi may use (3D invariants of C = F^T F; in 2D those of plane strain, F_33 = 1):

    I1, I2, I3, J        I1 = tr C, I2 = (I1^2 - C:C)/2, I3 = det C = J^2, J = det F
    I1b, I2b             the isochoric invariants J^(-2/3) I1, J^(-4/3) I2
    F11 .. F33           the components of F (row, column from 1)
    C11 .. C33           the components of C
    pi, e                the constants

Any other name is a parameter, given by keyword with its value. Two derivations:

- **invariants**: psi of I1, I2, I3, J, I1b, I2b only is rewritten as W(I1, I2, J) and
  differentiated to the 9 scalars (W1, W2, WJ, W11, W12, W22, W1J, W2J, WJJ); the tensors follow
  from the chain rule the built-in soft-tissue laws use (``_hyperelastic.invariant_tensors``).
- **components**: psi that uses F_ij or C_ij is written in the d x d components of F and
  differentiated to every P_ij and the upper triangle of dP/dF (the rest by symmetry).
"""

from __future__ import annotations

import ast
import inspect
from collections.abc import Callable
from dataclasses import dataclass

from tissuesim.errors import MaterialError
from tissuesim.validate import short

__all__ = ["FUNCTIONS", "VARIABLES", "Derivation", "parse_energy", "derive"]

#: the functions psi may call, by name -> SymPy's name
FUNCTIONS = {
    "log": "log",
    "ln": "log",
    "exp": "exp",
    "sqrt": "sqrt",
    "cbrt": "cbrt",
    "sin": "sin",
    "cos": "cos",
    "tan": "tan",
    "sinh": "sinh",
    "cosh": "cosh",
    "tanh": "tanh",
    "atan": "atan",
    "asinh": "asinh",
}
INVARIANTS = ("I1", "I2", "I3", "J", "I1b", "I2b")
COMPONENTS = tuple(f"{m}{i}{j}" for m in "FC" for i in (1, 2, 3) for j in (1, 2, 3))
VARIABLES = INVARIANTS + COMPONENTS
CONSTANTS = ("pi", "e")
#: a callable's arguments that receive F and C as 3 x 3 SymPy matrices
MATRICES = ("F", "C")
_ALLOWED = (
    ast.Expression, ast.BinOp, ast.UnaryOp, ast.Call, ast.Name, ast.Load, ast.Constant,
    ast.Add, ast.Sub, ast.Mult, ast.Div, ast.Pow, ast.USub, ast.UAdd,
)  # fmt: skip
HOW = (
    "write psi with numbers, + - * / **, the variables I1, I2, I3, J, I1b, I2b, F11..F33, "
    "C11..C33, the parameters, and " + ", ".join(sorted(FUNCTIONS))
)


def _sympy():
    try:
        import sympy
    except ImportError:
        raise MaterialError(
            "a law from its energy needs SymPy: pip install 'tissuesim[energy]' (or sympy)"
        ) from None
    return sympy


def _to_sympy(node: ast.AST, sp, text: str):
    """The SymPy expression of a checked ``ast`` node (names become Symbols)."""
    if isinstance(node, ast.Expression):
        return _to_sympy(node.body, sp, text)
    if isinstance(node, ast.Constant):
        if isinstance(node.value, bool) or not isinstance(node.value, (int, float)):
            raise MaterialError(f"psi: only numbers are allowed as constants in {short(text)}")
        return sp.Integer(node.value) if isinstance(node.value, int) else sp.Float(node.value)
    if isinstance(node, ast.Name):
        if node.id == "pi":
            return sp.pi
        if node.id == "e":
            return sp.E
        return sp.Symbol(node.id, real=True)
    if isinstance(node, ast.UnaryOp):
        value = _to_sympy(node.operand, sp, text)
        return -value if isinstance(node.op, ast.USub) else value
    if isinstance(node, ast.BinOp):
        a, b = _to_sympy(node.left, sp, text), _to_sympy(node.right, sp, text)
        if isinstance(node.op, ast.Add):
            return a + b
        if isinstance(node.op, ast.Sub):
            return a - b
        if isinstance(node.op, ast.Mult):
            return a * b
        return a / b if isinstance(node.op, ast.Div) else a**b
    assert isinstance(node, ast.Call)  # the tree was checked: nothing else is left
    args = [_to_sympy(a, sp, text) for a in node.args]
    return getattr(sp, FUNCTIONS[node.func.id])(*args)


def parse_energy(text: str):
    """psi as a SymPy expression of Symbols named as written; one-line MaterialError for text
    that is not an allowed expression (syntax, a disallowed construct, an unknown function)."""
    sp = _sympy()
    if not isinstance(text, str) or not text.strip():
        raise MaterialError(f"psi must be an expression string, e.g. 'mu/2*(I1 - 3)'; {HOW}")
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError as exc:
        raise MaterialError(f"psi: cannot parse {short(text)}: {exc.msg}; {HOW}") from None
    except (RecursionError, MemoryError):
        raise MaterialError(f"psi: {short(text)} is too long or too deeply nested") from None
    for node in ast.walk(tree):
        if not isinstance(node, _ALLOWED):
            what = type(node).__name__
            hint = " (a scalar is needed)" if what in ("Tuple", "List", "Dict", "Set") else ""
            raise MaterialError(f"psi: {what} is not allowed in {short(text)}{hint}; {HOW}")
        if isinstance(node, ast.Call):
            name = getattr(node.func, "id", None)
            if name not in FUNCTIONS:
                shown = name or ast.unparse(node.func)
                raise MaterialError(
                    f"psi: unknown function {short(shown)} in {short(text)}; allowed: "
                    f"{', '.join(sorted(FUNCTIONS))}"
                )
            if node.keywords or len(node.args) != 1:
                raise MaterialError(f"psi: {name}() takes one argument, in {short(text)}")
    try:
        return _to_sympy(tree, sp, text)
    except (RecursionError, MemoryError):
        raise MaterialError(f"psi: {short(text)} is too long or too deeply nested") from None
    except (TypeError, ValueError, ZeroDivisionError, OverflowError) as exc:
        raise MaterialError(f"psi: SymPy cannot build {short(text)}: {exc}") from None


def call_energy(fun: Callable, parameters: dict[str, float]):
    """psi from a callable: its arguments named as variables get SymPy objects (F and C as
    3 x 3 matrices, the rest as Symbols, resolved as in text), the others are parameters."""
    sp = _sympy()
    try:
        names = list(inspect.signature(fun).parameters)
    except (TypeError, ValueError):
        raise MaterialError(f"psi must be a string or a function, not {short(fun)}") from None
    args = {}
    for name in names:
        if name in MATRICES:
            args[name] = sp.Matrix(3, 3, lambda i, j, m=name: sp.Symbol(f"{m}{i + 1}{j + 1}"))
        elif name not in VARIABLES and name not in parameters:
            raise MaterialError(
                f"psi: the function's argument {name!r} is neither a variable (F, C, "
                f"{', '.join(INVARIANTS)}) nor a given parameter; give it, e.g. {name}=1.0"
            )
        else:
            args[name] = sp.Symbol(name, real=True)
    try:
        psi = fun(**args)
    except Exception as exc:  # the user's code: say what it raised, in one line
        raise MaterialError(f"psi: the function raised {type(exc).__name__}: {exc}") from None
    try:
        psi = sp.sympify(psi, strict=True)
    except (sp.SympifyError, TypeError):
        psi = None
    if psi is None or not isinstance(psi, sp.Expr) or psi.is_Matrix:
        raise MaterialError("psi: the function must return a scalar SymPy expression")
    return psi.subs({s: sp.Symbol(s.name, real=True) for s in psi.free_symbols})


@dataclass(frozen=True)
class Derivation:
    """psi and its derivatives for one dimension, as SymPy expressions.

    kind "invariants": ``args`` are the Symbols (I1, I2, J), ``energy`` psi and ``first``
    (W1, W2, WJ), ``second`` (W11, W12, W22, W1J, W2J, WJJ). kind "components": ``args`` are
    the d*d Symbols of F row by row, ``first`` the d*d P_ij and ``second`` the upper triangle
    of dP/dF over the flattened index (``pairs``)."""

    kind: str
    dim: int
    args: tuple
    parameters: tuple  # Symbols, sorted by name
    energy: object
    first: tuple
    second: tuple
    pairs: tuple  # ((a, b), ...) of the upper triangle, components only
    uses_i2: bool = True


def check_symbols(psi, parameters: dict[str, float]) -> None:
    """Every name of psi a variable or a given parameter, every parameter used, psi a scalar
    that depends on the deformation."""
    import sympy as sp

    if getattr(psi, "is_Matrix", False):
        raise MaterialError("psi must be a scalar, not a matrix")
    if psi.has(sp.I, sp.zoo, sp.nan, sp.oo, -sp.oo):
        raise MaterialError(
            "psi has an imaginary or infinite constant (a root of a negative number, a division "
            "by zero?); correct the expression"
        )
    names = {s.name for s in psi.free_symbols}
    unknown = sorted(names - set(VARIABLES) - set(parameters))
    if unknown:
        raise MaterialError(
            f"psi uses {unknown[0]!r}, neither a variable ({', '.join(INVARIANTS)}, F11..F33, "
            f"C11..C33) nor a given parameter; give it (e.g. {unknown[0]} = 1.0) or correct "
            "the expression"
        )
    unused = sorted(set(parameters) - names)
    if unused:
        raise MaterialError(
            f"parameter {unused[0]!r} is not used in psi; remove it or correct the expression"
        )
    if not names & set(VARIABLES):
        raise MaterialError(
            "psi does not depend on the deformation; use the variables I1, I2, J, I1b, I2b, "
            "F11..F33 or C11..C33"
        )


def derive(psi, parameter_names: list[str], dim: int) -> Derivation:
    """The derivatives of psi (from ``parse_energy`` or ``call_energy``) in ``dim`` = 2, 3."""
    sp = _sympy()
    syms = {s.name: s for s in psi.free_symbols}
    params = tuple(sp.Symbol(n, real=True) for n in sorted(parameter_names))
    names = set(syms)
    # the derivation's own symbols start with "_": no parameter may (EnergyLaw checks)
    I1, I2 = sp.Symbol("_I1", real=True), sp.Symbol("_I2", real=True)
    J = sp.Symbol("_J", positive=True)
    iso = {
        "I1": I1,
        "I2": I2,
        "J": J,
        "I3": J**2,
        "I1b": I1 * J ** sp.Rational(-2, 3),
        "I2b": I2 * J ** sp.Rational(-4, 3),
    }
    if not names & set(COMPONENTS):
        W = psi.subs({syms[n]: iso[n] for n in names if n in iso})
        first = tuple(sp.diff(W, v) for v in (I1, I2, J))
        second = tuple(
            sp.diff(first[a], v) for a, v in ((0, I1), (0, I2), (1, I2), (0, J), (1, J), (2, J))
        )
        return Derivation("invariants", dim, (I1, I2, J), params, W, first, second, (), W.has(I2))
    Fs = [sp.Symbol(f"_F{i}{j}", real=True) for i in range(dim) for j in range(dim)]
    F = sp.eye(3)
    for i in range(dim):
        for j in range(dim):
            F[i, j] = Fs[i * dim + j]
    C = F.T * F
    i1 = C.trace()
    i2 = (i1**2 - (C * C).trace()) / 2
    j = F.det()
    values = {
        "I1": i1,
        "I2": i2,
        "J": j,
        "I3": j**2,
        "I1b": i1 * j ** sp.Rational(-2, 3),
        "I2b": i2 * j ** sp.Rational(-4, 3),
        **{f"F{a + 1}{b + 1}": F[a, b] for a in range(3) for b in range(3)},
        **{f"C{a + 1}{b + 1}": C[a, b] for a in range(3) for b in range(3)},
    }
    W = psi.subs({syms[n]: values[n] for n in names if n in values})
    first = tuple(sp.diff(W, f) for f in Fs)
    n = dim * dim
    pairs = tuple((a, b) for a in range(n) for b in range(a, n))
    second = tuple(sp.diff(first[a], Fs[b]) for a, b in pairs)
    return Derivation("components", dim, tuple(Fs), params, W, first, second, pairs)
