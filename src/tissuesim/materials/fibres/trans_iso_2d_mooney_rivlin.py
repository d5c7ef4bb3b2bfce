"""FEBio's ``2D trans iso Mooney-Rivlin`` (``FE2DTransIsoMooneyRivlin.cpp``): an uncoupled
Mooney-Rivlin matrix and fibres spread in the plane normal to ``fiber`` (the transverse axis),
12 directions over the circle with weights from an ellipse:

    W = c1 (I1b - 3) + c2 (I2b - 3) + U(J) + sum_n c_n f(Ib_n),   Ib_n = J^(-2/3) a_n . C a_n
    v_n = (0, cos t_n, sin t_n),  t_n = 2 pi n / 12,  a_n = R v_n,
    c_n = w_n / sum w,  w_n = 1 / sqrt((cos t_n / w1)^2 + (sin t_n / w2)^2)

R the rotation that takes x to ``fiber`` (FEBio's quatd(x, r): about x ^ r by the angle
between them), f trans iso Mooney-Rivlin's fibre (``fiber_exp_linear_uncoupled``: l dW/dl =
c3 (exp(c4 (l - 1)) - 1) up to lam_max, c5 l + c6 past it; c3 = 0 kept, as FEBio does), and its
stress and tangent the sum of the matrix's and ``continuous_distribution.fibre_sum``'s. FEBio's
``active_contraction`` (and its ``a``) must be 0.
"""

from __future__ import annotations

import numpy as np

from tissuesim.errors import MaterialError
from tissuesim.materials.base import MaterialResponse
from tissuesim.materials.fibres._fibres import planar_keys, unit_vectors
from tissuesim.materials.fibres.continuous_distribution import fibre_sum
from tissuesim.materials.fibres.fibre_exp_linear import ExpLinearFibre, FiberExpLinearUncoupled
from tissuesim.materials.isotropic._common import check_input
from tissuesim.materials.soft_tissue._hyperelastic import (
    HyperelasticMaterial,
    parameter,
    parameter_list,
)
from tissuesim.materials.soft_tissue.mooney_rivlin import MooneyRivlin

__all__ = ["TransIso2DMooneyRivlin", "rotation_from_x"]

#: FEBio's NSTEPS
_STEPS = 12


def rotation_from_x(r: np.ndarray) -> np.ndarray:
    """(p, 3, 3) rotations taking x to the unit vectors r (p, 3) about x ^ r (FEBio's quatd)."""
    x = np.array([1.0, 0.0, 0.0])
    n = np.cross(x, r)
    s = np.linalg.norm(n, axis=-1)
    c = r[:, 0]
    n = np.where(s[:, None] > 0.0, n / np.where(s > 0.0, s, 1.0)[:, None], 0.0)
    K = np.zeros((len(r), 3, 3))
    K[:, 0, 1], K[:, 0, 2], K[:, 1, 2] = -n[:, 2], n[:, 1], -n[:, 0]
    K -= np.swapaxes(K, 1, 2)
    return np.eye(3) + s[:, None, None] * K + (1.0 - c)[:, None, None] * (K @ K)


class TransIso2DMooneyRivlin(HyperelasticMaterial):
    """FEBio's ``2D trans iso Mooney-Rivlin``: Mooney-Rivlin (c1, c2, k) plus fibres in the
    plane normal to ``fiber``, weighted by the ellipse ``w`` = (w1, w2)."""

    name = "2d_trans_iso_mooney_rivlin"
    febio_name = "2D trans iso Mooney-Rivlin"
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
        w: object = (1.0, 1.0),
        a: object = (1.0, 1.0),
        active_contraction: float = 0.0,
        fiber: object = (1.0, 0.0, 0.0),
    ) -> None:
        law = self.name
        self.matrix = MooneyRivlin(c1=c1, c2=c2, k=k, pressure_model=pressure_model)
        self.c1, self.c2, self.k = self.matrix.c1, self.matrix.c2, self.matrix.k
        self.bulk_kind = self.matrix.bulk_kind
        self.mu, self.lam = self.matrix.mu, self.matrix.lam
        self.fibre = FiberExpLinearUncoupled(c3=c3, c4=c4, c5=c5, lam_max=lam_max)
        self.fibre._fibre = ExpLinearFibre(law, c3, c4, c5, lam_max, continuous_slope=False)
        self.w = parameter_list(law, "w", w, unit="")
        self.a = parameter_list(law, "a", a, unit="")
        if len(self.w) != 2 or min(self.w) <= 0.0:
            raise MaterialError(f"{law}: w must be two numbers > 0, got {self.w!r}")
        self.active_contraction = parameter(law, "active_contraction", active_contraction)
        if self.active_contraction != 0.0:
            raise MaterialError(f"{law}: active_contraction other than 0 is not supported by "
                                "tissuesim")  # fmt: skip
        self.fiber = unit_vectors(law, "fiber", fiber)
        self.planar = planar_keys(fiber=fiber)
        r = self.fiber.reshape(-1, 3)
        if np.any(r[:, 0] <= -1.0 + 1e-12):
            raise MaterialError(f"{law}: fiber along -x has no rotation from x (FEBio's quatd "
                                "is undefined there); give +x")  # fmt: skip
        t = 2.0 * np.pi * np.arange(_STEPS) / _STEPS
        v = np.stack([np.zeros(_STEPS), np.cos(t), np.sin(t)], axis=1)
        self.directions = v @ np.swapaxes(rotation_from_x(r), 1, 2)  # (p, 12, 3)
        wn = 1.0 / np.sqrt((np.cos(t) / self.w[0]) ** 2 + (np.sin(t) / self.w[1]) ** 2)
        self.weights = (wn / wn.sum())[None]

    def parameters(self) -> dict[str, object]:
        f = self.fibre
        return {
            **self.matrix.parameters(),
            **dict(c3=f.c3, c4=f.c4, c5=f.c5, lam_max=f.lam_max, w=self.w, a=self.a),
            "fiber": self.fiber.tolist(),
        }

    def bind(self, n_points: int, dim: int, n_cells: int | None = None) -> TransIso2DMooneyRivlin:
        """This law with per-element fibres expanded to the body's integration points."""
        p = self.directions.shape[0]
        if dim == 3 and self.planar:
            raise MaterialError(f"{self.name}: fiber has 2 components on a 3D body")
        if p in (1, n_points):
            return self
        if (n_cells is not None and p != n_cells) or n_points % p:
            raise MaterialError(f"{self.name}: {p} fibre directions do not match the body's "
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
            raise MaterialError(f"{self.name} has {self.directions.shape[0]} fibre directions "
                                f"but was given {F.shape[0]} deformation gradients")  # fmt: skip
        m = self.matrix.evaluate(F, order)
        f = fibre_sum(self.fibre, F, self.directions, self.weights, True, order)
        if order == 0:
            return MaterialResponse(m.energy + f.energy)
        if order == 1:
            return MaterialResponse(m.energy + f.energy, m.stress + f.stress)
        return MaterialResponse(m.energy + f.energy, m.stress + f.stress, m.tangent + f.tangent)
