"""FEBio's solid mixtures with components that keep a history per integration point (FEBio's
``elastic damage`` as a mixture's ``<solid>``, as in its damage verification models): the
mixture of ``mixture.py`` (W the sum of the components' energies) that also steps its
components' histories: ``begin_step`` / ``accept_step`` go to each such component, and its state
(``state_arrays``, for checkpoints) is theirs, keyed ``c<i>_<key>``. ``make_material`` builds
one when a component has a history (``registry.py``; a prescribed active contraction's is
its time, ``materials/active/``); the name stays ``solid_mixture`` /
``uncoupled_solid_mixture`` (the same law)."""

from __future__ import annotations

import copy
from collections.abc import Sequence

import numpy as np

from tissuesim.errors import MaterialError
from tissuesim.materials.mixture import SolidMixture, UncoupledSolidMixture
from tissuesim.materials.reactive.damage import ElasticDamage

__all__ = ["HistorySolidMixture", "HistoryUncoupledSolidMixture", "HISTORY_MIXTURES"]


class _History:
    """The stepping of the components with a history (a mixin on the two mixtures)."""

    components: list

    def _init(self, components: object, extra: dict) -> None:
        if isinstance(components, (str, bytes, dict)) or not isinstance(components, Sequence):
            super()._init(components, extra)  # its one-line refusal
            return
        parts = list(components)
        # the mixture's checks on the wrapped laws (a history is refused there), then back
        # (a prescribed active contraction, whose state is the time: its ``stand_in``)
        stand_ins = [
            p.elastic
            if isinstance(p, ElasticDamage)
            else (p.stand_in() if hasattr(p, "stand_in") else p)
            for p in parts
        ]
        super()._init(stand_ins, extra)
        for i, p in enumerate(parts):
            if hasattr(p, "stand_in"):
                self.components[i] = copy.copy(p)
            if isinstance(p, ElasticDamage):
                if self.uncoupled and not p.uncoupled:
                    raise MaterialError(
                        f"{self.name}: components[{i}] ({p.name}) is coupled; an uncoupled "
                        "mixture takes uncoupled_elastic_damage"
                    )
                p = copy.copy(p)
                if self.uncoupled:  # FEBio ignores a component's k
                    p.k = 0.0
                self.components[i] = p

    def _stateful(self) -> list[tuple[int, object]]:
        return [(i, p) for i, p in enumerate(self.components) if hasattr(p, "accept_step")]

    def begin_step(self, h: float) -> None:
        for _, p in self._stateful():
            p.begin_step(h)

    @property
    def lagged(self) -> bool:
        """Whether a component lags something in a step (``relag``)."""
        return any(getattr(p, "lagged", False) for _, p in self._stateful())

    def lag_moved(self, F: np.ndarray) -> float:
        return max((p.lag_moved(F) for _, p in self._stateful() if getattr(p, "lagged", False)),
                   default=0.0)  # fmt: skip

    def relag(self, F: np.ndarray, tolerance: float) -> bool:
        changed = False
        for _, p in self._stateful():
            if getattr(p, "lagged", False):
                changed = p.relag(F, tolerance) or changed
        return changed

    def accept_step(self, F: np.ndarray) -> None:
        for _, p in self._stateful():
            p.accept_step(F)

    def state_arrays(self) -> dict[str, np.ndarray]:
        return {f"c{i}_{k}": v for i, p in self._stateful() for k, v in p.state_arrays().items()}

    def set_state_arrays(self, arrays: dict[str, np.ndarray]) -> None:
        for i, p in self._stateful():
            head = f"c{i}_"
            mine = {k[len(head) :]: v for k, v in arrays.items() if k.startswith(head)}
            if not mine:
                raise MaterialError(f"{self.name}: no state for components[{i}] ({p.name})")
            p.set_state_arrays(mine)

    def bind(self, n_points: int, dim: int, n_cells: int | None = None):
        out = copy.copy(self)
        out.components = [
            p.bind(n_points, dim, n_cells) if hasattr(p, "bind") else p for p in self.components
        ]
        return out


class HistorySolidMixture(_History, SolidMixture):
    """``solid_mixture`` with components that keep a history (``elastic_damage``)."""


class HistoryUncoupledSolidMixture(_History, UncoupledSolidMixture):
    """``uncoupled_solid_mixture`` with components that keep a history
    (``uncoupled_elastic_damage``)."""


#: the mixture's name -> the class that steps its components' histories
HISTORY_MIXTURES = {
    SolidMixture.name: HistorySolidMixture,
    UncoupledSolidMixture.name: HistoryUncoupledSolidMixture,
}
