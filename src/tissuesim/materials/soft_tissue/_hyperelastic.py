"""Shared machinery of the FEBio-style soft-tissue laws: parameter checks, the J <= 0 rule, and
the invariant engine that turns scalar derivatives of W(I1, I2, J) into P and dP/dF.

Invariants of C = F^T F (2D: plane strain, the 3D invariants of diag(F, 1)):

    I1 = |F|^2 (+1 in 2D)                    dI1/dF = 2 F           d2I1 = 2 delta_ik delta_jl
    I2 = (I1^2 - C:C (+1 in 2D)) / 2         dI2/dF = 2 (I1 F - F C)
    d2I2/dF_ij dF_kl = 2 [2 F_ij F_kl + I1 delta_ik delta_jl - delta_ik C_lj - F_il F_kj
                          - B_ik delta_jl],  B = F F^T
    J = det F                                dJ/dF = cof F          d2J = det_hessian(F)

so P = W1 dI1 + W2 dI2 + WJ dJ and A = W1 d2I1 + W2 d2I2 + WJ d2J + sum_ab W_ab dI_a (x) dI_b.

Uncoupled (FEBio's ``FEUncoupledMaterial``) laws are W = w(I1b, I2b) + U(J) on the
isochoric invariants I1b = J^(-2/3) I1, I2b = J^(-4/3) I2; the chain rule through I1b(I1, J),
I2b(I2, J) gives the derivatives in (I1, I2, J) (``isochoric_derivatives``). Coupled laws are
W = w(I1, I2) - 2 (w1 + 2 w2)|_rest ln J + k/2 (ln J)^2: the ln J term makes the rest state
stress-free (FEBio's coupled Mooney-Rivlin and coupled Veronda-Westmann are exactly this).

U(J) is FEBio's ``pressure_model`` of its uncoupled laws (``bulk_energy``):

    "default"                      U = k/2 (ln J)^2
    "NIKE3D" and "Abaqus (GOH)"    U = k/4 (J^2 - 1 - 2 ln J)     (the same function)
    "Abaqus"                       U = k/2 (J - 1)^2

all with U(1) = U'(1) = 0, U''(1) = k: the small-strain bulk modulus is k for each.

Small-strain moduli of w about I1 = I2 = 3 (derivatives there): mu = 2 (w1 + w2); uncoupled
lam = k - 2 mu / 3; coupled lam = k + 4 w2 + 4 w11 + 16 w12 + 16 w22.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from tissuesim.errors import InputError, InvertedElementError, MaterialError
from tissuesim.materials.base import Material, MaterialResponse
from tissuesim.materials.isotropic._common import (
    IDENTITY,
    bcast,
    check_input,
    cofactor,
    det,
    det_hessian,
    outer,
)
from tissuesim.validate import real, short

__all__ = [
    "PRESSURE_MODELS",
    "pressure_model",
    "bulk_energy",
    "HyperelasticMaterial",
    "InvariantLaw",
    "Derivatives",
    "parameter",
    "parameter_list",
    "inverted_error",
    "invariant_tensors",
]


def parameter(
    law: str,
    key: str,
    value: object,
    *,
    positive: bool = False,
    unit: str = "Pa",
    meaning: str = "",
) -> float:
    """A finite real material parameter, or a one-line MaterialError naming law and key."""
    what = f" ({meaning})" if meaning else ""
    if value is None:
        raise MaterialError(f"{law} needs {key}{what}")
    try:
        x = real(value, f"{law}: {key}", unit=unit)
    except InputError as exc:
        raise MaterialError(str(exc)) from None
    if positive and x <= 0.0:
        unit_text = f" {unit}" if unit else ""
        raise MaterialError(f"{law}: {key}{what} must be > 0{unit_text}, got {x!r}")
    return x


#: FEBio's pressure_model names, by its integer value; the volumetric kind of each
PRESSURE_MODELS = ("default", "NIKE3D", "Abaqus", "Abaqus (GOH)")
BULK_KINDS = ("log", "goh", "quadratic_J", "goh")


def pressure_model(law: str, value: object) -> str:
    """FEBio's pressure_model (its name, any case, or its integer 0..3) as the bulk kind."""
    if isinstance(value, (int, np.integer)) and not isinstance(value, bool) and 0 <= value <= 3:
        return BULK_KINDS[int(value)]
    key = str(value).strip().lower() if isinstance(value, str) else None
    names = [name.lower() for name in PRESSURE_MODELS]
    if key not in names:
        raise MaterialError(
            f"{law}: pressure_model must be one of {', '.join(map(repr, PRESSURE_MODELS))} "
            f"(or 0..3), not {short(value)}"
        )
    return BULK_KINDS[names.index(key)]


def bulk_energy(kind: str, k: float, J: np.ndarray, lnJ: np.ndarray) -> tuple:
    """(U, U', U'') of the bulk term ``kind`` (``BULK_KINDS``) at J > 0."""
    if kind == "log":
        return 0.5 * k * lnJ**2, k * lnJ / J, k * (1.0 - lnJ) / J**2
    if kind == "goh":
        return 0.25 * k * (J**2 - 1.0 - 2.0 * lnJ), 0.5 * k * (J - 1.0 / J), 0.5 * k * (1.0 + J**-2)
    return 0.5 * k * (J - 1.0) ** 2, k * (J - 1.0), np.full_like(J, k)


def bulk_response(name: str, kind: str, k: float, F: np.ndarray, order: int) -> MaterialResponse:
    """The bulk term U(J) of ``kind`` alone at F (q, 3, 3): its energy (inf where J <= 0),
    first Piola stress U' cof F and tangent U'' cof (x) cof + U' dcof/dF up to ``order``
    (an uncoupled law's volumetric part: the mixtures' and the viscoelastic wrappers')."""
    cof = cofactor(F)
    J = det(F, cof)
    ok = J > 0.0
    if order > 0 and not ok.all():
        raise inverted_error(name, J, ok)
    Js = np.where(ok, J, 1.0)
    U, dU, ddU = bulk_energy(kind, k, Js, np.log(Js))
    U = np.where(ok, U, math.inf)
    if order == 0:
        return MaterialResponse(U)
    P = bcast(dU, 3) * cof
    if order == 1:
        return MaterialResponse(U, P)
    A = bcast(ddU, 5) * outer(cof, cof) + bcast(dU, 5) * det_hessian(F)
    return MaterialResponse(U, P, A)


def parameter_list(law: str, key: str, value: object, *, unit: str = "Pa") -> list[float]:
    """A non-empty list of finite reals (a scalar is a list of one)."""
    if isinstance(value, (int, float, np.number)) and not isinstance(value, bool):
        value = [value]
    if isinstance(value, np.ndarray):
        value = value.tolist()
    if not isinstance(value, Sequence) or isinstance(value, str) or len(value) == 0:
        raise MaterialError(f"{law}: {key} must be a non-empty list of numbers, not {short(value)}")
    return [parameter(law, f"{key}[{i}]", v, unit=unit) for i, v in enumerate(value)]


def inverted_error(name: str, J: np.ndarray, ok: np.ndarray) -> InvertedElementError:
    """The error for stress or tangent asked where J <= 0 (or NaN)."""
    bad = np.flatnonzero(~ok)
    return InvertedElementError(
        f"{name} is undefined for J <= 0 but {bad.size} point(s) are inverted or degenerate "
        f"(q indices {bad[:10].tolist()}{' ...' if bad.size > 10 else ''}, "
        f"J = {J[bad[:3]].tolist()}); take smaller steps, or use course_neo_hookean or "
        "fixed_corotated for inversion-robust simulation",
        indices=bad,
    )


class HyperelasticMaterial(Material):
    """A law given by its own parameters (FEBio's names), with small-strain ``mu`` and ``lam``
    and the bulk coefficient ``k`` of its volumetric term. +inf energy for J <= 0, and
    InvertedElementError for stress or tangent there."""

    #: FEBio's name of the law (its ``type`` in a .feb file)
    febio_name: str = ""
    k: float
    #: the bulk term U(J) (``BULK_KINDS``): FEBio's pressure_model of an uncoupled law
    bulk_kind: str = "log"

    def parameters(self) -> dict[str, object]:
        """The law's parameters by keyword, as ``make_material`` takes them."""
        raise NotImplementedError

    def _bulk_parameter(self) -> dict[str, object]:
        """{"pressure_model": name} when it is not FEBio's default, else {}."""
        if self.bulk_kind == "log":
            return {}
        return {"pressure_model": PRESSURE_MODELS[BULK_KINDS.index(self.bulk_kind, 1)]}

    def __repr__(self) -> str:
        args = ", ".join(f"{key}={value!r}" for key, value in self.parameters().items())
        return f"{type(self).__name__}({args})"

    def _check_moduli(self) -> None:
        if not (self.mu > 0.0 and math.isfinite(self.mu)):
            raise MaterialError(
                f"{self.name}: the parameters give a small-strain shear modulus mu = "
                f"{self.mu!r} Pa; it must be > 0 ({self.parameters()})"
            )
        bulk = self.lam + 2.0 * self.mu / 3.0
        if not (bulk > 0.0 and math.isfinite(bulk)):
            raise MaterialError(
                f"{self.name}: the parameters give a small-strain bulk modulus {bulk!r} Pa; it "
                f"must be > 0 ({self.parameters()})"
            )


@dataclass
class Derivatives:
    """w and its derivatives in two invariants, arrays (q,) or scalars; None when zero."""

    w: np.ndarray
    w1: np.ndarray | float = 0.0
    w2: np.ndarray | float = 0.0
    w11: np.ndarray | float = 0.0
    w12: np.ndarray | float = 0.0
    w22: np.ndarray | float = 0.0


def isochoric_derivatives(
    d: Derivatives, I1b: np.ndarray, I2b: np.ndarray, J: np.ndarray, order: int
) -> tuple:
    """(W1, W2, WJ, W11, W12, W22, W1J, W2J, WJJ) of w(I1b(I1, J), I2b(I2, J)) in (I1, I2, J)."""
    a1, a2 = J ** (-2.0 / 3.0), J ** (-4.0 / 3.0)
    b1, b2 = -2.0 / 3.0 * I1b / J, -4.0 / 3.0 * I2b / J  # dI1b/dJ, dI2b/dJ
    W1, W2 = d.w1 * a1, d.w2 * a2
    WJ = d.w1 * b1 + d.w2 * b2
    if order < 2:
        return W1, W2, WJ
    W11, W12, W22 = d.w11 * a1 * a1, d.w12 * a1 * a2, d.w22 * a2 * a2
    W1J = (d.w11 * b1 + d.w12 * b2) * a1 - 2.0 / 3.0 * d.w1 * a1 / J
    W2J = (d.w12 * b1 + d.w22 * b2) * a2 - 4.0 / 3.0 * d.w2 * a2 / J
    WJJ = (
        (d.w11 * b1 + d.w12 * b2) * b1
        + (d.w12 * b1 + d.w22 * b2) * b2
        + 10.0 / 9.0 * d.w1 * I1b / J**2
        + 28.0 / 9.0 * d.w2 * I2b / J**2
    )
    return W1, W2, WJ, W11, W12, W22, W1J, W2J, WJJ


class InvariantLaw(HyperelasticMaterial):
    """W = w(I1b, I2b) + k/2 (ln J)^2 (``uncoupled``) or w(I1, I2) - 2 (w1 + 2 w2)|_rest ln J
    + k/2 (ln J)^2 (coupled). Subclasses give ``w(I1, I2, order)`` and set ``uncoupled``;
    ``uses_i2`` = False skips the second invariant."""

    uncoupled: bool = True
    uses_i2: bool = True

    def w(self, I1: np.ndarray, I2: np.ndarray, order: int) -> Derivatives:
        """w and, up to ``order``, its derivatives at the invariants (arrays (q,))."""
        raise NotImplementedError

    def _set_moduli(self, k: float, model: object = "default") -> None:
        self.k = k
        if not self.uncoupled and model != "default":
            raise MaterialError(
                f"{self.name} has no pressure_model: it is a parameter of FEBio's uncoupled laws"
            )
        self.bulk_kind = pressure_model(self.name, model)
        three = np.array([3.0])
        r = self.w(three, three, 2)
        w1, w2 = float(np.asarray(r.w1).ravel()[0]), float(np.asarray(r.w2).ravel()[0])
        w11, w12, w22 = (float(np.asarray(x).ravel()[0]) for x in (r.w11, r.w12, r.w22))
        self._rest_slope = 2.0 * (w1 + 2.0 * w2)  # coefficient of -ln J in the coupled form
        self.mu = 2.0 * (w1 + w2)
        if self.uncoupled:
            self.lam = k - 2.0 * self.mu / 3.0
        else:
            self.lam = k + 4.0 * w2 + 4.0 * w11 + 16.0 * w12 + 16.0 * w22
        self._check_moduli()

    def evaluate(self, F: np.ndarray, order: int = 2) -> MaterialResponse:
        F = check_input(F, order)
        d, k = F.shape[-1], self.k
        cof = cofactor(F)
        J = det(F, cof)
        ok = J > 0.0  # also False for NaN
        if order > 0 and not ok.all():
            raise inverted_error(self.name, J, ok)
        Js = np.where(ok, J, 1.0)
        lnJ = np.log(Js)
        extra = 3.0 - d  # the out-of-plane unit stretch of plane strain
        I1 = np.einsum("qij,qij->q", F, F) + extra
        if self.uses_i2:
            C = np.einsum("qki,qkj->qij", F, F)
            I2 = 0.5 * (I1**2 - np.einsum("qij,qij->q", C, C) - extra)
        else:
            I2 = np.full_like(I1, 3.0)
        if self.uncoupled:
            I1b, I2b = I1 * Js ** (-2.0 / 3.0), I2 * Js ** (-4.0 / 3.0)
            r = self.w(I1b, I2b, order)
            U, dU, ddU = bulk_energy(self.bulk_kind, k, Js, lnJ)
            psi = r.w + U
        else:
            r = self.w(I1, I2, order)
            U, dU, ddU = bulk_energy("log", k, Js, lnJ)
            psi = r.w - self._rest_slope * lnJ + U
        psi = np.where(ok, psi, np.inf)
        if order == 0:
            return MaterialResponse(psi)
        if self.uncoupled:
            W = isochoric_derivatives(r, I1b, I2b, J, order)
            WJ = W[2] + dU
        else:
            W = (r.w1, r.w2, 0.0, r.w11, r.w12, r.w22, 0.0, 0.0, 0.0)
            WJ = dU - self._rest_slope / J
        if order == 1:
            P, _ = invariant_tensors(F, I1, C if self.uses_i2 else None, cof, J, W[:2] + (WJ,), 1)
            return MaterialResponse(psi, P)
        WJJ = ddU + (W[8] if self.uncoupled else self._rest_slope / J**2)
        W = W[:2] + (WJ,) + tuple(W[3:8]) + (WJJ,)
        P, A = invariant_tensors(F, I1, C if self.uses_i2 else None, cof, J, W, 2)
        return MaterialResponse(psi, P, A)


def invariant_tensors(
    F: np.ndarray,
    I1: np.ndarray,
    C: np.ndarray | None,
    cof: np.ndarray,
    J: np.ndarray,
    W: Sequence,
    order: int,
) -> tuple[np.ndarray, np.ndarray | None]:
    """P and (order 2) dP/dF of W(I1, I2, J) from its derivatives in the invariants.

    ``W`` = (W1, W2, WJ) for order 1, (W1, W2, WJ, W11, W12, W22, W1J, W2J, WJJ) for order 2,
    arrays (q,) or scalars; ``C`` = F^T F, or None when W does not depend on I2 (its terms are
    then skipped). ``I1`` is the 3D invariant (plane strain: |F|^2 + 1), ``cof`` = dJ/dF."""
    d = F.shape[-1]
    uses_i2 = C is not None
    W1, W2 = np.broadcast_to(W[0], J.shape), np.broadcast_to(W[1], J.shape)
    WJ = np.broadcast_to(W[2], J.shape)
    g1 = 2.0 * F
    P = bcast(W1, 3) * g1 + bcast(WJ, 3) * cof
    if uses_i2:
        FC = F @ C
        g2 = 2.0 * (bcast(I1, 3) * F - FC)
        P = P + bcast(W2, 3) * g2
    if order == 1:
        return P, None
    W11, W1J = np.broadcast_to(W[3], J.shape), np.broadcast_to(W[6], J.shape)
    WJJ = np.broadcast_to(W[8], J.shape)
    q, n = F.shape[0], d * d
    # sum_ab W_ab dI_a (x) dI_b as one batched product G^T H, G = rows dI_a, H = sum_b W_ab dI_b
    h1 = bcast(W11, 3) * g1 + bcast(W1J, 3) * cof
    hJ = bcast(W1J, 3) * g1 + bcast(WJJ, 3) * cof
    iso = 2.0 * W1  # coefficient of delta_ik delta_jl
    if uses_i2:
        W12, W22 = np.broadcast_to(W[4], J.shape), np.broadcast_to(W[5], J.shape)
        W2J = np.broadcast_to(W[7], J.shape)
        # the 4 W2 F (x) F of W2 d2I2 is W2 g1 (x) g1: it joins h1
        h1 = h1 + bcast(W12, 3) * g2 + bcast(W2, 3) * g1
        hJ = hJ + bcast(W2J, 3) * g2
        h2 = bcast(W12, 3) * g1 + bcast(W22, 3) * g2 + bcast(W2J, 3) * cof
        G, H = np.stack([g1, g2, cof], 1), np.stack([h1, h2, hJ], 1)
        iso = iso + 2.0 * W2 * I1
    else:
        G, H = np.stack([g1, cof], 1), np.stack([h1, hJ], 1)
    A = (np.swapaxes(G.reshape(q, -1, n), 1, 2) @ H.reshape(q, -1, n)).reshape(q, d, d, d, d)
    A += bcast(iso, 5) * IDENTITY[d] + bcast(WJ, 5) * det_hessian(F)
    if uses_i2:
        # the rest of W2 d2I2: -2 W2 (delta_ik C_lj + F_il F_kj + B_ik delta_jl)
        I = np.eye(d)
        B = F @ np.swapaxes(F, 1, 2)
        rest = I[None, :, None, :, None] * C[:, None, :, None, :]
        rest = rest + F[:, :, None, None, :] * np.swapaxes(F, 1, 2)[:, None, :, :, None]
        rest = rest + B[:, :, None, :, None] * I[None, None, :, None, :]
        A -= bcast(2.0 * W2, 5) * rest
    return P, A
