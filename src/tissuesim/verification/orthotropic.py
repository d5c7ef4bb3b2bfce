"""FEBio's orthotropic laws against closed forms by hand: the orthotropic Hooke law of the
engineering constants at small strain, and FEBio's energies at finite strain.

Small strain (strain 1e-6, tolerance 1e-5): pulled along local axis a_1 with the lateral
strains of the compliance (e_22 = -v12 e, e_33 = -v13 e, v13 = v31 E1 / E3), the stress along
a_1 is E1 e (Fung-ortho-compressible's bulk term adds k (J - 1), J - 1 = (1 - v12 - v13) e;
not checked for the uncoupled Fung law, Hooke's law on the deviatoric strain only); sheared in
the a_1-a_2 plane by g, the shear stress is G12 g.

Finite strain (the combinations of ``laws.py``, tolerance 1e-8): with the strain's components
E_ab = a_a . E a_b along the axes (A_a : E = E_aa, A_a : E^2 = sum_c E_ac^2), FEBio's
W_o = sum_a mu_a A_a : E^2 + 1/2 sum_ab lam_ab E_aa E_bb has
S = sum_ab lam_ab E_bb a_a (x) a_a + sum_a mu_a (A_a E + E A_a) (written out per axis below),
P = F S; Fung: S = exp(2 W_o / c) S_o on E (compressible) or on E~ at J = 1 (uncoupled: the
same, the pressure dropped by the combination). mu_1 = G12 + G31 - G23 (and cyclic) and
lam + 2 diag(mu) the inverse of the compliance.
"""

from __future__ import annotations

import math

import numpy as np

from tissuesim.verification.laws import G, L

__all__ = ["CASES"]

ORTHO = dict(E1=1000.0, E2=2000.0, E3=3000.0, G12=600.0, G23=400.0, G31=500.0)
ORTHO.update(v12=0.3, v23=0.2, v31=0.25)
#: local axes e1 = y, e2 = -x, e3 = z (mat_axis a = y, d = -x)
AXES = {"mat_axis_a": (0.0, 1.0, 0.0), "mat_axis_d": (-1.0, 0.0, 0.0)}
_A = ((0.0, 1.0, 0.0), (-1.0, 0.0, 0.0), (0.0, 0.0, 1.0))
SMALL = 1e-6


def _moduli() -> tuple[list[float], list[list[float]]]:
    p = ORTHO
    mu = [p["G12"] + p["G31"] - p["G23"], p["G12"] - p["G31"] + p["G23"],
          p["G31"] + p["G23"] - p["G12"]]  # fmt: skip
    compliance = np.array(
        [
            [1 / p["E1"], -p["v12"] / p["E1"], -p["v31"] / p["E3"]],
            [-p["v12"] / p["E1"], 1 / p["E2"], -p["v23"] / p["E2"]],
            [-p["v31"] / p["E3"], -p["v23"] / p["E2"], 1 / p["E3"]],
        ]
    )
    lam = np.linalg.inv(compliance)
    return mu, [[lam[a][b] - (2 * mu[a] if a == b else 0.0) for b in range(3)] for a in range(3)]


def _stress(F: np.ndarray, c: float | None) -> np.ndarray:
    """P = F S of W_o (c None) or of Fung's c/2 (exp(2 W_o / c) - 1), term by term."""
    mu, lam = _moduli()
    E = 0.5 * (F.T @ F - np.eye(3))
    a = [np.array(v) for v in _A]
    Eab = [[float(a[i] @ E @ a[j]) for j in range(3)] for i in range(3)]
    S = np.zeros((3, 3))
    wo = 0.0
    for i in range(3):
        Ai = np.outer(a[i], a[i])
        S += sum(lam[i][j] * Eab[j][j] for j in range(3)) * Ai + mu[i] * (Ai @ E + E @ Ai)
        wo += mu[i] * sum(Eab[i][k] ** 2 for k in range(3))
        wo += 0.5 * sum(lam[i][j] * Eab[i][i] * Eab[j][j] for j in range(3))
    if c is not None:
        S *= math.exp(2.0 * wo / c)
    return F @ S


def _closed(kind: str, c: float | None = None, k: float = 0.0):
    """The combination s of ``kind`` from the hand stress (F as in ``laws.py``); "hooke" and
    "hooke_shear" the small-strain stresses E1 e (+ k (J - 1) with a bulk term k) and
    G12 g."""

    def value() -> float:
        p = ORTHO
        if kind == "hooke":  # Fung-ortho-compressible's k/2 (ln J)^2 adds k (J - 1)
            bulk = 0.0 if c is None else k * (1.0 - p["v12"] - p["v31"] * p["E1"] / p["E3"])
            return (p["E1"] + bulk) * SMALL
        if kind == "hooke_shear":
            return p["G12"] * SMALL
        if kind == "uniaxial":
            t = L**-0.5
            P = _stress(np.diag([L, t, t]), c)
            return float(P[0, 0] - P[1, 1] * t / L)
        if kind == "equibiaxial":
            b = L**-2
            P = _stress(np.diag([L, L, b]), c)
            return float(P[0, 0] - P[2, 2] * b / L)
        F = np.eye(3)
        F[0, 1] = G
        return float(_stress(F, c)[0, 1])

    return value


def hooke(law, kind: str) -> float:
    """The law's stress along a_1 = y pulled by SMALL with the compliance's lateral strains
    (along x: a_2 = -x, z: a_3), or its shear stress a_1-a_2 sheared by SMALL."""
    p = ORTHO
    if kind == "hooke":
        v13 = p["v31"] * p["E1"] / p["E3"]
        F = np.diag([1.0 - p["v12"] * SMALL, 1.0 + SMALL, 1.0 - v13 * SMALL])
        return float(law.stress(F[None])[0, 1, 1])
    F = np.eye(3)
    F[1, 0] = -SMALL  # a_1 . (F - I) a_2 = y . (F - I)(-x)
    return float(law.stress(F[None])[0, 1, 0] * -1.0)


def _cases() -> list[tuple]:
    out = []
    for name, extra, c in (
        ("orthotropic_elastic", {}, None),
        ("fung_orthotropic", {"c": 1500.0, "k": 20000.0}, 1500.0),
        ("fung_ortho_compressible", {"c": 1500.0, "k": 20000.0}, 1500.0),
    ):
        params = {**ORTHO, **AXES, **extra}
        if name != "fung_orthotropic":  # uncoupled: Hooke's law on the deviatoric strain only
            what = "E1 e" + (" + k (J - 1)" if c else "")
            out.append(
                (
                    name,
                    f"small strain along a_1 = y: {what} (e = {SMALL:g})",
                    "hooke",
                    params,
                    _closed("hooke", c, extra.get("k", 0.0)),
                    None,
                )
            )
        out += [
            (name, f"small shear in a_1-a_2: G12 g (g = {SMALL:g})", "hooke_shear", params,
             _closed("hooke_shear"), None),
            (name, f"uniaxial along x = -a_2 (l = {L})", "uniaxial", params,
             _closed("uniaxial", c), None),
            (name, f"equibiaxial (l = {L})", "equibiaxial", params, _closed("equibiaxial", c),
             None),
            (name, f"shear (g = {G})", "shear", params, _closed("shear", c), None),
        ]  # fmt: skip
    return out


#: (law, quantity, deformation, parameters, closed form (no arguments), None)
CASES = _cases()
