"""FEBio's ``multigeneration`` (``FEElasticMultigeneration``): generations of elastic laws, each
born at its ``start_time`` with the body's shape then as its reference. FEBio's Cauchy stress is
the sum over the generations born so far of their laws at Fe_i = F F_i^-1 (F_i the deformation
gradient when generation i was born, F_0 = I); per unit reference volume that is

    W = sum_i J_i W_i(F G_i)      P = sum_i J_i P_i(F G_i) G_i^T      G_i = F_i^-1, J_i = det F_i

and the tangent J_i A_i,imkn G_i,jm G_i,ln. As FEBio's ``FEMultigenerationMaterialPoint::
Update`` does at the start of each step: with t the step's end time, the generation whose
start_time is the last <= t is the newest; when its start_time is later than the newest born,
the next generation is born, with F the state the step starts from (one generation a step). The
law keeps the time, the count born, their references and the last accepted F per integration
point (``bind``); a rejected step begins again from the accepted state.
"""

from __future__ import annotations

import copy

import numpy as np

from tissuesim.errors import MaterialError
from tissuesim.materials.base import Material, MaterialResponse
from tissuesim.materials.isotropic._common import check_input
from tissuesim.validate import short

__all__ = ["Multigeneration"]


class Multigeneration(Material):
    """FEBio's multigeneration: ``generations``, a list of {"start_time": s, "solid": law}
    (the first at 0, start times increasing)."""

    name = "multigeneration"

    def __init__(self, *, generations: object = None) -> None:
        law = self.name
        if not isinstance(generations, (list, tuple)) or not generations:
            raise MaterialError(f"{law}: generations must be a list of {{start_time, solid}}, "
                                f"not {short(generations)}")  # fmt: skip
        times, solids = [], []
        for i, g in enumerate(generations):
            if not isinstance(g, dict) or set(g) - {"start_time", "solid"} or "solid" not in g:
                raise MaterialError(f"{law}: generations[{i}] takes start_time and solid")
            solid = g["solid"]
            if not isinstance(solid, Material) or hasattr(solid, "begin_step"):
                raise MaterialError(f"{law}: generations[{i}]: solid must be an elastic law")
            times.append(float(g.get("start_time", 0.0)))
            solids.append(solid)
        if times[0] != 0.0 or any(b <= a for a, b in zip(times, times[1:], strict=False)):
            raise MaterialError(f"{law}: the first generation starts at 0 and the start times "
                                f"increase, got {times}")  # fmt: skip
        self.times, self.solids = times, solids
        self.mu, self.lam = solids[0].mu, solids[0].lam
        self.time = self._trial = 0.0
        self._born = 1  # generations born (the first always)
        self._tgen = 0.0  # the newest born's start time
        self._F = None  # (n, d, d) the last accepted F, once bound
        self._refs = None  # (N, n, d, d) G_i = F_i^-1 of each generation born
        self._step = None  # (born, tgen, refs) of the step in progress

    def __repr__(self) -> str:
        gens = [{"start_time": t, "solid": s} for t, s in zip(self.times, self.solids, strict=True)]
        return f"{type(self).__name__}(generations={gens!r})"

    def bind(self, n_points: int, dim: int, n_cells: int | None = None) -> Multigeneration:
        """A copy holding the state of ``n_points`` integration points, at rest."""
        out = copy.copy(self)
        out.solids = [s.bind(n_points, dim, n_cells) if hasattr(s, "bind") else s
                      for s in self.solids]  # fmt: skip
        out._F = np.broadcast_to(np.eye(dim), (n_points, dim, dim)).copy()
        out._refs = np.broadcast_to(np.eye(dim), (len(self.times), n_points, dim, dim)).copy()
        out._step = None
        return out

    def _need_state(self, what: str) -> None:
        if self._F is None:
            raise MaterialError(
                f"{self.name}: {what} needs the state of a body's integration points; it works "
                "on FEM bodies (their model binds it)"
            )

    def begin_step(self, h: float) -> None:
        """The step to t = time + h: FEBio's Update, from the accepted state."""
        self._need_state("begin_step")
        t = self.time + float(h)
        newest = max(i for i, s in enumerate(self.times) if s <= t)
        born, tgen, refs = self._born, self._tgen, self._refs
        if self.times[newest] > tgen and born < len(self.times):
            refs = refs.copy()
            refs[born] = np.linalg.inv(self._F)
            born, tgen = born + 1, self.times[newest]
        self._trial = t
        self._step = (born, tgen, refs)

    def accept_step(self, F: np.ndarray) -> None:
        """The step converged at ``F`` (n, d, d): its generations and F kept."""
        self._need_state("accept_step")
        if self._step is not None:
            self._born, self._tgen, self._refs = self._step
        self._F = np.array(F, dtype=float)
        self.time = self._trial
        self._step = None

    def state_arrays(self) -> dict[str, np.ndarray]:
        """The state between steps (for checkpoints)."""
        self._need_state("state_arrays")
        scalars = np.array([self.time, self._tgen, float(self._born)])
        return {"scalars": scalars, "F": self._F.copy(), "refs": self._refs.copy()}

    def set_state_arrays(self, arrays: dict[str, np.ndarray]) -> None:
        """Restore a state of ``state_arrays``."""
        self._need_state("set_state_arrays")
        F, refs = np.asarray(arrays["F"], float), np.asarray(arrays["refs"], float)
        if F.shape != self._F.shape or refs.shape != self._refs.shape:
            raise MaterialError(f"{self.name}: a saved state of shapes {F.shape}, {refs.shape} "
                                f"does not fit {self._F.shape}, {self._refs.shape}")  # fmt: skip
        self.time, self._tgen, born = (float(v) for v in arrays["scalars"])
        self._trial, self._born = self.time, int(born)
        self._F, self._refs, self._step = F.copy(), refs.copy(), None

    def evaluate(self, F: np.ndarray, order: int = 2) -> MaterialResponse:
        F = check_input(F, order)
        q, d = F.shape[0], F.shape[-1]
        born, _, refs = self._step if self._step is not None else (self._born, 0, self._refs)
        psi = np.zeros(q)
        P = np.zeros_like(F) if order > 0 else None
        A = np.zeros((q, d, d, d, d)) if order > 1 else None
        for i in range(born):
            G = np.broadcast_to(np.eye(d), (q, d, d)) if refs is None else refs[i]
            if G.shape[0] not in (1, q):
                raise MaterialError(f"{self.name} holds {G.shape[0]} points but was given {q} "
                                    "deformation gradients")  # fmt: skip
            G = np.broadcast_to(G, (q, d, d))  # one point's state: any batch of F there
            Ji = 1.0 / np.linalg.det(G)
            res = self.solids[i].evaluate(F @ G, order)
            psi = psi + Ji * res.energy
            if order > 0:
                P += Ji[:, None, None] * res.stress @ np.swapaxes(G, 1, 2)
            if order > 1:
                Ai = np.einsum("qimkn,qjm,qln->qijkl", res.tangent, G, G, optimize=True)
                A += Ji[:, None, None, None, None] * Ai
        return MaterialResponse(psi, P, A)
