"""Material laws by name, as used in scene files: ``make_material("neo_hookean", ...)``.

The soft-tissue laws carry FEBio's names (its ``type`` with spaces and dashes as underscores):
``mooney_rivlin``, ``ogden``, ``yeoh``, ``veronda_westmann`` and ``arruda_boyce`` are FEBio's
uncoupled laws; ``coupled_mooney_rivlin``, ``coupled_veronda_westmann`` and
``ogden_unconstrained`` its coupled ones; ``coupled_yeoh`` and ``coupled_arruda_boyce`` are
tissuesim's coupled forms where FEBio has none. ``<law>_uncoupled`` and ``<law>_coupled`` are
accepted as aliases (``ALIASES``).
"""

from __future__ import annotations

import difflib
import inspect

from tissuesim.errors import MaterialError
from tissuesim.materials.arruda_boyce import ArrudaBoyce, CoupledArrudaBoyce
from tissuesim.materials.base import Material
from tissuesim.materials.corotated import FixedCorotated
from tissuesim.materials.course_neo_hookean import CourseNeoHookean
from tissuesim.materials.linear import LinearElastic
from tissuesim.materials.mooney_rivlin import CoupledMooneyRivlin, MooneyRivlin
from tissuesim.materials.neo_hookean import NeoHookean
from tissuesim.materials.ogden import Ogden, OgdenUnconstrained
from tissuesim.materials.stvk import StVenantKirchhoff
from tissuesim.materials.veronda_westmann import CoupledVerondaWestmann, VerondaWestmann
from tissuesim.materials.yeoh import CoupledYeoh, Yeoh
from tissuesim.validate import short

__all__ = ["MATERIALS", "ALIASES", "SOFT_TISSUE_LAWS", "make_material"]

#: the laws with their own parameters (FEBio's names), not (E, nu) or (mu, lambda)
SOFT_TISSUE_LAWS: tuple[type[Material], ...] = (
    MooneyRivlin,
    CoupledMooneyRivlin,
    Ogden,
    OgdenUnconstrained,
    Yeoh,
    CoupledYeoh,
    VerondaWestmann,
    CoupledVerondaWestmann,
    ArrudaBoyce,
    CoupledArrudaBoyce,
)

MATERIALS: dict[str, type[Material]] = {
    cls.name: cls
    for cls in (
        CourseNeoHookean,
        NeoHookean,
        StVenantKirchhoff,
        LinearElastic,
        FixedCorotated,
        *SOFT_TISSUE_LAWS,
    )
}

#: other spellings of the soft-tissue laws' names: "<law>_uncoupled", "<law>_coupled"
ALIASES: dict[str, str] = {
    **{f"{law}_uncoupled": law for law in ("mooney_rivlin", "yeoh", "veronda_westmann")},
    **{f"{law}_coupled": f"coupled_{law}" for law in ("mooney_rivlin", "yeoh", "veronda_westmann")},
    "arruda_boyce_uncoupled": "arruda_boyce",
    "arruda_boyce_coupled": "coupled_arruda_boyce",
    "ogden_uncoupled": "ogden",
    "ogden_coupled": "ogden_unconstrained",
}


def _suggest(word: str, choices: list[str]) -> str:
    close = difflib.get_close_matches(word, choices, n=3, cutoff=0.5)
    hint = f"did you mean {' or '.join(repr(c) for c in close)}? " if close else ""
    return f"{hint}valid: {', '.join(sorted(choices))}"


def make_material(model: str, **params: object) -> Material:
    """Build the law registered as ``model`` with keyword parameters (e.g. E and nu, or a
    soft-tissue law's own: ``make_material("ogden", c=[1e3], m=[8.0], k=1e5)``).

    FEBio's law names work as written there (``"Mooney-Rivlin"``, ``"Ogden unconstrained"``):
    case, spaces and dashes do not matter."""
    key = str(model).strip().lower().replace("-", "_").replace(" ", "_")
    key = ALIASES.get(key, key)
    if key not in MATERIALS:
        raise MaterialError(
            f"unknown material model {short(model)}; {_suggest(key, list(MATERIALS))}"
        )
    cls = MATERIALS[key]
    sig = inspect.signature(cls.__init__).parameters
    allowed = [n for n, p in sig.items() if p.kind is inspect.Parameter.KEYWORD_ONLY]
    for name in params:
        if name not in allowed:
            raise MaterialError(
                f"unknown parameter {short(name)} for material {key!r}; {_suggest(name, allowed)}"
            )
    return cls(**params)
