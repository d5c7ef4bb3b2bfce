"""Material laws by name, as used in scene files: ``make_material("neo_hookean", ...)``."""

from __future__ import annotations

import difflib
import inspect

from tissuesim.errors import MaterialError
from tissuesim.materials.base import Material
from tissuesim.materials.corotated import FixedCorotated
from tissuesim.materials.course_neo_hookean import CourseNeoHookean
from tissuesim.materials.linear import LinearElastic
from tissuesim.materials.neo_hookean import NeoHookean
from tissuesim.materials.stvk import StVenantKirchhoff
from tissuesim.validate import short

__all__ = ["MATERIALS", "make_material"]

MATERIALS: dict[str, type[Material]] = {
    cls.name: cls
    for cls in (CourseNeoHookean, NeoHookean, StVenantKirchhoff, LinearElastic, FixedCorotated)
}


def _suggest(word: str, choices: list[str]) -> str:
    close = difflib.get_close_matches(word, choices, n=3, cutoff=0.5)
    hint = f"did you mean {' or '.join(repr(c) for c in close)}? " if close else ""
    return f"{hint}valid: {', '.join(sorted(choices))}"


def make_material(model: str, **params: float) -> Material:
    """Build the law registered as ``model`` with keyword parameters (e.g. E and nu)."""
    key = str(model).strip().lower().replace("-", "_").replace(" ", "_")
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
