"""FEBio's ``elastic damage`` and ``uncoupled elastic damage`` (``FEDamageMaterial.cpp``,
``FEDamageMaterialUC.cpp``): an elastic law whose stress is scaled by 1 - D, D a damage CDF
(``damage_functions.py``) of the running maximum of a damage criterion of the undamaged law.

FEBio's definition. At each point FEBio keeps Xmax, the largest criterion value of the
converged steps (``FEDamageMaterialPoint::Update``), and evaluates, at every Newton iterate,

    X = criterion(F),  D = Dmax CDF(max(X, Xmax)),  sigma = (1 - D) sigma_e(F),
    tangent (1 - D) c_e   (no dD/dF term)

(uncoupled: the deviatoric stress and tangent only; the bulk term U(J) is not damaged). D at
the current iterate makes the stress no derivative of an energy (its Jacobian, with the dD/dF
term, is not symmetric), and FEBio's tangent drops that term anyway.

tissuesim's step. D is frozen over a step from the accepted state, D_n = Dmax CDF(Xmax_n), and
Xmax is updated once the step is accepted (``accept_step``: Xmax_{n+1} = max(Xmax_n, X(F_{n+1})));
the step is then the minimum of the potential

    psi_step(F) = (1 - D_n) psi_e(F)        [uncoupled: (1 - D_n) psi_dev(F) + U(J)]

with P = (1 - D_n) P_e and dP/dF = (1 - D_n) A_e, exact and symmetric. The price: D lags one
step behind FEBio's (a step's damage grows from the criterion reached at the step before), an
O(h) difference in the softening branch only; at a held deformation the next step has FEBio's D.
Between steps the law answers with the accepted D (FEBio's D at the converged state).

State per integration point (``bind``): Xmax (n,); ``state_arrays`` saves it for checkpoints.
"""

from __future__ import annotations

import copy
import math

import numpy as np

from tissuesim.errors import MaterialError
from tissuesim.materials.base import Material, MaterialResponse
from tissuesim.materials.isotropic._common import check_input
from tissuesim.materials.reactive.damage_functions import DamageCDF, DamageCriterion
from tissuesim.materials.soft_tissue._hyperelastic import bulk_response, parameter
from tissuesim.materials.soft_tissue._hyperelastic import pressure_model as pressure_model_kind
from tissuesim.validate import short

__all__ = ["ElasticDamage", "UncoupledElasticDamage", "DAMAGE_LAWS"]


class ElasticDamage(Material):
    """FEBio's ``elastic damage``: (1 - D) times any elastic law, D = Dmax CDF(max X) of a
    damage criterion X; see the module docstring.

    ``ElasticDamage(NeoHookean(youngs_modulus=1e3, poisson_ratio=0.3), damage={"model":
    "weibull", "alpha": 2.0, "mu": 100.0}, criterion="von_mises_stress")``. ``density``
    (kg/m^3) is the specific strain energy criterion's divisor (the elastic law's density)."""

    name = "elastic_damage"
    febio_name = "elastic damage"
    uncoupled = False

    def __init__(
        self,
        elastic: Material | None = None,
        *,
        damage: object = None,
        criterion: object = None,
        density: float = 1.0,
    ) -> None:
        law = self.name
        if not isinstance(elastic, Material) or hasattr(elastic, "begin_step"):
            raise MaterialError(
                f"{law} needs an elastic law (elastic = a material without a history, e.g. "
                f"NeoHookean(...) or {{ model = 'neo_hookean', ... }}), not "
                f"{getattr(elastic, 'name', None) or short(elastic)}"
            )
        self._check_base(elastic)
        self.elastic = elastic
        self.cdf = DamageCDF(law, damage)
        self.criterion = DamageCriterion(law, "max_normal_lagrange_strain" if criterion is None
                                         else criterion)  # fmt: skip
        self.density = float(density)
        if not (self.density > 0.0 and math.isfinite(self.density)):
            raise MaterialError(f"{law}: density must be > 0 kg/m^3, got {density!r}")
        self.mu, self.lam = elastic.mu, elastic.lam
        self._n: int | None = None
        self._xmax: np.ndarray | None = None
        self._in_step = False

    def _check_base(self, elastic: Material) -> None:
        """Coupled: any law."""

    def __repr__(self) -> str:
        return (f"{type(self).__name__}({self.elastic!r}, damage={self.cdf.as_table()!r}, "
                f"criterion={self.criterion.as_table()!r})")  # fmt: skip

    # -- the state ------------------------------------------------------------------------
    @property
    def bound(self) -> bool:
        return self._n is not None

    def bind(self, n_points: int, dim: int, n_cells: int | None = None) -> ElasticDamage:
        """A copy holding Xmax = 0 for ``n_points`` integration points."""
        out = copy.copy(self)
        if hasattr(self.elastic, "bind"):
            out.elastic = self.elastic.bind(n_points, dim, n_cells)
        out._n = int(n_points)
        out._xmax = np.zeros(out._n)
        out._in_step = False
        return out

    def _need_state(self, what: str) -> None:
        if not self.bound:
            raise MaterialError(f"{self.name}: {what} needs the state of a body's integration "
                                "points; a damage material works on FEM bodies")  # fmt: skip

    def begin_step(self, h: float) -> None:
        """A step starts: D stays the accepted state's over it (nothing is written)."""
        self._need_state("begin_step")
        self._in_step = True

    def accept_step(self, F: np.ndarray) -> None:
        """The step converged at ``F`` (n, d, d): Xmax = max(Xmax, X(F))."""
        self._need_state("accept_step")
        self._xmax = np.maximum(self._xmax, self.criterion_value(F))
        self._in_step = False

    def state_arrays(self) -> dict[str, np.ndarray]:
        self._need_state("state_arrays")
        return {"xmax": self._xmax.copy()}

    def set_state_arrays(self, arrays: dict[str, np.ndarray]) -> None:
        self._need_state("set_state_arrays")
        x = np.asarray(arrays["xmax"], dtype=float)
        if x.shape != self._xmax.shape:
            raise MaterialError(f"{self.name}: a state of shape {x.shape} does not fit "
                                f"{self._xmax.shape}")  # fmt: skip
        self._xmax, self._in_step = x.copy(), False

    @property
    def damage(self) -> np.ndarray:
        """D (n,) of the accepted state."""
        self._need_state("damage")
        return self.cdf(self._xmax)

    @property
    def criterion_maximum(self) -> np.ndarray:
        """Xmax (n,) of the accepted state."""
        self._need_state("criterion_maximum")
        return self._xmax.copy()

    # -- the law --------------------------------------------------------------------------
    def _damaged(self, F: np.ndarray, order: int) -> MaterialResponse:
        return self.elastic.evaluate(F, order)

    def _rest(self, F: np.ndarray, order: int) -> MaterialResponse | None:
        return None

    def criterion_value(self, F: np.ndarray) -> np.ndarray:
        """X (n,) of the undamaged law at F (a 2D F as plane strain, F_33 = 1)."""
        F = check_input(F, 1)
        if F.shape[-1] == 2:
            full = np.zeros((F.shape[0], 3, 3))
            full[:, :2, :2], full[:, 2, 2] = F, 1.0
            F = full
        r, rest = self._damaged(F, 1), self._rest(F, 1)
        psi, P = r.energy, r.stress
        if rest is not None:
            psi, P = psi + rest.energy, P + rest.stress
        return self.criterion(F, psi, P, self.density)

    def _factor(self, q: int) -> float | np.ndarray:
        if not self.bound or q != self._n:
            return 1.0
        return 1.0 - self.cdf(self._xmax)

    def evaluate(self, F: np.ndarray, order: int = 2) -> MaterialResponse:
        """psi = (1 - D) psi_e (+ U(J) uncoupled), P and dP/dF alike, D of the accepted state
        (frozen over a step). Shapes as ``Material.evaluate``."""
        F = check_input(F, order)
        s = self._factor(F.shape[0])
        s = np.asarray(s, dtype=float)
        r, rest = self._damaged(F, order), self._rest(F, order)
        with np.errstate(invalid="ignore"):
            psi = np.where(np.isfinite(r.energy), s * r.energy, r.energy)
        if rest is not None:
            psi = psi + rest.energy
        if order == 0:
            return MaterialResponse(psi)
        P = s[..., None, None] * r.stress if s.ndim else s * r.stress
        if rest is not None:
            P = P + rest.stress
        if order == 1:
            return MaterialResponse(psi, P)
        A = s[..., None, None, None, None] * r.tangent if s.ndim else s * r.tangent
        if rest is not None:
            A = A + rest.tangent
        return MaterialResponse(psi, P, A)


class UncoupledElasticDamage(ElasticDamage):
    """FEBio's ``uncoupled elastic damage``: (1 - D) on the deviatoric part of an uncoupled law
    (``mooney_rivlin``, ``fiber_pow_linear_uncoupled``, ...), the law less its own bulk term;
    the wrapper's own bulk term U(J) (``k``, default 0, and ``pressure_model``, as FEBio's) is
    not damaged (in an uncoupled solid mixture the mixture's k gives U: the component's is 0)."""

    name = "uncoupled_elastic_damage"
    febio_name = "uncoupled elastic damage"
    uncoupled = True

    def _check_base(self, elastic: Material) -> None:
        from tissuesim.materials.soft_tissue.ogden import Ogden

        if not (isinstance(elastic, Ogden) or getattr(elastic, "uncoupled", False) is True):
            raise MaterialError(
                f"{self.name} needs an uncoupled elastic law (mooney_rivlin, ogden, "
                f"fiber_pow_linear_uncoupled, ...), not {getattr(elastic, 'name', '?')}; use "
                "elastic_damage for the others"
            )

    def __init__(
        self,
        elastic: Material | None = None,
        *,
        damage: object = None,
        criterion: object = None,
        density: float = 1.0,
        k: float = 0.0,
        pressure_model: str | int = "default",
    ) -> None:
        super().__init__(elastic, damage=damage, criterion=criterion, density=density)
        self.k = parameter(self.name, "k", k, meaning="bulk modulus")
        if self.k < 0.0:
            raise MaterialError(f"{self.name}: k (bulk modulus) must be >= 0 Pa, got {self.k!r}")
        self.bulk_kind = pressure_model_kind(self.name, pressure_model)
        self.lam = self.k - 2.0 * self.mu / 3.0

    def _damaged(self, F: np.ndarray, order: int) -> MaterialResponse:
        """The elastic law's deviatoric part: the law less its own bulk term (if any)."""
        base = self.elastic
        full = base.evaluate(F, order)
        k0 = float(getattr(base, "k", 0.0) or 0.0)
        if k0 == 0.0:
            return full
        bulk = bulk_response(base.name, getattr(base, "bulk_kind", "log"), k0, F, order)
        with np.errstate(invalid="ignore"):
            psi = np.where(np.isfinite(full.energy), full.energy - bulk.energy, math.inf)
        if order == 0:
            return MaterialResponse(psi)
        P = full.stress - bulk.stress
        if order == 1:
            return MaterialResponse(psi, P)
        return MaterialResponse(psi, P, full.tangent - bulk.tangent)

    def _rest(self, F: np.ndarray, order: int) -> MaterialResponse | None:
        """U(J) with the wrapper's own k and pressure_model (FEBio's: not the elastic law's)."""
        return None if self.k == 0.0 else bulk_response(self.name, self.bulk_kind, self.k, F,
                                                         order)  # fmt: skip


#: the damage wrappers by name (``make_material`` builds their ``elastic`` law from a table)
DAMAGE_LAWS: dict[str, type[ElasticDamage]] = {
    ElasticDamage.name: ElasticDamage,
    UncoupledElasticDamage.name: UncoupledElasticDamage,
}
