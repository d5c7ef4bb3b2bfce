"""FEBio's ``Mooney-Rivlin von Mises Fibers`` (``FEMRVonMisesFibers.cpp``, Girard et al. 2009,
Gouget et al. 2012): an uncoupled Mooney-Rivlin matrix and fibres in the plane of the local
axes e1, e2, at angles t around the preferred angle tp (radians), weighted by a von Mises
density over the half circle:

    W = c1 (I1b - 3) + c2 (I2b - 3) + U(J) + sum_i w_i R(t_i) f(Ib_i),
    n_i = cos t_i e1 + sin t_i e2,   Ib_i = J^(-2/3) n_i . C n_i

t_i, w_i: the 10-point Gauss-Legendre rule on each of gipt / 10 equal parts of
[tp - pi/2, tp + pi/2] (FEBio's points; their 8-digit table is this rule). R: vmc = 1 the
semi-circular von Mises exp(kf cos 2 (t - tp)) / (pi I0(kf)); vmc = 2 the constrained one
(1 - b) / pi + b exp(kf cos 2 (t - tp)) / (pi I0(kf)), b = (I1(kf) / I0(kf))^var_n (I0, I1 the
modified Bessel functions; FEBio's polynomial fits of them agree to about 1e-7). Not normalised
by the rule. f: trans iso Mooney-Rivlin's fibre (``fiber_exp_linear_uncoupled``: c3, c4, c5,
lam_max). Stress and tangent: the matrix's plus ``continuous_distribution.fibre_sum``'s.
"""

from __future__ import annotations

import numpy as np
from scipy.special import i0, i1

from tissuesim.errors import MaterialError
from tissuesim.materials.base import MaterialResponse
from tissuesim.materials.fibres._fibres import local_axes, planar_keys
from tissuesim.materials.fibres.continuous_distribution import fibre_sum
from tissuesim.materials.fibres.fibre_exp_linear import FiberExpLinearUncoupled
from tissuesim.materials.isotropic._common import check_input
from tissuesim.materials.soft_tissue._hyperelastic import HyperelasticMaterial, parameter
from tissuesim.materials.soft_tissue.mooney_rivlin import MooneyRivlin

__all__ = ["MooneyRivlinVonMisesFibers", "von_mises_rule"]


def von_mises_rule(
    kf: float, tp: float, gipt: int, vmc: int, var_n: float
) -> tuple[np.ndarray, np.ndarray]:
    """(angles t (gipt,), weights w R(t) (gipt,)) of FEBio's Mooney-Rivlin von Mises fibres."""
    x, w = np.polynomial.legendre.leggauss(10)
    parts = gipt // 10
    step = np.pi / parts
    lo = tp - np.pi / 2.0 + step * np.arange(parts)
    t = (lo[:, None] + step / 2.0 * (x[None] + 1.0)).ravel()
    weights = np.tile(w * step / 2.0, parts)
    vm = np.exp(kf * np.cos(2.0 * (t - tp))) / (np.pi * i0(kf))
    if vmc == 2:
        b = (i1(kf) / i0(kf)) ** var_n
        vm = (1.0 - b) / np.pi + b * vm
    return t, weights * vm


class MooneyRivlinVonMisesFibers(HyperelasticMaterial):
    """FEBio's ``Mooney-Rivlin von Mises Fibers``: Mooney-Rivlin (c1, c2, k) plus fibres in the
    e1-e2 plane of ``mat_axis_a``, ``mat_axis_d`` spread by a von Mises density (kf, tp, vmc,
    var_n) and summed by ``gipt`` Gauss points."""

    name = "mooney_rivlin_von_mises_fibers"
    febio_name = "Mooney-Rivlin von Mises Fibers"
    uncoupled = True

    def __init__(
        self,
        *,
        c1: float | None = None,
        c2: float = 0.0,
        k: float | None = None,
        pressure_model: str | int = "default",
        c3: float = 0.0,
        c4: float = 0.0,
        c5: float = 0.0,
        lam_max: float = 1.0,
        kf: float = 0.0,
        tp: float = 0.0,
        gipt: float = 10,
        vmc: float = 1,
        var_n: float = 1.0,
        mat_axis_a: object = (1.0, 0.0, 0.0),
        mat_axis_d: object = (0.0, 1.0, 0.0),
    ) -> None:
        law = self.name
        self.matrix = MooneyRivlin(c1=c1, c2=c2, k=k, pressure_model=pressure_model)
        self.c1, self.c2, self.k = self.matrix.c1, self.matrix.c2, self.matrix.k
        self.bulk_kind = self.matrix.bulk_kind
        self.mu, self.lam = self.matrix.mu, self.matrix.lam
        self.fibre = FiberExpLinearUncoupled(c3=c3, c4=c4, c5=c5, lam_max=lam_max)
        self.kf = parameter(law, "kf", kf, unit="")
        self.tp = parameter(law, "tp", tp, unit="")
        self.var_n = parameter(law, "var_n", var_n, unit="")
        gipt_f, vmc_f = parameter(law, "gipt", gipt, unit=""), parameter(law, "vmc", vmc, unit="")
        if gipt_f < 10 or gipt_f % 10:
            raise MaterialError(f"{law}: gipt must be a multiple of 10 (FEBio sums 10 Gauss "
                                f"points per part), got {gipt_f!r}")  # fmt: skip
        if vmc_f not in (1, 2):
            raise MaterialError(f"{law}: vmc must be 1 (semi-circular von Mises) or 2 "
                                f"(constrained), got {vmc_f!r}")  # fmt: skip
        if self.kf < 0.0:
            raise MaterialError(f"{law}: kf must be >= 0, got {self.kf!r}")
        self.gipt, self.vmc = int(gipt_f), int(vmc_f)
        self.mat_axis_a, self.mat_axis_d = mat_axis_a, mat_axis_d
        e1, e2 = local_axes(law, mat_axis_a, mat_axis_d)
        self.planar = planar_keys(mat_axis_a=mat_axis_a, mat_axis_d=mat_axis_d)
        t, c = von_mises_rule(self.kf, self.tp, self.gipt, self.vmc, self.var_n)
        e1, e2 = e1.reshape(-1, 1, 3), e2.reshape(-1, 1, 3)
        self.directions = np.cos(t)[None, :, None] * e1 + np.sin(t)[None, :, None] * e2
        self.weights = c[None]

    def parameters(self) -> dict[str, object]:
        f = self.fibre
        return {
            **self.matrix.parameters(),
            **dict(c3=f.c3, c4=f.c4, c5=f.c5, lam_max=f.lam_max, kf=self.kf, tp=self.tp),
            **dict(gipt=self.gipt, vmc=self.vmc, var_n=self.var_n),
            "mat_axis_a": np.asarray(self.mat_axis_a).tolist(),
            "mat_axis_d": np.asarray(self.mat_axis_d).tolist(),
        }

    def bind(
        self, n_points: int, dim: int, n_cells: int | None = None
    ) -> MooneyRivlinVonMisesFibers:
        """This law with per-element axes expanded to the body's integration points."""
        p = self.directions.shape[0]
        if dim == 3 and self.planar:
            raise MaterialError(f"{self.name}: the mat_axis has 2 components on a 3D body")
        if p in (1, n_points):
            return self
        if (n_cells is not None and p != n_cells) or n_points % p:
            raise MaterialError(f"{self.name}: {p} local axes do not match the body's "
                                f"{n_cells} elements")  # fmt: skip
        bound = object.__new__(type(self))
        bound.__dict__.update(self.__dict__)
        bound.directions = np.repeat(self.directions, n_points // p, axis=0)
        return bound

    def evaluate(self, F: np.ndarray, order: int = 2) -> MaterialResponse:
        F = check_input(F, order)
        if F.shape[-1] != 3:
            raise MaterialError(f"{self.name} runs on 3D bodies only")
        if self.directions.shape[0] not in (1, F.shape[0]):
            raise MaterialError(f"{self.name} has {self.directions.shape[0]} local axes but "
                                f"was given {F.shape[0]} deformation gradients")  # fmt: skip
        m = self.matrix.evaluate(F, order)
        f = fibre_sum(self.fibre, F, self.directions, self.weights, True, order)
        if order == 0:
            return MaterialResponse(m.energy + f.energy)
        if order == 1:
            return MaterialResponse(m.energy + f.energy, m.stress + f.stress)
        return MaterialResponse(m.energy + f.energy, m.stress + f.stress, m.tangent + f.tangent)
