"""FEBio's ``reactive viscoelastic`` and ``uncoupled reactive viscoelastic``
(``FEReactiveViscoelastic.cpp``, ``FEUncoupledReactiveViscoelastic.cpp``): strong bonds (an
elastic law, ``elastic``) plus weak bonds (``bond``, another law) that break and reform in
generations, each generation loaded from the stretch at which it formed and decaying with a
relaxation function g (``relaxation.py``).

FEBio's definition. Per point FEBio keeps a list of generations: generation k formed at the
right stretch U_k^ref (the identity for the first, the original bonds), started breaking at
time v_k, with mass f_k and the stretch U_k at v_k (its K2 = |dev ln U_k| for the
distortion-dependent g). At time t the weak bonds' stress is

    sigma_w = sum_k w_k sigma_b(F (U_k^ref)^-1) / det U_k^ref,
    kinetics 1 (type I):  w_k = f_k g(t - v_k; K2_k),
    kinetics 2 (type II): w_k = g(t - v_k; K2_k) - g(t - v_(k-1); K2_k)  (w_0 = g(t - v_0; K2_0)),

both type II terms at generation k's own K2 (FEBio's ``BreakingBondMassFraction`` sets F to
U_k for both), so the type II weights need not sum to 1,

and the newest generation is created while solving the step to t (FEBio's
``UpdateSpecializedMaterialPoints`` runs at each iterate): when the strain of F relative to the
last stretch U_r (any strain: |E|; distortional: |dev h|; dilatational: |ln J|, ``trigger``)
exceeds max(emin, 10 machine epsilon) and the reforming mass f_r = 1 - sum_k w_k(t) is at least
wmin, the bonds formed at U_r start breaking at v = t with mass f_r and weight f_r g(0) = f_r,
and U_r becomes U(F). Before any generation the weak bonds carry sigma_b(F) in full. Type II
weighs the reforming bonds 1 - g(t - v_last; K2) (``generations.weights``), FEBio with K2 of
the current F; tissuesim takes the last generation's K2 (the previous step's stretch), as a
weight that followed F would leave the step without a potential: FEBio's ma28 (exp_distortion,
type II) is -6.6e-5 from FEBio's norm with it, 2.8e-10 with K2 following F in the stress.

The incremental potential. Within the step to t = t_n + h every generation's reference, time
and mass are fixed, and sigma_b(F U^-1)/det U is the Cauchy stress of the energy
psi_b(F U^-1) per unit reference volume (d psi_b(F U^-1)/dF = P_b(F U^-1) U^-1, U symmetric),
so the step is the minimum of

    psi_step(F) = psi_s(F) + sum_k w_k(t) psi_b(F (U_k^ref)^-1) + c(F) f_r(t) psi_b(F U_r^-1)

with P = P_s + sum_k w_k P_b(F_k) U_k^-1 (+ the reforming term alike) and
dP_ij/dF_kl = A_s,ijkl + sum_k w_k A_b,ipkq(F_k) U^-1_pj U^-1_lq: exact and symmetric (FEBio's
tangent is the same sum of the bonds' tangents). c(F) is FEBio's rule: the reforming bonds
count once the strain from U_r passes the threshold and f_r >= wmin (always before the first
generation), so
psi_step jumps by f_r psi_b, of order E emin^2, where the strain crosses emin, and its stress by
order E emin (nothing for emin = 0). ``accept_step(F)`` applies the same rule to the converged F:
the generation is created (or not) and U_r set. (FEBio keeps a generation created at an earlier
iterate of the step even if the converged strain fell back below the threshold.)

FEBio's culling (``wmin`` > 0, ``generations.py``) runs on the accepted step too, where FEBio
culls at the first iterate that creates the generation (the merged generation, whose weight is
below wmin, enters the stress a step later).

Bond recruitment (``recruitment``, FEBio's ``FEBondRecruitment``: ``recruitment.py``) weighs
each generation by brf(X), X the trigger's scalar strain of the total F when it forms (FEBio's
``ScalarStrain``: |E|, |dev ln V| or |ln J|), kept with the generation (``wv``). FEBio sets the
forming generation's brf at every iterate of its step, so at its converged point the weight is
brf(X(F)) of that F, with no derivative of brf in its stress or tangent: not a potential. The
step here holds the forming bonds' brf at a lagged strain X_lag (the last accepted one at the
step's start), minimises, and re-lags X_lag at the converged F (``relag``, with the steps' other
lagged terms: ``time/lags.py``) until brf no longer changes: that fixed point is FEBio's
converged state. The potential of each solve is exact (the weight a constant in it). A strong
bond with FEBio's ``elastic damage`` scales the weak bonds by its 1 - D, D frozen over the step
as the damage law's own (``damage.py``).
Uncoupled: strong and weak bonds are the deviatoric parts of uncoupled laws (each law less its
own bulk term), and the wrapper's ``k`` and ``pressure_model`` give the bulk term U(J).

State per integration point (``bind``): the generations (``generations.py``: FEBio's lists
padded to the largest count, U_r, the time since the start); ``state_arrays`` for checkpoints.
"""

from __future__ import annotations

import copy
import math

import numpy as np

from tissuesim.errors import MaterialError
from tissuesim.materials.base import Material, MaterialResponse
from tissuesim.materials.isotropic._common import check_input
from tissuesim.materials.reactive import generations as gen
from tissuesim.materials.reactive.damage import ElasticDamage
from tissuesim.materials.reactive.recruitment import Recruitment
from tissuesim.materials.reactive.relaxation import Relaxation
from tissuesim.materials.soft_tissue._hyperelastic import bulk_response, parameter
from tissuesim.materials.soft_tissue._hyperelastic import pressure_model as pressure_model_kind
from tissuesim.validate import short

__all__ = ["ReactiveViscoelastic", "UncoupledReactiveViscoelastic", "REACTIVE_VISCOELASTIC_LAWS"]

_EPS = 10.0 * np.finfo(float).eps


class ReactiveViscoelastic(Material):
    """FEBio's ``reactive viscoelastic``: ``elastic`` (strong bonds) plus ``bond`` (weak bonds
    in generations) relaxing by ``relaxation``; see the module docstring.

    ``ReactiveViscoelastic(NeoHookean(...), bond=NeoHookean(...), relaxation={"model":
    "exponential", "tau": 0.2})``. Parameters: ``kinetics`` 1 or 2 (FEBio's type I, II),
    ``trigger`` 0 (any strain), 1 (distortional), 2 (dilatational), ``emin`` >= 0,
    ``wmin`` in [0, 1] (FEBio's culling of generations lighter than wmin), ``recruitment``
    (a bond recruitment table, ``recruitment.py``; None: every generation weighs 1)."""

    name = "reactive_viscoelastic"
    febio_name = "reactive viscoelastic"
    uncoupled = False

    def __init__(
        self,
        elastic: Material | None = None,
        *,
        bond: Material | None = None,
        relaxation: object = None,
        kinetics: int = 1,
        trigger: int = 0,
        emin: float = 0.0,
        wmin: float = 0.0,
        recruitment: object = None,
    ) -> None:
        law = self.name
        for key, part in (("elastic", elastic), ("bond", bond)):
            damaged = key == "elastic" and isinstance(part, ElasticDamage)  # FEBio's too
            if not isinstance(part, Material) or (hasattr(part, "begin_step") and not damaged):
                raise MaterialError(
                    f"{law} needs {key} = an elastic law without a history (e.g. "
                    f"NeoHookean(...) or {{ model = 'neo_hookean', ... }}), not "
                    f"{getattr(part, 'name', None) or short(part)}"
                )
            self._check_part(key, part)
        self.elastic, self.bond = elastic, bond
        self.relaxation = Relaxation(law, relaxation)
        self.kinetics = self._choice("kinetics", kinetics, (1, 2))
        self.trigger = self._choice("trigger", trigger, (0, 1, 2))
        self.emin = parameter(law, "emin", emin, unit="")
        if self.emin < 0.0:
            raise MaterialError(f"{law}: emin must be >= 0, got {self.emin!r}")
        self.wmin = parameter(law, "wmin", wmin, unit="")
        if not 0.0 <= self.wmin <= 1.0:
            raise MaterialError(f"{law}: wmin must be in [0, 1], got {self.wmin!r}")
        self.recruitment = None if recruitment is None else Recruitment(law, recruitment)
        self.mu, self.lam = elastic.mu + bond.mu, elastic.lam + bond.lam
        self._x_lag: np.ndarray | None = None  # the forming bonds' strain X in a step
        self._n: int | None = None
        self._s: dict[str, np.ndarray] = {}
        self._h: float | None = None  # the step in progress

    def _choice(self, key: str, value: object, allowed: tuple[int, ...]) -> int:
        x = parameter(self.name, key, value, unit="")
        if x not in allowed:
            raise MaterialError(f"{self.name}: {key} must be one of {allowed}, got {value!r}")
        return int(x)

    def _check_part(self, key: str, part: Material) -> None:
        """Coupled: any law."""

    def __repr__(self) -> str:
        return (f"{type(self).__name__}({self.elastic!r}, bond={self.bond!r}, relaxation="
                f"{self.relaxation.as_table()!r}, kinetics={self.kinetics})")  # fmt: skip

    # -- the state ------------------------------------------------------------------------
    @property
    def bound(self) -> bool:
        return self._n is not None

    def bind(self, n_points: int, dim: int, n_cells: int | None = None) -> ReactiveViscoelastic:
        """A copy with no generations at ``n_points`` points (d = ``dim``)."""
        out = copy.copy(self)
        for key in ("elastic", "bond"):
            part = getattr(self, key)
            if hasattr(part, "bind"):
                setattr(out, key, part.bind(n_points, dim, n_cells))
        out._n = int(n_points)
        out._s = gen.new_state(out._n, dim)
        out._h = None
        return out

    def _need_state(self, what: str) -> None:
        if not self.bound:
            raise MaterialError(
                f"{self.name}: {what} needs the state of a body's integration points; a "
                "reactive viscoelastic material works on FEM bodies"
            )

    def begin_step(self, h: float) -> None:
        """A step of ``h`` s starts from the accepted state (which it does not change)."""
        self._need_state("begin_step")
        self._h = float(h)
        self._x_lag = self._s["et"].copy()  # the forming bonds' strain, from the last step
        if hasattr(self.elastic, "begin_step"):  # a damaged strong bond
            self.elastic.begin_step(h)

    def state_arrays(self) -> dict[str, np.ndarray]:
        """The generations (``generations.KEYS``) and a damaged strong bond's (``base_...``)."""
        self._need_state("state_arrays")
        out = {k: v.copy() for k, v in self._s.items()}
        if hasattr(self.elastic, "state_arrays"):
            out.update({f"base_{k}": v for k, v in self.elastic.state_arrays().items()})
        return out

    def set_state_arrays(self, arrays: dict[str, np.ndarray]) -> None:
        self._need_state("set_state_arrays")
        arrays = dict(arrays)  # a state from before recruitment: every weight 1
        for key in gen.RECRUITMENT_KEYS:
            if key not in arrays:
                v = np.asarray(arrays["v"])
                arrays[key] = np.ones(v.shape) if key == "wv" else np.zeros(v.shape[0])
        s = {k: np.asarray(arrays[k], dtype=float).copy() for k in gen.KEYS}
        if s["ur"].shape != self._s["ur"].shape or s["v"].shape[0] != self._n:
            raise MaterialError(f"{self.name}: a state for {s['v'].shape[0]} points does not fit "
                                f"{self._n}")  # fmt: skip
        if hasattr(self.elastic, "set_state_arrays"):
            base = {k[5:]: v for k, v in arrays.items() if k.startswith("base_")}
            self.elastic.set_state_arrays(base)
        self._s, self._h = s, None

    @property
    def generations(self) -> np.ndarray:
        """The number of breaking generations at each point (n,)."""
        self._need_state("generations")
        return self._s["count"].astype(int)

    # -- the weights ----------------------------------------------------------------------
    def _time(self) -> float:
        return float(self._s["time"][0]) + (self._h or 0.0)

    def weights(self, t: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(w (n, G) of the breaking generations, f_r (n,) of the reforming one) at time t
        (default: the step's end, or the accepted time between steps)."""
        t = self._time() if t is None else t
        return gen.weights(self._s, self.relaxation, self.kinetics, t)

    def accept_step(self, F: np.ndarray) -> None:
        """The step converged at ``F``: FEBio's new generation where the strain from U_r
        exceeds the trigger threshold and the reforming mass is at least wmin, then its
        culling; the time moves on (and a damaged strong bond's history)."""
        self._need_state("accept_step")
        if self._h is None:
            raise MaterialError(f"{self.name}: accept_step without begin_step")
        F = check_input(np.asarray(F, dtype=float), 1)
        s, t = self._s, self._time()
        _, fr = self.weights(t)
        Fu = F @ np.linalg.inv(s["ur"])
        new = np.flatnonzero((self._trigger(Fu) > max(self.emin, _EPS)) & (fr >= self.wmin))
        x = self.scalar_strain(F)
        wv = None if self.recruitment is None else self.recruitment(x[new])
        gen.push(s, new, gen.right_stretch(F[new]), t, fr[new], wv)
        gen.cull(s, new, self.relaxation, self.kinetics, t, self.wmin)
        s["time"] = np.array([t])
        s["et"] = x
        self._h = self._x_lag = None
        if hasattr(self.elastic, "accept_step"):
            self.elastic.accept_step(F)

    @property
    def lagged(self) -> bool:
        """Whether a step lags something (the forming bonds' recruitment) to re-lag."""
        return self.recruitment is not None

    def lag_moved(self, F: np.ndarray) -> float:
        """How far the forming bonds' brf at F is from the lagged one (0: settled)."""
        if not self.lagged or self._x_lag is None:
            return 0.0
        x = self.scalar_strain(check_input(np.asarray(F, dtype=float), 1))
        return float(np.max(np.abs(self.recruitment(x) - self.recruitment(self._x_lag)),
                            initial=0.0))  # fmt: skip

    def relag(self, F: np.ndarray, tolerance: float) -> bool:
        """Re-lag the forming bonds' strain at the step's converged F; whether their brf
        moved by more than ``tolerance`` anywhere."""
        if not self.lagged or self._x_lag is None:
            return False
        x = self.scalar_strain(check_input(np.asarray(F, dtype=float), 1))
        moved = np.max(np.abs(self.recruitment(x) - self.recruitment(self._x_lag)), initial=0.0)
        self._x_lag = x
        return bool(moved > tolerance)

    def lag_derivatives(self, F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(dP/dX_lag, dX/dF), each (q, d, d), at F in the step: how the stress moves with
        the forming bonds' lagged strain (f_r brf'(X_lag) P_b(F U_r^-1) U_r^-1 where they
        form), and how the strain that re-lags it moves with F. Their product is the lag's
        share of the step's derivative at FEBio's fixed point (the sensitivities':
        ``Model.lag_coupling``). brf' and dX/dF by central differences (brf is a user's curve
        with kinks; |dev ln V| has no simple closed derivative)."""
        self._need_state("lag_derivatives")
        F = check_input(np.asarray(F, dtype=float), 1)
        s, d = self._s, F.shape[-1]
        _, fr = self.weights()
        ur_inv = np.linalg.inv(s["ur"])
        trig = self._trigger(F @ ur_inv) > max(self.emin, _EPS)
        x = s["et"] if self._x_lag is None else self._x_lag
        e = 1e-7 * np.maximum(np.abs(x), 1e-3)
        dbrf = (self.recruitment(x + e) - self.recruitment(x - e)) / (2.0 * e)
        coef = np.where(trig & (fr >= self.wmin), fr * dbrf, 0.0)
        if isinstance(self.elastic, ElasticDamage):
            coef = coef * (1.0 - self.elastic.damage)
        Fr = F @ ur_inv
        dP = coef[:, None, None] * (self._weak(Fr, 1).stress @ ur_inv)
        dX = np.zeros_like(F)
        step = 1e-7
        for i in range(d):
            for j in range(d):
                Fp, Fm = F.copy(), F.copy()
                Fp[:, i, j] += step
                Fm[:, i, j] -= step
                dX[:, i, j] = (self.scalar_strain(Fp) - self.scalar_strain(Fm)) / (2 * step)
        return dP, dX

    def scalar_strain(self, F: np.ndarray) -> np.ndarray:
        """FEBio's ``ScalarStrain`` of the total F (the recruitment's argument): |E|,
        |dev ln V| or |ln J| for trigger 0, 1, 2."""
        if self.trigger == 1:
            return gen.dev_log_norm(gen.right_stretch(F))
        return self._trigger(F)

    def _trigger(self, Fu: np.ndarray) -> np.ndarray:
        if self.trigger == 0:
            E = 0.5 * (np.swapaxes(Fu, -1, -2) @ Fu - np.eye(Fu.shape[-1]))
            return np.sqrt(np.einsum("...ij,...ij->...", E, E))
        if self.trigger == 1:
            return gen.dev_log_norm(gen.right_stretch(Fu))  # |dev ln V| = |dev ln U|
        return np.abs(np.log(np.linalg.det(Fu)))

    # -- the law --------------------------------------------------------------------------
    def _strong(self, F: np.ndarray, order: int) -> MaterialResponse:
        return self.elastic.evaluate(F, order)

    def _weak(self, F: np.ndarray, order: int) -> MaterialResponse:
        return self.bond.evaluate(F, order)

    def _rest(self, F: np.ndarray, order: int) -> MaterialResponse | None:
        return None

    def evaluate(self, F: np.ndarray, order: int = 2) -> MaterialResponse:
        """psi_s + sum_k w_k psi_b(F U_k^-1) + f_r psi_b(F U_r^-1) (+ U(J) uncoupled), its P
        and dP/dF; unbound or at other points: the strong and weak bonds intact."""
        F = check_input(F, order)
        q, d = F.shape[0], F.shape[-1]
        strong = self._strong(F, order)
        rest = self._rest(F, order)
        if self.bound and q == self._n:
            s = self._s
            w, fr = self.weights()
            ur_inv = np.linalg.inv(s["ur"])
            # the reforming bonds: FEBio's original bonds before any generation, later a
            # generation only where the strain from U_r passes the trigger threshold (and
            # their mass is at least wmin)
            trig = self._trigger(F @ ur_inv) > max(self.emin, _EPS)
            formed = (s["count"] == 0) | (trig & (fr >= self.wmin))
            uinv = np.concatenate([s["uinv"], ur_inv[:, None]], axis=1)
            forming = np.where(formed, fr, 0.0)
            if self.recruitment is not None:  # each generation by its brf; the forming one's
                w = w * s["wv"]  # at the lagged strain, once it forms (FEBio's m_wv)
                x = s["et"] if self._x_lag is None else self._x_lag
                forming = np.where(trig, forming * self.recruitment(x), forming)
            w = np.concatenate([w, forming[:, None]], axis=1)
            if isinstance(self.elastic, ElasticDamage):  # FEBio's (1 - D) on the weak bonds
                w = w * (1.0 - self.elastic.damage)[:, None]
        else:
            uinv = np.broadcast_to(np.eye(d), (q, 1, d, d))
            w = np.ones((q, 1))
        G = w.shape[1]
        Fr = np.einsum("qij,qgjk->qgik", F, uinv).reshape(q * G, d, d)
        active = (np.abs(w) > 1e-15).ravel()  # fractions of the bonds: lighter add nothing
        weak = self._weak(Fr[active], order) if active.any() else None
        psi_b = np.zeros(q * G)
        if weak is not None:
            psi_b[active] = weak.energy
        with np.errstate(invalid="ignore"):
            psi = strong.energy + np.sum((w.ravel() * np.where(active, psi_b, 0.0)).reshape(q, G),
                                         axis=1)  # fmt: skip
        if rest is not None:
            psi = psi + rest.energy
        if order == 0:
            return MaterialResponse(psi)
        Pb = np.zeros((q * G, d, d))
        if weak is not None:
            Pb[active] = weak.stress
        Pb = Pb.reshape(q, G, d, d) * w[..., None, None]
        P = strong.stress + np.einsum("qgip,qgpj->qij", Pb, uinv)
        if rest is not None:
            P = P + rest.stress
        if order == 1:
            return MaterialResponse(psi, P)
        Ab = np.zeros((q * G, d, d, d, d))
        if weak is not None:
            Ab[active] = weak.tangent
        Ab = Ab.reshape(q, G, d, d, d, d) * w[..., None, None, None, None]
        A = strong.tangent + np.einsum("qgipkr,qgpj,qglr->qijkl", Ab, uinv, uinv)
        if rest is not None:
            A = A + rest.tangent
        return MaterialResponse(psi, P, A)


def _deviatoric(law: Material, F: np.ndarray, order: int) -> MaterialResponse:
    """An uncoupled law less its own bulk term."""
    full = law.evaluate(F, order)
    k0 = float(getattr(law, "k", 0.0) or 0.0)
    if k0 == 0.0:
        return full
    bulk = bulk_response(law.name, getattr(law, "bulk_kind", "log"), k0, F, order)
    with np.errstate(invalid="ignore"):
        psi = np.where(np.isfinite(full.energy), full.energy - bulk.energy, math.inf)
    if order == 0:
        return MaterialResponse(psi)
    if order == 1:
        return MaterialResponse(psi, full.stress - bulk.stress)
    return MaterialResponse(psi, full.stress - bulk.stress, full.tangent - bulk.tangent)


class UncoupledReactiveViscoelastic(ReactiveViscoelastic):
    """FEBio's ``uncoupled reactive viscoelastic``: the deviatoric parts of uncoupled
    ``elastic`` and ``bond`` laws (their own k unused) and the wrapper's bulk term (``k``,
    ``pressure_model``)."""

    name = "uncoupled_reactive_viscoelastic"
    febio_name = "uncoupled reactive viscoelastic"
    uncoupled = True

    def __init__(
        self,
        elastic: Material | None = None,
        *,
        k: float = 0.0,
        pressure_model: str | int = "default",
        **kwargs: object,
    ) -> None:
        super().__init__(elastic, **kwargs)  # type: ignore[arg-type]
        self.k = parameter(self.name, "k", k, meaning="bulk modulus")
        if self.k < 0.0:
            raise MaterialError(f"{self.name}: k (bulk modulus) must be >= 0 Pa, got {self.k!r}")
        self.bulk_kind = pressure_model_kind(self.name, pressure_model)
        self.lam = self.k - 2.0 * self.mu / 3.0

    def _check_part(self, key: str, part: Material) -> None:
        from tissuesim.materials.soft_tissue.ogden import Ogden

        if not (isinstance(part, Ogden) or getattr(part, "uncoupled", False) is True):
            raise MaterialError(f"{self.name} needs an uncoupled {key} law (mooney_rivlin, "
                                f"ogden, ...), not {getattr(part, 'name', '?')}")  # fmt: skip

    def _strong(self, F: np.ndarray, order: int) -> MaterialResponse:
        return _deviatoric(self.elastic, F, order)

    def _weak(self, F: np.ndarray, order: int) -> MaterialResponse:
        return _deviatoric(self.bond, F, order)

    def _rest(self, F: np.ndarray, order: int) -> MaterialResponse | None:
        if self.k == 0.0:
            return None
        return bulk_response(self.name, self.bulk_kind, self.k, F, order)


#: the wrappers by name (``make_material`` builds ``elastic`` and ``bond`` from tables)
REACTIVE_VISCOELASTIC_LAWS: dict[str, type[ReactiveViscoelastic]] = {
    ReactiveViscoelastic.name: ReactiveViscoelastic,
    UncoupledReactiveViscoelastic.name: UncoupledReactiveViscoelastic,
}
