"""FEBio's solid mixtures: ``solid mixture`` and ``uncoupled solid mixture`` (FEBio User
Manual, "Solid Mixture", "Uncoupled Solid Mixture"; ``FEElasticMixture.cpp``,
``FEUncoupledElasticMixture.cpp``). A mixture's energy is the sum of its components' energies,
so its stress and tangent are the sums of theirs:

    solid_mixture              W = sum_i W_i(F)
    uncoupled_solid_mixture    W = sum_i W_dev,i(F) + U(J)

Components are any elastic laws (materials; ``make_material`` also takes tables
``{ model = ..., ... }``, ``registry.py``): a matrix (``neo_hookean``, ``mooney_rivlin``, ...)
and fibres (``fiber_exp_pow``, ``fiber_pow_linear``, ``holzapfel_gasser_ogden``, ...), each with
its own directions. As in FEBio, a mixture is not a component of a mixture, and the uncoupled
mixture takes uncoupled components whose bulk terms are left out: its own ``k`` (Pa) and
``pressure_model`` (as every uncoupled law's, ``_hyperelastic.bulk_energy``) give U(J), and a
component's ``k`` is ignored (FEBio warns and sets it to 0), so it need not be given.
Visco-elastic components are refused (their history is the body's, not a component's).

``.mu`` and ``.lam`` are the sums of the components' (uncoupled: lam = k - 2 mu / 3); a mixture
needs a component with a shear modulus (the fibres have none: slack at rest).
"""

from __future__ import annotations

import copy
import math
from collections.abc import Sequence

import numpy as np

from tissuesim.errors import MaterialError
from tissuesim.materials.base import Material, MaterialResponse
from tissuesim.materials.isotropic._common import (
    check_input,
)
from tissuesim.materials.soft_tissue._hyperelastic import (
    BULK_KINDS,
    PRESSURE_MODELS,
    HyperelasticMaterial,
    bulk_response,
    parameter,
    pressure_model,
)
from tissuesim.validate import short

__all__ = ["SolidMixture", "UncoupledSolidMixture", "MIXTURES"]


class SolidMixture(Material):
    """FEBio's ``solid mixture``: W = sum of the components' energies (any elastic laws).

    ``SolidMixture([NeoHookean(youngs_modulus=1e3, poisson_ratio=0.3),
    FiberExpPow(ksi=50.0, alpha=2.0, beta=2.0, fiber=[1, 0, 0])])``"""

    name = "solid_mixture"
    febio_name = "solid mixture"
    uncoupled = False

    def __init__(self, components: Sequence | None = None, **kwargs: object) -> None:
        self._init(components, kwargs)

    def _init(self, components: object, extra: dict) -> None:
        law = self.name
        if extra:
            raise MaterialError(
                f"unknown parameter {short(next(iter(extra)))} for material {law!r}; "
                "it takes components" + (", k, pressure_model" if self.uncoupled else "")
            )
        if isinstance(components, (str, bytes, dict)) or not isinstance(components, Sequence):
            raise MaterialError(
                f"{law} needs components: a list of materials or tables with their model, "
                f"not {short(components)}"
            )
        if not components:
            raise MaterialError(f"{law} needs at least one component")
        parts = list(components)
        for i, part in enumerate(parts):
            if not isinstance(part, Material):
                raise MaterialError(
                    f"{law}: components[{i}] must be a material, not {short(part)} (tables "
                    "with their model: make_material)"
                )
            if isinstance(part, SolidMixture):
                raise MaterialError(f"{law}: components[{i}] is a mixture; FEBio allows none")
            if hasattr(part, "begin_step"):
                raise MaterialError(
                    f"{law}: components[{i}] ({part.name}) is visco-elastic; wrap the whole "
                    "mixture in viscoelastic instead"
                )
            if self.uncoupled and getattr(part, "uncoupled", None) is not True:
                from tissuesim.materials.soft_tissue.ogden import Ogden

                if not isinstance(part, Ogden):
                    raise MaterialError(
                        f"{law}: components[{i}] ({part.name}) is not an uncoupled law; an "
                        "uncoupled mixture takes mooney_rivlin, ogden, fiber_exp_pow_uncoupled, "
                        "... (solid_mixture takes the coupled ones)"
                    )
        if self.uncoupled:  # the components' deviatoric parts: FEBio ignores their k
            parts = [copy.copy(p) for p in parts]
            for p in parts:
                p.k = 0.0
        self.components: list[Material] = parts
        self.mu = float(sum(p.mu for p in parts))
        self.lam = float(sum(p.lam for p in parts))
        if not (self.mu > 0.0 and math.isfinite(self.mu)):
            raise MaterialError(
                f"{law}: the components give a small-strain shear modulus mu = {self.mu!r} Pa; "
                "it must be > 0 (add a matrix: fibres are slack at rest)"
            )

    def __repr__(self) -> str:
        parts = ", ".join(repr(p) for p in self.components)
        return f"{type(self).__name__}([{parts}]{self._repr_tail()})"

    def _repr_tail(self) -> str:
        return ""

    def bind(self, n_points: int, dim: int, n_cells: int | None = None) -> SolidMixture:
        """This mixture with its components' per-element directions expanded to the body's
        integration points (``FibreLaw.bind``); itself when no component needs it."""
        bound = [
            p.bind(n_points, dim, n_cells) if hasattr(p, "bind") else p for p in self.components
        ]
        if all(b is p for b, p in zip(bound, self.components, strict=True)):
            return self
        out = copy.copy(self)
        out.components = bound
        return out

    def _bulk(self, F: np.ndarray, order: int) -> MaterialResponse | None:
        return None

    def evaluate(self, F: np.ndarray, order: int = 2) -> MaterialResponse:
        F = check_input(F, order)
        parts = [p.evaluate(F, order) for p in self.components]
        bulk = self._bulk(F, order)
        if bulk is not None:
            parts.append(bulk)
        psi = np.sum([r.energy for r in parts], axis=0)
        if order == 0:
            return MaterialResponse(psi)
        P = np.sum([r.stress for r in parts], axis=0)
        if order == 1:
            return MaterialResponse(psi, P)
        return MaterialResponse(psi, P, np.sum([r.tangent for r in parts], axis=0))


class UncoupledSolidMixture(SolidMixture, HyperelasticMaterial):
    """FEBio's ``uncoupled solid mixture``: the uncoupled components' deviatoric energies plus
    the mixture's own bulk term U(J) with ``k`` (Pa) and ``pressure_model``."""

    name = "uncoupled_solid_mixture"
    febio_name = "uncoupled solid mixture"
    uncoupled = True

    def __init__(
        self,
        components: Sequence | None = None,
        *,
        k: float | None = None,
        pressure_model: str | int = "default",
        **kwargs: object,
    ) -> None:
        self.k = parameter(self.name, "k", k, positive=True, meaning="bulk modulus")
        self.bulk_kind = _pressure(self.name, pressure_model)
        self._init(components, kwargs)
        self.lam = self.k - 2.0 * self.mu / 3.0

    def parameters(self) -> dict[str, object]:
        return {"k": self.k, **self._bulk_parameter()}

    def _repr_tail(self) -> str:
        tail = f", k={self.k!r}"
        if self.bulk_kind != "log":
            tail += f", pressure_model={PRESSURE_MODELS[BULK_KINDS.index(self.bulk_kind, 1)]!r}"
        return tail

    def _bulk(self, F: np.ndarray, order: int) -> MaterialResponse:
        return bulk_response(self.name, self.bulk_kind, self.k, F, order)


def _pressure(law: str, value: object) -> str:
    return pressure_model(law, value)


#: the mixtures by name
MIXTURES: dict[str, type[SolidMixture]] = {
    SolidMixture.name: SolidMixture,
    UncoupledSolidMixture.name: UncoupledSolidMixture,
}
