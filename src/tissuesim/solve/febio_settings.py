"""The settings of FEBio's quasi-Newton solver (``NewtonOptions(method="febio")``,
solve/quasin.py): FEBio's <solver> keys with FEBio's defaults (``FESolidSolver2``,
``FENewtonSolver``, ``BFGSSolver``, ``FELineSearch``)."""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Literal

from tissuesim.errors import InputError

__all__ = ["FebioSettings", "febio_settings"]

QnMethod = Literal["BFGS", "Broyden", "full Newton"]


@dataclass(frozen=True)
class FebioSettings:
    """FEBio's <solver> settings of ``FESolidSolver2`` (FEBio's defaults)."""

    dtol: float = 1e-3
    etol: float = 1e-2
    rtol: float = 0.0
    min_residual: float = 1e-20
    max_residual: float = 0.0  # 0: not checked
    lstol: float = 0.9  # 0: no line search (s = 1)
    lsmin: float = 0.01
    lsiter: int = 5
    qn_method: QnMethod = "BFGS"
    max_ups: int = 10  # 0: full Newton
    max_refs: int = 15
    cmax: float = 1e5
    diverge_reform: bool = True
    reform_each_time_step: bool = True
    reform_augment: bool = False

    def __post_init__(self) -> None:
        from tissuesim import validate

        for key in ("dtol", "etol", "rtol", "min_residual", "max_residual", "lstol", "lsmin"):
            validate.real(getattr(self, key), f"febio.{key}", low=0.0)
        validate.real(self.cmax, "febio.cmax", low=0.0, low_open=True)
        validate.integer(self.lsiter, "febio.lsiter", low=0, high=1000)
        validate.integer(self.max_ups, "febio.max_ups", low=0, high=10_000)
        validate.integer(self.max_refs, "febio.max_refs", low=1, high=10_000)
        validate.choice(self.qn_method, "febio.qn_method", ("BFGS", "Broyden", "full Newton"))
        for key in ("diverge_reform", "reform_each_time_step", "reform_augment"):
            if not isinstance(getattr(self, key), bool):
                raise InputError(f"febio.{key} must be true or false")
        if self.dtol == 0.0 and self.etol == 0.0 and self.rtol == 0.0:
            raise InputError("febio: dtol, etol and rtol are all 0: nothing would stop a step")

    @classmethod
    def from_table(cls, table: dict) -> FebioSettings:
        """From a ``[newton.febio]`` table; an unknown key is refused in one line."""
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(table) - known)
        if unknown:
            raise InputError(f"febio: unknown setting {unknown[0]!r}; known: {sorted(known)}")
        return cls(**table)

    @property
    def max_updates(self) -> int:
        """The quasi-Newton updates allowed between reformations plus one (0: full Newton)."""
        return 0 if self.qn_method == "full Newton" else self.max_ups


def febio_settings(method: str, settings) -> FebioSettings:
    """``NewtonOptions.febio`` checked: a FebioSettings from None (FEBio's defaults), a table
    or a FebioSettings, for ``method`` "febio" only (one-line InputError otherwise)."""
    from tissuesim import validate

    if method != "febio":
        raise InputError("febio settings are used by method = 'febio' only: set it")
    if settings is None:
        return FebioSettings()
    if isinstance(settings, dict):
        return FebioSettings.from_table(settings)
    if not isinstance(settings, FebioSettings):
        given = validate.short(settings)
        raise InputError(f"febio must be a table of FEBio's solver settings, not {given}")
    return settings
