"""A law from its strain-energy density: the user writes psi, SymPy derives P and dP/dF.

    EnergyLaw("mu/2*(I1 - 3) - mu*log(J) + lam/2*log(J)**2", mu=400.0, lam=600.0)
    EnergyLaw(lambda C, k1: k1 * (C11 - 1)**2 ...)            # or a function of SymPy objects
    [material] model = "energy", psi = "...", mu = 400.0, lam = 600.0      (a scene)

psi is a string parsed safely (``energy_expr.py``: no ``eval`` of the text) or a Python
function called once with SymPy objects; its variables are the invariants I1, I2, I3, J, I1b,
I2b and the components F11..F33, C11..C33, every other name a parameter given by keyword.
SymPy differentiates it once per dimension (2D: plane strain, F_33 = 1); the derivatives are
compiled to NumPy by ``sympy.lambdify`` with common subexpressions, and, with the Numba
backend, to a point kernel the fused assembly calls (``energy_kernel.py``).

The law is checked as the built-in ones are: the rest state must be stress-free, the
small-strain shear and bulk moduli (``mu``, ``lam`` read off dP/dF at F = I; averaged over
directions for an anisotropic psi) positive, and a psi of F's components objective (checked
on random rotations; C's components and the invariants are objective by construction).
The law is undefined where J <= 0 or psi is not finite: energy +inf there, and stress or
tangent raise ``InvertedElementError``, as for the neo-Hookean law.
"""

from __future__ import annotations

import keyword
import math
from collections.abc import Callable

import numpy as np

from tissuesim.errors import InvertedElementError, MaterialError
from tissuesim.materials.base import Material, MaterialResponse
from tissuesim.materials.energy_law.energy_expr import (
    CONSTANTS,
    FUNCTIONS,
    MATRICES,
    VARIABLES,
    Derivation,
    call_energy,
    check_symbols,
    derive,
    parse_energy,
)
from tissuesim.materials.isotropic._common import check_input, cofactor, det
from tissuesim.materials.soft_tissue._hyperelastic import invariant_tensors, parameter
from tissuesim.validate import short

__all__ = ["EnergyLaw", "from_energy"]


class _Compiled:
    """One dimension's derivation and its NumPy functions (``lambdify`` with CSE)."""

    def __init__(self, derivation: Derivation) -> None:
        import sympy as sp

        self.derivation = derivation
        args = derivation.args + derivation.parameters
        self.energy = sp.lambdify(args, derivation.energy, modules="numpy", cse=True)
        self.first = sp.lambdify(args, list(derivation.first), modules="numpy", cse=True)
        self.second = sp.lambdify(args, list(derivation.second), modules="numpy", cse=True)
        if derivation.kind == "components":
            n = derivation.dim**2
            self.rows = np.array([a for a, _ in derivation.pairs])
            self.cols = np.array([b for _, b in derivation.pairs])
            self.n = n


def _column(value, q: int) -> np.ndarray:
    """A lambdified output (an array, or a number where the derivative is constant) as (q,)."""
    return np.broadcast_to(np.asarray(value, dtype=float), (q,))


class EnergyLaw(Material):
    """A hyperelastic law given by its strain-energy density psi (J/m^3).

    ``psi``: an expression string in the invariants I1, I2, I3, J, I1b, I2b, the components
    F11..F33 and C11..C33 of F and C = F^T F, and the parameters; or a Python function whose
    arguments are such names (``F`` and ``C`` give 3 x 3 SymPy matrices) and which returns a
    SymPy expression. ``parameters``: every other name of psi with its value (SI units).

    ``EnergyLaw("c1*(I1b - 3) + c2*(I2b - 3) + k/2*log(J)**2", c1=1e3, c2=200.0, k=1e5)``
    is FEBio's uncoupled Mooney-Rivlin law; ``.mu`` and ``.lam`` are its small-strain Lame
    parameters, read off the derived tangent at rest."""

    name = "energy"

    def __init__(self, psi: str | Callable, **parameters: float) -> None:
        self._params = {}
        for key, value in parameters.items():
            self._params[key] = parameter(self.name, _check_name(key), value, unit="")
        try:
            if isinstance(psi, str):
                expr = parse_energy(psi)
                self.psi_text = " ".join(psi.split())
            elif callable(psi):
                expr = call_energy(psi, self._params)
                self.psi_text = str(expr)
            else:
                raise MaterialError(
                    f"psi must be an expression string or a function, not {short(psi)}"
                )
            check_symbols(expr, self._params)
        except MaterialError as exc:  # one line naming the law: "energy: psi ..."
            raise MaterialError(f"energy: {exc}") from None
        self._expr = expr
        self._compiled: dict[int, _Compiled] = {}
        self._kernels: dict[int, object] = {}
        self.kind = self._derived(3).derivation.kind
        self._check_rest()
        if any(n[0] == "F" for n in (s.name for s in expr.free_symbols) if n in VARIABLES):
            self._check_objective()

    # -- what the rest of tissuesim reads --------------------------------------------------

    def parameters(self) -> dict[str, object]:
        """psi and the parameters by keyword, as ``make_material("energy", ...)`` takes them."""
        return {"psi": self.psi_text, **self._params}

    def __repr__(self) -> str:
        args = ", ".join(f"{key}={value!r}" for key, value in self.parameters().items())
        return f"EnergyLaw({args})"

    def __getstate__(self) -> dict:
        state = dict(self.__dict__)
        state["_compiled"], state["_kernels"] = {}, {}  # functions made again when needed
        return state

    @property
    def values(self) -> np.ndarray:
        """The parameters' values in the order of the derivation's parameter symbols."""
        return np.array([self._params[k] for k in sorted(self._params)], dtype=float)

    def _derived(self, dim: int) -> _Compiled:
        if dim not in self._compiled:
            self._compiled[dim] = _Compiled(derive(self._expr, list(self._params), dim))
        return self._compiled[dim]

    def point_kernel(self, dim: int):
        """The Numba point kernel of dimension ``dim`` (``energy_kernel.py``), or None when it
        cannot be made; for the fused assembly (``energies/elastic.py``)."""
        if dim not in self._kernels:
            from tissuesim.materials.energy_law.energy_kernel import make_kernel

            self._kernels[dim] = make_kernel(self._derived(dim).derivation, self.psi_text)
        return self._kernels[dim]

    # -- evaluation ---------------------------------------------------------------------------

    def evaluate(self, F: np.ndarray, order: int = 2) -> MaterialResponse:
        F = check_input(F, order)
        q, d = F.shape[0], F.shape[-1]
        c = self._derived(d)
        cof = cofactor(F)
        J = det(F, cof)
        ok = J > 0.0  # also False for NaN
        p = tuple(self.values)
        if c.derivation.kind == "invariants":
            Js = np.where(ok, J, 1.0)
            I1 = np.einsum("qij,qij->q", F, F) + (3.0 - d)
            C = np.einsum("qki,qkj->qij", F, F) if c.derivation.uses_i2 else None
            I2 = 0.5 * (I1**2 - np.einsum("qij,qij->q", C, C) - (3.0 - d)) if C is not None else I1
            args = (I1, I2, Js) + p
        else:
            args = tuple(F[:, i, j] for i in range(d) for j in range(d)) + p
        with np.errstate(all="ignore"):
            psi = _column(c.energy(*args), q)
        ok &= np.isfinite(psi)
        psi = np.where(ok, psi, np.inf)
        if order == 0:
            return MaterialResponse(psi)
        if not ok.all():
            raise _undefined(J, ok)
        first = [_column(v, q) for v in c.first(*args)]
        second = [_column(v, q) for v in c.second(*args)] if order == 2 else []
        if c.derivation.kind == "invariants":
            W = first if order == 1 else [*first[:2], first[2], *second]
            # second = (W11, W12, W22, W1J, W2J, WJJ): invariant_tensors' order after WJ
            P, A = invariant_tensors(F, I1, C, cof, J, W, order)
            return MaterialResponse(psi, P, A)
        P = np.stack(first, axis=1).reshape(q, d, d)
        if order == 1:
            return MaterialResponse(psi, P)
        values = np.stack(second, axis=1)
        A = np.empty((q, c.n, c.n))
        A[:, c.rows, c.cols] = values
        A[:, c.cols, c.rows] = values
        return MaterialResponse(psi, P, A.reshape(q, d, d, d, d))

    # -- the checks of a new law ---------------------------------------------------------------

    def _check_rest(self) -> None:
        """Stress-free at rest, positive small-strain moduli (3D, at F = I)."""
        with np.errstate(all="ignore"):
            rest = self.evaluate(np.eye(3)[None], 0)
            if not np.isfinite(rest.energy).all():
                raise MaterialError(
                    f"energy: psi is not finite at rest (F = I): {self.psi_text!r}; check the "
                    "expression (a division by I1 - 3 or by log(J)?)"
                )
            res = self.evaluate(np.eye(3)[None], 2)
        A = res.tangent[0]
        if not np.isfinite(A).all() or not np.isfinite(res.stress).all():
            raise MaterialError(
                f"energy: the stress or tangent of psi is not finite at rest (F = I): "
                f"{self.psi_text!r}; psi must be twice differentiable there"
            )
        pairs = [(i, j) for i in range(3) for j in range(3) if i != j]
        self.mu = float(np.mean([A[i, j, i, j] for i, j in pairs]))
        self.lam = float(np.mean([A[i, i, j, j] for i, j in pairs]))
        scale = max(np.abs(A).max(), 1e-300)
        P0 = res.stress[0]
        if np.abs(P0).max() > 1e-9 * scale:
            worst = float(P0.flat[np.abs(P0).argmax()])
            raise MaterialError(
                f"energy: psi is not stress-free at rest: P(F = I) has entries up to {worst!r} "
                "Pa; add the term that balances it (for mu/2*(I1 - 3), -mu*log(J))"
            )
        bulk = self.lam + 2.0 * self.mu / 3.0
        for what, value in (("shear modulus mu", self.mu), ("bulk modulus", bulk)):
            if not (value > 0.0 and math.isfinite(value)):
                raise MaterialError(
                    f"energy: psi gives a small-strain {what} of {value!r} Pa at rest; it must "
                    f"be > 0 (parameters {self._params})"
                )

    def _check_objective(self) -> None:
        """A psi of F's components must not change when F is rotated (Q F for rotations Q)."""
        rng = np.random.default_rng(0)
        F = np.eye(3) + 0.2 * rng.standard_normal((8, 3, 3))
        Q, _ = np.linalg.qr(rng.standard_normal((8, 3, 3)))
        Q[np.linalg.det(Q) < 0, :, 0] *= -1.0
        a, b = self.energy_density(F), self.energy_density(Q @ F)
        fine = np.isfinite(a) & np.isfinite(b)
        if np.abs(a - b)[fine].max(initial=0.0) > 1e-8 * max(np.abs(a[fine]).max(), self.mu):
            raise MaterialError(
                "energy: psi is not objective (it changes when the body rotates rigidly); write "
                "it with C11..C33 (C = F^T F) or the invariants instead of F11..F33"
            )


def _check_name(key: str) -> str:
    """A parameter name psi can use: an identifier that is not a variable or a function."""
    reserved = set(VARIABLES) | set(FUNCTIONS) | set(CONSTANTS) | set(MATRICES)
    if not key.isidentifier() or keyword.iskeyword(key) or key.startswith("_"):
        raise MaterialError(
            f"energy: parameter name {short(key)} must be a name such as mu or k1 (letters, "
            "digits and _, not starting with _ or a digit)"
        )
    if key in reserved:
        raise MaterialError(
            f"energy: {key!r} is a variable or function of psi, not a parameter name; rename "
            "the parameter"
        )
    return key


def _undefined(J: np.ndarray, ok: np.ndarray) -> InvertedElementError:
    bad = np.flatnonzero(~ok)
    return InvertedElementError(
        f"energy law is undefined at {bad.size} point(s) (J <= 0 or psi not finite; q indices "
        f"{bad[:10].tolist()}{' ...' if bad.size > 10 else ''}, J = {J[bad[:3]].tolist()}); "
        "take smaller steps, or write psi so that it stays finite there",
        indices=bad,
    )


def from_energy(psi: str | Callable, **parameters: float) -> EnergyLaw:
    """A law from its strain-energy density psi: ``EnergyLaw(psi, **parameters)``."""
    return EnergyLaw(psi, **parameters)
