"""Discrete springs between vertices of one FEM body, or from a vertex to a fixed point: FEBio's
discrete elements (``FESpringMaterial``, ``FENonlinearSpringMaterial``) as an energy.

A spring of rest length L0 between x_a and x_b (length l = |x_b - x_a|, direction e) carries
the force f(DL) along e, DL = l - L0; its energy is W(DL) = int_0^DL f. The laws
(``SpringLaw``): linear, f = E DL (FELinearSpring); tension-only, f = E max(DL, 0)
(FETensionOnlyLinearSpring); a force curve, f = scale F(s) of the measure s = DL
(elongation), DL / L0 (strain) or l / L0 (stretch) (FENonlinearSpringMaterial), its energy
the curve's exact integral (``ForceCurve``: polynomial pieces), or of an expression of the
measure (``ExpressionForce``: FEBio's math force). The gradient is -f e at a and
f e at b; the Hessian's block K = f'(DL) e e^T + f / l (I - e e^T), [[K, -K], [-K, K]] over
(a, b) (FESpringMaterial::Stiffness); projected, f' and f / l are clamped at zero.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from tissuesim.energies.accumulator import Accumulator
from tissuesim.errors import InputError

__all__ = ["ForceCurve", "ExpressionForce", "SpringLaw", "NodeSprings", "spring_stencil"]

MEASURES = ("elongation", "strain", "stretch")


@dataclass(frozen=True, eq=False)
class ForceCurve:
    """A piecewise polynomial force F(s) (N) with its derivative and its exact integral:
    ``breaks`` (n + 1,) increasing, ``coefficients`` (n, degree + 1) per piece in powers of
    (s - breaks[i]) (highest first, numpy's order); beyond the ends constant (``extend``
    "constant") or linear with the end piece's slope ("extrapolate")."""

    breaks: np.ndarray
    coefficients: np.ndarray
    extend: str = "constant"

    @classmethod
    def from_function(
        cls, f: Callable[[np.ndarray], np.ndarray], breaks, degree: int = 5, extend="constant"
    ) -> ForceCurve:
        """The polynomial pieces of degree ``degree`` through f at Chebyshev points of each
        interval: exact for a curve polynomial of that degree on each (FEBio's point curves:
        linear, step, smooth (cubic at most), smooth step (quintic))."""
        b = np.asarray(breaks, dtype=float)
        if b.ndim != 1 or b.size < 2 or np.any(np.diff(b) <= 0):
            raise InputError("a force curve needs at least two increasing breakpoints")
        k = np.arange(degree + 1)
        u = 0.5 - 0.5 * np.cos((2 * k + 1) * np.pi / (2 * degree + 2))  # in (0, 1)
        coefficients = []
        for lo, hi in zip(b[:-1], b[1:], strict=True):
            s = lo + (hi - lo) * u
            coefficients.append(np.polyfit(s - lo, np.asarray(f(s), dtype=float), degree))
        if extend not in ("constant", "extrapolate"):
            raise InputError(f"force curve extend must be constant or extrapolate, not {extend!r}")
        return cls(b, np.array(coefficients), extend)

    def _piece(self, s: np.ndarray):
        i = np.clip(np.searchsorted(self.breaks, s, side="right") - 1, 0, len(self.breaks) - 2)
        lo, hi = self.breaks[0], self.breaks[-1]
        t = np.clip(s, lo, hi)
        return i, t - self.breaks[i], t

    def _polyval(self, c: np.ndarray, x: np.ndarray) -> np.ndarray:
        y = np.zeros_like(x)
        for j in range(c.shape[1]):
            y = y * x + c[:, j]
        return y

    def value(self, s: np.ndarray) -> np.ndarray:
        s = np.asarray(s, dtype=float)
        i, x, t = self._piece(s)
        y = self._polyval(self.coefficients[i], x)
        if self.extend == "extrapolate":
            y = y + self.slope_at_end(s, i, x) * (s - t)
        return y

    def slope_at_end(self, s: np.ndarray, i: np.ndarray, x: np.ndarray) -> np.ndarray:
        """The end piece's slope where s lies beyond the curve (0 inside)."""
        d = self._polyval(self._derivative()[i], x)
        return np.where((s < self.breaks[0]) | (s > self.breaks[-1]), d, 0.0)

    def _derivative(self) -> np.ndarray:
        c = self.coefficients
        m = c.shape[1] - 1
        return c[:, :-1] * np.arange(m, 0, -1)

    def derivative(self, s: np.ndarray) -> np.ndarray:
        s = np.asarray(s, dtype=float)
        i, x, t = self._piece(s)
        d = self._polyval(self._derivative()[i], x)
        outside = (s < self.breaks[0]) | (s > self.breaks[-1])
        return np.where(outside, d if self.extend == "extrapolate" else 0.0, d)

    def _antiderivative_at(self, s: np.ndarray) -> np.ndarray:
        """G(s) = int_{breaks[0]}^s F over the curve's range and beyond."""
        c = self.coefficients
        m = c.shape[1]
        integral = np.concatenate([c / np.arange(m, 0, -1), np.zeros((len(c), 1))], axis=1)
        widths = np.diff(self.breaks)
        whole = np.array([self._polyval(integral[k : k + 1], widths[k : k + 1])[0]
                          for k in range(len(c))])  # fmt: skip
        before = np.concatenate([[0.0], np.cumsum(whole)])
        i, x, t = self._piece(s)
        g = before[i] + self._polyval(integral[i], x)
        lo, hi = self.breaks[0], self.breaks[-1]
        f_lo, f_hi = self.value(np.array([lo]))[0], self.value(np.array([hi]))[0]
        below, above = np.minimum(s - lo, 0.0), np.maximum(s - hi, 0.0)
        g = g + f_lo * below + f_hi * above
        if self.extend == "extrapolate":
            d = self.derivative(np.array([lo, hi]))
            g = g + 0.5 * d[0] * below**2 + 0.5 * d[1] * above**2
        return g

    def integral(self, s0: np.ndarray, s1: np.ndarray) -> np.ndarray:
        """int_{s0}^{s1} F, exact."""
        return self._antiderivative_at(np.asarray(s1, float)) - self._antiderivative_at(
            np.asarray(s0, float)
        )


#: functions through which a complex step differentiates exactly (analytic ones)
_ANALYTIC = {"sin", "cos", "tan", "arcsin", "arccos", "arctan", "sinh", "cosh", "tanh", "exp",
             "log", "log10", "sqrt"}  # fmt: skip


class ExpressionForce:
    """A force F(s) (N) given as an expression of the measure ``x`` (FEBio's math force of a
    nonlinear spring, e.g. "2 * (exp(50 * x) - 1)"), checked as the scene's expressions are
    (``scene/expressions.py``). F' by a complex step where the expression is analytic (exact to
    round-off), else by central differences; the energy's integral by composite
    Gauss-Legendre (16 panels of 8 points: round-off for smooth F)."""

    PANELS, POINTS = 16, 8

    def __init__(self, text: str, where: str = "force") -> None:
        import ast

        from tissuesim.scene.expressions import compile_named

        self.text = text
        self._f, _ = compile_named(text, ("x",), where, real=False)
        calls = {n.func.id for n in ast.walk(ast.parse(text.strip(), mode="eval"))
                 if isinstance(n, ast.Call) and isinstance(n.func, ast.Name)}  # fmt: skip
        comparisons = any(isinstance(n, ast.Compare | ast.BoolOp)
                          for n in ast.walk(ast.parse(text.strip(), mode="eval")))  # fmt: skip
        self.analytic = calls <= _ANALYTIC and not comparisons
        xi, w = np.polynomial.legendre.leggauss(self.POINTS)
        self._xi, self._w = xi, w

    def _eval(self, s: np.ndarray) -> np.ndarray:
        return np.broadcast_to(self._f({"x": s}), np.shape(s))

    def value(self, s: np.ndarray) -> np.ndarray:
        return np.asarray(self._eval(np.asarray(s, dtype=float)), dtype=float)

    def derivative(self, s: np.ndarray) -> np.ndarray:
        s = np.asarray(s, dtype=float)
        if self.analytic:
            h = 1e-30
            return np.imag(self._eval(s + 1j * h)) / h
        h = 1e-6 * (1.0 + np.abs(s))
        return (self.value(s + h) - self.value(s - h)) / (2.0 * h)

    def integral(self, s0: np.ndarray, s1: np.ndarray) -> np.ndarray:
        """int_{s0}^{s1} F by composite Gauss-Legendre."""
        s0, s1 = np.broadcast_arrays(np.asarray(s0, float), np.asarray(s1, float))
        edges = s0[..., None] + (s1 - s0)[..., None] * np.linspace(0, 1, self.PANELS + 1)
        lo, hi = edges[..., :-1, None], edges[..., 1:, None]
        points = 0.5 * (lo + hi) + 0.5 * (hi - lo) * self._xi
        return (0.5 * (hi - lo)[..., 0] * (self.value(points) @ self._w)).sum(axis=-1)


@dataclass(frozen=True, eq=False)
class SpringLaw:
    """A spring's force as a function of its elongation DL: ``kind`` "linear" (``stiffness``
    E, N/m), "tension_only" (E, no force in compression) or "curve" (``scale`` times
    ``curve`` F of the ``measure``)."""

    kind: str
    stiffness: float = 0.0
    curve: ForceCurve | ExpressionForce | None = None
    measure: str = "elongation"
    scale: float = 1.0

    def __post_init__(self) -> None:
        if self.kind not in ("linear", "tension_only", "curve"):
            raise InputError(f"spring law must be linear, tension_only or curve, not {self.kind!r}")
        if self.kind != "curve" and not (np.isfinite(self.stiffness) and self.stiffness > 0):
            raise InputError(f"spring stiffness must be > 0 N/m, got {self.stiffness!r}")
        if self.kind == "curve" and (self.curve is None or self.measure not in MEASURES):
            raise InputError(f"a spring force curve needs a curve and a measure in {MEASURES}")

    def evaluate(self, dl: np.ndarray, rest: np.ndarray):
        """(W, f, f') per spring at elongations dl (k,) of rest lengths ``rest`` (k,)."""
        if self.kind == "linear":
            E = self.stiffness
            return 0.5 * E * dl**2, E * dl, np.full_like(dl, E)
        if self.kind == "tension_only":
            E = self.stiffness
            on = dl >= 0.0
            return np.where(on, 0.5 * E * dl**2, 0.0), np.where(on, E * dl, 0.0), E * on
        c, a = self.curve, self.scale
        if self.measure == "elongation":
            s, ds, s0 = dl, np.ones_like(dl), np.zeros_like(dl)
        else:
            if np.any(rest <= 0):
                raise InputError(f"a spring of zero rest length has no {self.measure}")
            s = dl / rest if self.measure == "strain" else 1.0 + dl / rest
            ds, s0 = 1.0 / rest, np.zeros_like(dl) if self.measure == "strain" else np.ones_like(dl)
        # W = int_0^DL a F(s(l)) dl = a / s'(l) int_{s(0)}^{s} F (s is affine in l)
        return a * c.integral(s0, s) / ds, a * c.value(s), a * c.derivative(s) * ds


def spring_stencil(pairs: np.ndarray, dim: int) -> np.ndarray:
    """The DOFs (k, 2 d) of vertex pairs (k, 2): a Hessian stencil of the body's pattern."""
    return (np.asarray(pairs)[:, :, None] * dim + np.arange(dim)).reshape(len(pairs), -1)


@dataclass(frozen=True, eq=False)
class NodeSprings:
    """Springs of one ``law`` in a body of dimension ``dim``: ``pairs`` (k, 2) vertices (the
    second -1 for a spring to the fixed point ``anchors[i]``), ``rest`` (k,) rest lengths (m),
    ``name`` the energy term. The body's pattern must hold the pairs' blocks
    (``spring_stencil``)."""

    pairs: np.ndarray
    rest: np.ndarray
    law: SpringLaw
    anchors: np.ndarray | None = None
    name: str = "springs"
    dim: int = 3
    #: t -> the factor on the whole law at time t (None: 1; FEBio's node distance penalty
    #: on a load curve), and that factor for the step being solved (``at``)
    scale: Callable[[float], float] | None = None
    factor: float = 1.0

    def at(self, t: float) -> NodeSprings:
        """These springs at time t: the law times ``scale(t)``."""
        if self.scale is None:
            return self
        from dataclasses import replace

        factor = float(self.scale(t))
        if not np.isfinite(factor):
            raise InputError(f"{self.name}: the stiffness scale is not finite at t = {t:g}")
        return replace(self, factor=factor)

    def _ends(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        X = x.reshape(-1, self.dim)
        second = self.pairs[:, 1:] >= 0
        b = X[np.maximum(self.pairs[:, 1], 0)]
        if self.anchors is not None:
            b = np.where(second, b, self.anchors)
        return X[self.pairs[:, 0]], b

    def tensions(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(f (k,) N, unit directions e (k, d) from the first end to the second)."""
        a, b = self._ends(x)
        r = b - a
        length = np.linalg.norm(r, axis=1)
        _, f, _ = self.law.evaluate(length - self.rest, self.rest)
        zero = length == 0.0
        return np.where(zero, 0.0, self.factor * f), r / np.where(zero, 1.0, length)[:, None]

    def accumulate(self, x: np.ndarray, acc: Accumulator) -> None:
        d = self.dim
        a, b = self._ends(x)
        r = b - a
        length = np.linalg.norm(r, axis=1)
        W, f, df = self.law.evaluate(length - self.rest, self.rest)
        if self.factor != 1.0:
            W, f, df = self.factor * W, self.factor * f, self.factor * df
        acc.add_value(self.name, float(W.sum()))
        if acc.order < 1:
            return
        zero = length == 0.0
        e = r / np.where(zero, 1.0, length)[:, None]
        f = np.where(zero, 0.0, f)
        two = self.pairs[:, 1] >= 0
        dofs = self.pairs[:, :, None] * d + np.arange(d)  # (k, 2, d)
        np.add.at(acc.gradient, dofs[:, 0], -f[:, None] * e)
        np.add.at(acc.gradient, dofs[two, 1], f[two, None] * e[two])
        if acc.order < 2:
            return
        # K = f' e e^T + f / l (I - e e^T); at l = 0 (coincident ends, L0 = 0) its limit f' I
        axial, lateral = df, np.where(zero, df, f / np.where(zero, 1.0, length))
        if acc.project:
            axial, lateral = np.maximum(axial, 0.0), np.maximum(lateral, 0.0)
        ee = e[:, :, None] * e[:, None, :]
        K = axial[:, None, None] * ee + lateral[:, None, None] * (np.eye(d) - ee)
        one = dofs[~two, 0]
        rows, cols, data = [one[:, :, None] + 0 * one[:, None, :]], [], [K[~two]]
        cols.append(one[:, None, :] + 0 * one[:, :, None])
        if np.any(two):
            both = dofs[two].reshape(-1, 2 * d)  # (m, 2 d): a's DOFs then b's
            rows.append(both[:, :, None] + 0 * both[:, None, :])
            cols.append(both[:, None, :] + 0 * both[:, :, None])
            data.append(np.block([[K[two], -K[two]], [-K[two], K[two]]]))
        r_all = np.concatenate([v.ravel() for v in rows])
        c_all = np.concatenate([v.ravel() for v in cols])
        np.add.at(
            acc.hessian,
            acc.pattern.positions(r_all, c_all),
            np.concatenate([v.ravel() for v in data]),
        )
