"""FEBio's ``viscoelastic damage`` (``FEViscoElasticDamage.cpp``): the Prony series of
``viscoelastic`` (``materials/viscoelastic.py``) on the undamaged law of an ``elastic damage``,
the whole stress scaled by its 1 - D:

    S = (1 - D) [g0 Se + sum_i g_i H_i],   H_i^{n+1} = e_i H_i^n + gamma_i (Se^{n+1} - Se^n),

Se the undamaged law's second Piola-Kirchhoff stress, D = Dmax CDF(max X) of the damage's
criterion on the undamaged law. As for ``elastic damage`` (``damage.py``), D is frozen over a
step at the accepted state's, so the step minimises (1 - D_n) [a psi_e + S_h : E] (the
viscoelastic step's potential times a constant per point), with the exact tangent; the
criterion's maximum is updated once the step is accepted, with the history H.
"""

from __future__ import annotations

import numpy as np

from tissuesim.errors import MaterialError
from tissuesim.materials.base import Material, MaterialResponse
from tissuesim.materials.isotropic._common import check_input
from tissuesim.materials.reactive.damage import ElasticDamage
from tissuesim.materials.viscoelastic import Viscoelastic
from tissuesim.validate import short

__all__ = ["ViscoelasticDamage"]


class ViscoelasticDamage(Viscoelastic):
    """FEBio's ``viscoelastic damage``: ``elastic`` an ``ElasticDamage``; ``g``, ``tau``,
    ``g0`` as ``Viscoelastic``'s. ``ViscoelasticDamage(ElasticDamage(NeoHookean(...),
    damage={...}, criterion=...), g=[2.0], tau=[5.0])``."""

    name = "viscoelastic_damage"
    febio_name = "viscoelastic damage"

    def __init__(
        self,
        elastic: Material | None = None,
        *,
        g: object = None,
        tau: object = None,
        g0: float = 1.0,
    ) -> None:
        if not isinstance(elastic, ElasticDamage) or elastic.uncoupled:
            raise MaterialError(
                f"{self.name} needs elastic = an elastic_damage law (FEBio's elastic damage), "
                f"not {getattr(elastic, 'name', None) or short(elastic)}"
            )
        self.damaged = elastic
        super().__init__(elastic.elastic, g=g, tau=tau, g0=g0)

    def __repr__(self) -> str:
        return (f"{type(self).__name__}({self.damaged!r}, g={self.g!r}, tau={self.tau!r}, "
                f"g0={self.g0!r})")  # fmt: skip

    def bind(self, n_points: int, dim: int, n_cells: int | None = None) -> ViscoelasticDamage:
        out = super().bind(n_points, dim, n_cells)
        out.damaged = self.damaged.bind(n_points, dim, n_cells)
        out.damaged.elastic = out.elastic
        return out

    def begin_step(self, h: float) -> None:
        super().begin_step(h)
        self.damaged.begin_step(h)

    def accept_step(self, F: np.ndarray) -> None:
        super().accept_step(F)
        self.damaged.accept_step(F)

    def state_arrays(self) -> dict[str, np.ndarray]:
        """The Prony history (H, Se) and the damage's (``damage_xmax``)."""
        out = super().state_arrays()
        out.update({f"damage_{k}": v for k, v in self.damaged.state_arrays().items()})
        return out

    def set_state_arrays(self, arrays: dict[str, np.ndarray]) -> None:
        super().set_state_arrays({k: arrays[k] for k in ("H", "Se")})
        self.damaged.set_state_arrays({k[7:]: v for k, v in arrays.items()
                                       if k.startswith("damage_")})  # fmt: skip

    def _scale(self, q: int) -> np.ndarray | float:
        if not self.damaged.bound or q != self._n:
            return 1.0
        return 1.0 - self.damaged.damage

    def evaluate(self, F: np.ndarray, order: int = 2) -> MaterialResponse:
        """The viscoelastic law's response times 1 - D (per point; D of the accepted state)."""
        F = check_input(F, order)
        r = super().evaluate(F, order)
        s = np.asarray(self._scale(F.shape[0]), dtype=float)
        if s.ndim == 0:
            s = np.full(F.shape[0], float(s))
        with np.errstate(invalid="ignore"):
            psi = np.where(np.isfinite(r.energy), s * r.energy, r.energy)
        if order == 0:
            return MaterialResponse(psi)
        P = s[:, None, None] * r.stress
        if order == 1:
            return MaterialResponse(psi, P)
        return MaterialResponse(psi, P, s[:, None, None, None, None] * r.tangent)

    def stored_energy_density(self, F: np.ndarray) -> np.ndarray:
        return np.asarray(self._scale(np.shape(F)[0])) * super().stored_energy_density(F)
