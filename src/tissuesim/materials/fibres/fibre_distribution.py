"""FEBio's fibre density distributions and fibre integration schemes, the parts of its
continuous fibre distribution (``continuous_distribution.py``).

Distributions R(n), n a unit vector in the law's local axes (``FEFiberDensityDistribution.cpp``):

    spherical       R = 1
    ellipsoidal     R = 1 / sqrt((n1/a1)^2 + (n2/a2)^2 + (n3/a3)^2),   spa = (a1, a2, a3)
    von_mises_3d    R = exp(b (2 n1^2 - 1))
    elliptical      R = 1 / sqrt((n1/a1)^2 + (n2/a2)^2),               spa1, spa2 (2D)
    von_mises_2d    R = exp(b (2 n1^2 - 1))                            (2D)

FEBio does not normalise R in closed form: the law divides by the scheme's own integral of R
(``IntegratedFiberDensity``, the scheme's fixed points).

Schemes: points n_k and weights w_k (``FEFiberIntegrationTrapezoidal.cpp``,
``FEFiberIntegrationGaussKronrod.cpp``):

    fibers_2d_trapezoidal   n = (cos t, sin t, 0), t = i pi / nth (i < nth), w = 2 pi / nth
    fibers_3d_gkt           t = 2 pi i / nth (i < nth) by the rectangle rule, and over
                            ksi = cos(polar angle) in [ksia, ksib] the (2 m + 1)-point
                            Gauss-Kronrod rule (nph = 2 m + 1 = 7, 11, ..., 27), points
                            n = v1 cos t sqrt(1 - ksi^2) + v2 sin t sqrt(1 - ksi^2) + v3 ksi,
                            w = 2 gw dt (ksib - ksia) / 2 (the other half sphere by symmetry).

The Gauss-Kronrod rule is derived here (``gauss_kronrod``), not tabulated: the Gauss-Legendre
nodes of order m and the m + 1 roots of the Stieltjes polynomial (orthogonal to P_m x^k,
k <= m), weights exact for polynomials of degree 3 m + 1. FEBio's tables hold 12 digits of it.

The Gauss-Kronrod scheme adapts to the deformation, as FEBio's does: from the eigenvalues
l1 <= l2 <= l3 (eigenvectors v) of E = (C - I) / 2 (C isochoric for an uncoupled law) it
integrates the half sphere (l1 >= 0), or only the cap where the fibres are stretched (one
tension: ksi from sqrt(nu / de), nu = -(l1 c^2 + l2 s^2), de = l3 - l1 c^2 - l2 s^2, to 1;
two tensions: the axes 1 and 3 swapped, ksi from 0 to sqrt(nu / de)), or nothing (l3 <= 0).
Its points are in the eigenvector frame and are read as local directions (R(n), then Q n), as
FEBio does.
"""

from __future__ import annotations

import numpy as np

from tissuesim.errors import MaterialError
from tissuesim.materials.soft_tissue._hyperelastic import parameter
from tissuesim.validate import short

__all__ = ["Distribution", "Scheme", "make_distribution", "make_scheme", "gauss_kronrod"]


class Distribution:
    """A fibre density R(n) (n: (..., 3) unit vectors in the local axes)."""

    def __init__(self, model: str, params: dict) -> None:
        self.model = model
        self.params = dict(params)
        law = f"distribution {model}"
        allowed = {
            "spherical": (),
            "ellipsoidal": ("spa",),
            "von_mises_3d": ("b",),
            "elliptical": ("spa1", "spa2"),
            "von_mises_2d": ("b",),
        }
        if model not in allowed:
            raise MaterialError(
                f"unknown fibre distribution {short(model)}; valid: {', '.join(allowed)}"
            )
        for key in params:
            if key not in allowed[model]:
                raise MaterialError(f"{law}: unknown parameter {short(key)}; it takes "
                                    f"{', '.join(allowed[model]) or 'none'}")  # fmt: skip
        self.planar = model in ("elliptical", "von_mises_2d")
        if model == "ellipsoidal":
            spa = np.asarray(params.get("spa", (1.0, 1.0, 1.0)), dtype=float)
            if spa.shape != (3,) or not np.all(spa > 0.0) or not np.all(np.isfinite(spa)):
                raise MaterialError(f"{law}: spa must be three numbers > 0, got {short(spa)}")
            self.axes = spa
        elif model == "elliptical":
            self.axes = np.array(
                [parameter(law, k, params.get(k, 1.0), unit="", positive=True)
                 for k in ("spa1", "spa2")] + [np.inf]
            )  # fmt: skip
        elif model in ("von_mises_3d", "von_mises_2d"):
            self.b = parameter(law, "b", params.get("b", 0.0), unit="")
            if self.b < 0.0:
                raise MaterialError(f"{law}: b must be >= 0, got {self.b!r}")

    def density(self, n: np.ndarray) -> np.ndarray:
        """R at the local unit vectors n (..., 3)."""
        if self.model == "spherical":
            return np.ones(n.shape[:-1])
        if self.model in ("ellipsoidal", "elliptical"):
            return 1.0 / np.sqrt(np.sum((n / self.axes) ** 2, axis=-1))
        return np.exp(self.b * (2.0 * n[..., 0] ** 2 - 1.0))


def gauss_kronrod(npoints: int) -> tuple[np.ndarray, np.ndarray]:
    """The (2 m + 1)-point Gauss-Kronrod nodes and weights on [-1, 1], npoints = 2 m + 1."""
    m = (npoints - 1) // 2
    leg = np.polynomial.legendre
    xg, _ = leg.leggauss(3 * m + 4)  # exact for the products below (degree <= 3 m + 2)
    wg = leg.leggauss(3 * m + 4)[1]
    # the Stieltjes polynomial E = P_{m+1} + sum_{j <= m} c_j P_j, orthogonal to P_m P_k, k <= m
    Pm = leg.legval(xg, np.eye(m + 1)[m])
    basis = np.array([leg.legval(xg, np.eye(m + 2)[j]) for j in range(m + 2)])  # (m + 2, n)
    tests = np.array([Pm * leg.legval(xg, np.eye(m + 1)[k]) for k in range(m + 1)])
    G = tests * wg @ basis.T  # (m + 1, m + 2): integral of P_m P_k P_j
    c = np.linalg.solve(G[:, : m + 1], -G[:, m + 1])
    kron = leg.legroots(np.concatenate([c, [1.0]]))
    gauss = leg.leggauss(m)[0]
    x = np.sort(np.concatenate([gauss, np.real(kron)]))
    V = np.array([leg.legval(x, np.eye(npoints)[j]) for j in range(npoints)])
    moments = np.zeros(npoints)
    moments[0] = 2.0
    return x, np.linalg.solve(V, moments)


class Scheme:
    """A fibre integration scheme: ``fixed`` (n (K, 3), w (K,)) and, for the adaptive
    Gauss-Kronrod scheme, ``points(C)`` -> (n (q, K, 3), w (q, K)) per deformation."""

    def __init__(self, model: str, params: dict) -> None:
        self.model = model
        self.params = dict(params)
        law = f"scheme {model}"
        allowed = {"fibers_2d_trapezoidal": ("nth",), "fibers_3d_gkt": ("nph", "nth")}
        if model not in allowed:
            raise MaterialError(
                f"unknown fibre integration scheme {short(model)}; valid: {', '.join(allowed)} "
                "(FEBio's fibers-3d-fei, fibers-3d-trapezoidal, fibers-3d-gauss are not run)"
            )
        for key in params:
            if key not in allowed[model]:
                raise MaterialError(f"{law}: unknown parameter {short(key)}; it takes "
                                    f"{', '.join(allowed[model])}")  # fmt: skip
        default_nth = 12 if model == "fibers_2d_trapezoidal" else 31
        self.nth = _count(law, "nth", params.get("nth", default_nth))
        self.adaptive = model == "fibers_3d_gkt"
        if self.adaptive:
            self.nph = _count(law, "nph", params.get("nph", 7))
            if self.nph not in (7, 11, 15, 19, 23, 27):
                raise MaterialError(f"{law}: nph must be 7, 11, 15, 19, 23 or 27 (as FEBio), "
                                    f"got {self.nph}")  # fmt: skip
            self.gp, self.gw = gauss_kronrod(self.nph)
            self.planar = False
            self.fixed = self._gk(np.eye(3)[None], np.zeros((1, 3)), np.zeros(1, dtype=int))
            self.fixed = (self.fixed[0][0], self.fixed[1][0])
        else:
            t = np.arange(self.nth) * np.pi / self.nth
            n = np.stack([np.cos(t), np.sin(t), np.zeros_like(t)], axis=1)
            self.fixed = (n, np.full(self.nth, 2.0 * np.pi / self.nth))
            self.planar = True

    def points(self, C: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(n (q or 1, K, 3), w (q or 1, K)) for the right Cauchy-Green tensors C (q, 3, 3)."""
        if not self.adaptive:
            n, w = self.fixed
            return n[None], w[None]
        E = 0.5 * (C - np.eye(3))
        lam, vec = np.linalg.eigh(E)  # ascending, vectors in columns
        eps = np.finfo(float).eps
        case = np.where(lam[:, 0] >= 0.0, 0, np.where(lam[:, 1] <= eps, 1, 2))
        case = np.where(lam[:, 2] <= 0.0, -1, case)
        swap = case == 2  # FEBio swaps the first and last eigenpairs
        lam = np.where(swap[:, None], lam[:, ::-1] * [1, 0, 1] + lam * [0, 1, 0], lam)
        vec = np.where(swap[:, None, None], vec[:, :, [2, 1, 0]], vec)
        return self._gk(vec, lam, case)

    def _gk(self, vec: np.ndarray, lam: np.ndarray, case: np.ndarray) -> tuple:
        dth = 2.0 * np.pi / self.nth
        t = np.arange(self.nth) * dth
        c2, s2 = np.cos(t) ** 2, np.sin(t) ** 2
        l0, l1, l2 = lam[:, 0:1], lam[:, 1:2], lam[:, 2:3]
        q = len(case)
        ka, kb = np.zeros((q, self.nth)), np.ones((q, self.nth))
        with np.errstate(divide="ignore", invalid="ignore"):
            nu1 = np.maximum(-l0 * c2 - l1 * s2, 0.0)
            de1 = l2 - l0 * c2 - l1 * s2
            ka1 = np.where(de1 <= 0.0, 1.0, np.sqrt(nu1) / np.sqrt(np.where(de1 > 0, de1, 1.0)))
            nu2 = np.maximum(l0 * c2 + l1 * s2, 0.0)
            de2 = l0 * c2 + l1 * s2 - l2
            kb2 = np.where(de2 <= 0.0, 0.0, np.sqrt(nu2) / np.sqrt(np.where(de2 > 0, de2, 1.0)))
        ka = np.where((case == 1)[:, None], ka1, ka)
        kb = np.where((case == 2)[:, None], kb2, kb)
        dk, sk = (kb - ka) / 2.0, (kb + ka) / 2.0  # (q, nth)
        ksi = sk[:, :, None] + dk[:, :, None] * self.gp  # (q, nth, nph)
        sph = np.sqrt(np.maximum(1.0 - ksi**2, 0.0))
        local = np.stack(
            [np.cos(t)[None, :, None] * sph, np.sin(t)[None, :, None] * sph, ksi], axis=-1
        )
        n = local.reshape(q, -1, 3) @ np.swapaxes(vec, 1, 2)
        w = (2.0 * dth) * dk[:, :, None] * self.gw  # (q, nth, nph)
        w = np.where((case >= 0)[:, None, None], w, 0.0).reshape(q, -1)
        return n, w


def _count(law: str, key: str, value: object) -> int:
    try:
        number = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise MaterialError(f"{law}: {key} must be a whole number, not {short(value)}") from None
    if number != int(number) or number < 1:
        raise MaterialError(f"{law}: {key} must be a whole number >= 1, got {short(value)}")
    return int(number)


def _table(what: str, value: object) -> tuple[str, dict]:
    if isinstance(value, (Distribution, Scheme)):
        return value.model, value.params
    if not isinstance(value, dict) or "model" not in value:
        raise MaterialError(
            f"continuous_fiber_distribution: {what} must be a table with its model, "
            f"not {short(value)}"
        )
    table = dict(value)
    model = str(table.pop("model")).strip().lower().replace("-", "_").replace(" ", "_")
    return model, table


def make_distribution(value: object) -> Distribution:
    """A ``Distribution`` from a table {model = "von_mises_3d", b = ...}."""
    return Distribution(*_table("distribution", value))


def make_scheme(value: object) -> Scheme:
    """A ``Scheme`` from a table {model = "fibers_3d_gkt", nph = 11, nth = 31}."""
    return Scheme(*_table("scheme", value))
