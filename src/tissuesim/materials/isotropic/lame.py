"""Lame parameters (mu, lambda) from exactly one pair of elastic constants.

    mu = E / (2 (1 + nu)),    lambda = E nu / ((1 + nu) (1 - 2 nu))

Valid ranges: E > 0, -1 < nu < 0.5, mu > 0 and a positive 3D bulk modulus lambda + 2 mu / 3 > 0.
"""

from __future__ import annotations

from tissuesim.errors import InputError, MaterialError
from tissuesim.validate import real, short

__all__ = ["lame_parameters"]

_PAIRS = "(youngs_modulus, poisson_ratio) or (shear_modulus, lame_lambda)"


def _finite(key: str, value: object) -> float:
    """A finite real number (not a bool, not a numeric string), via the shared validator."""
    try:
        return real(value, key, unit="Pa" if key != "poisson_ratio" else "")
    except InputError as exc:
        raise MaterialError(str(exc)) from None


def lame_parameters(
    *,
    youngs_modulus: float | None = None,
    poisson_ratio: float | None = None,
    shear_modulus: float | None = None,
    lame_lambda: float | None = None,
) -> tuple[float, float]:
    """Return ``(mu, lam)`` in Pa from (E, nu) or from (mu, lambda); exactly one pair."""
    given = {
        k: v
        for k, v in dict(
            youngs_modulus=youngs_modulus,
            poisson_ratio=poisson_ratio,
            shear_modulus=shear_modulus,
            lame_lambda=lame_lambda,
        ).items()
        if v is not None
    }
    keys = set(given)
    if keys == {"youngs_modulus", "poisson_ratio"}:
        E = _finite("youngs_modulus", youngs_modulus)
        nu = _finite("poisson_ratio", poisson_ratio)
        if E <= 0.0:
            raise MaterialError(f"youngs_modulus must be > 0 Pa, got {short(E)}")
        if not -1.0 < nu < 0.5:
            raise MaterialError(
                f"poisson_ratio must satisfy -1 < poisson_ratio < 0.5, got {short(nu)} "
                "(0.5 is incompressible, which these compressible laws cannot represent)"
            )
        return E / (2.0 * (1.0 + nu)), E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))
    if keys == {"shear_modulus", "lame_lambda"}:
        mu = _finite("shear_modulus", shear_modulus)
        lam = _finite("lame_lambda", lame_lambda)
        if mu <= 0.0:
            raise MaterialError(f"shear_modulus must be > 0 Pa, got {short(mu)}")
        if lam + 2.0 * mu / 3.0 <= 0.0:
            raise MaterialError(
                f"lame_lambda must be > -2/3 shear_modulus = {-2.0 * mu / 3.0!r} Pa "
                f"(positive bulk modulus), got {short(lam)}"
            )
        return mu, lam
    got = ", ".join(sorted(keys)) or "nothing"
    raise MaterialError(f"give exactly one pair of elastic constants: {_PAIRS}; got {got}")
