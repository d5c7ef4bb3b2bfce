"""FEBio's ``kinematic growth`` (``FEKinematicGrowth``, the growth tensors of
``FEGrowthTensor.cpp``): an elastic law evaluated at the elastic part Fe = F Fg^-1 of the
deformation, Fg a prescribed growth tensor that follows the time. FEBio's four tensors are each

    Fg = a (I - n n) + b n n,      Fg^-1 = (I - n n) / a + n n / b,      Jg = a^2 b

with n the growth's ``fiber`` (FEBio's default (1, 0, 0)) and, from its multipliers,

    volume growth    a = b = g                 area growth     a = sqrt(g), b = 1
    fiber growth     a = 1, b = g              general growth  a = iso, b = iso + ani - 1

(FEBio's inverses, written out there, are these). FEBio takes the elastic law's Cauchy stress
at Fe; per unit reference volume that is the energy and its derivatives

    W = Jg W_e(Fe)      P = Jg P_e(Fe) Fg^-1      dP_ij / dF_kl = Jg A_e,imkn(Fe) G_jm G_ln

(G = Fg^-1, symmetric). A multiplier is a number or an expression of t (FEBio's value times its
load curve); the law keeps the time (``_time.py``). 3D only (a growth tensor has no plane-strain
form: Fe_33 = 1/Fg_33 is not the plane-strain restriction of the elastic law).
"""

from __future__ import annotations

import numpy as np

from tissuesim.errors import MaterialError
from tissuesim.materials.active._time import TimeKept, time_function
from tissuesim.materials.base import Material, MaterialResponse
from tissuesim.materials.isotropic._common import check_input
from tissuesim.validate import short

__all__ = ["KinematicGrowth", "GROWTH_TYPES"]

#: growth type -> its multipliers (FEBio's parameter names)
GROWTH_TYPES = {
    "volume": ("multiplier",),
    "area": ("multiplier",),
    "fiber": ("multiplier",),
    "general": ("iso", "ani"),
}


class KinematicGrowth(TimeKept, Material):
    """FEBio's ``kinematic growth``: ``elastic`` (a material) at Fe = F Fg^-1, ``growth`` one
    of ``GROWTH_TYPES`` with its multipliers (numbers or expressions of t, default 1) and
    ``fiber`` n.

    ``KinematicGrowth(elastic=NeoHookean(youngs_modulus=1.0, poisson_ratio=0.3),
    growth="volume", multiplier="1 + t")``"""

    name = "kinematic_growth"

    def __init__(
        self,
        *,
        elastic: Material | None = None,
        growth: str = "volume",
        multiplier: float | str = 1.0,
        iso: float | str = 1.0,
        ani: float | str = 1.0,
        fiber: object = (1.0, 0.0, 0.0),
    ) -> None:
        law = self.name
        if not isinstance(elastic, Material):
            raise MaterialError(f"{law}: elastic must be a material, not {short(elastic)}")
        if hasattr(elastic, "begin_step"):
            raise MaterialError(
                f"{law}: elastic ({elastic.name}) keeps a history; kinematic growth takes an "
                "elastic law"
            )
        if getattr(elastic, "uncoupled", False) is True:
            raise MaterialError(
                f"{law}: elastic ({elastic.name}) is uncoupled; FEBio's kinematic growth takes "
                "a coupled law"
            )
        if growth not in GROWTH_TYPES:
            raise MaterialError(
                f"{law}: growth {short(growth)} is not one of {', '.join(GROWTH_TYPES)}"
            )
        from tissuesim.materials.fibres._fibres import unit_vectors

        self.elastic = elastic
        self.growth = growth
        given = {"multiplier": multiplier, "iso": iso, "ani": ani}
        self.values = {k: given[k] for k in GROWTH_TYPES[growth]}
        unused = [k for k in ("multiplier", "iso", "ani") if k not in self.values]
        for k in unused:
            if given[k] != 1.0:
                raise MaterialError(
                    f"{law}: {growth} growth takes {', '.join(GROWTH_TYPES[growth])}, not {k}"
                )
        self._f = {k: time_function(law, k, v) for k, v in self.values.items()}
        self.fiber = unit_vectors(law, "fiber", fiber)
        if self.fiber.ndim != 1:
            raise MaterialError(f"{law}: fiber is one vector for the whole body")
        self.mu, self.lam = elastic.mu, elastic.lam
        self._factors(0.0)  # a growth that fails fails here

    def parameters(self) -> dict[str, object]:
        return {"growth": self.growth, **self.values, "fiber": self.fiber.tolist()}

    def __repr__(self) -> str:
        args = ", ".join(f"{k}={v!r}" for k, v in self.parameters().items())
        return f"{type(self).__name__}(elastic={self.elastic!r}, {args})"

    def bind(self, n_points: int, dim: int, n_cells: int | None = None) -> KinematicGrowth:
        """This law with its elastic law's per-element directions bound."""
        if not hasattr(self.elastic, "bind"):
            return self
        bound = self.elastic.bind(n_points, dim, n_cells)
        if bound is self.elastic:
            return self
        out = object.__new__(type(self))
        out.__dict__.update(self.__dict__)
        out.elastic = bound
        return out

    def _factors(self, t: float) -> tuple[float, float]:
        """(a, b) of Fg = a (I - n n) + b n n at time t."""
        v = {k: f(t) for k, f in self._f.items()}
        if self.growth == "volume":
            a = b = v["multiplier"]
        elif self.growth == "area":
            if not v["multiplier"] > 0.0:
                raise MaterialError(f"{self.name}: the area multiplier is {v['multiplier']!r} "
                                    f"at t = {t:g}; it must be > 0")  # fmt: skip
            a, b = float(np.sqrt(v["multiplier"])), 1.0
        elif self.growth == "fiber":
            a, b = 1.0, v["multiplier"]
        else:
            a, b = v["iso"], v["iso"] + v["ani"] - 1.0
        if not (a > 0.0 and b > 0.0):
            raise MaterialError(
                f"{self.name}: the {self.growth} growth tensor at t = {t:g} has stretches "
                f"{a!r}, {b!r}; they must be > 0"
            )
        return a, b

    def growth_tensor(self) -> np.ndarray:
        """Fg (3, 3) at the time of the step in progress."""
        a, b = self._factors(self._trial)
        nn = np.outer(self.fiber, self.fiber)
        return a * (np.eye(3) - nn) + b * nn

    def evaluate(self, F: np.ndarray, order: int = 2) -> MaterialResponse:
        F = check_input(F, order)
        if F.shape[-1] != 3:
            raise MaterialError(
                f"{self.name} is 3D only (a growth tensor has no plane-strain form)"
            )
        a, b = self._factors(self._trial)
        nn = np.outer(self.fiber, self.fiber)
        G = (np.eye(3) - nn) / a + nn / b
        Jg = a * a * b
        res = self.elastic.evaluate(F @ G, order)
        psi = Jg * res.energy
        if order == 0:
            return MaterialResponse(psi)
        P = Jg * res.stress @ G
        if order == 1:
            return MaterialResponse(psi, P)
        A = Jg * np.einsum("qimkn,jm,ln->qijkl", res.tangent, G, G, optimize=True)
        return MaterialResponse(psi, P, A)
