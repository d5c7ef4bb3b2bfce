"""The collection of every family's problems (``run``) and the table ``tissuesim verify``
prints (``table``)."""

from __future__ import annotations

from collections.abc import Callable

from tissuesim.verification.result import Check

__all__ = ["FAMILIES", "run", "table"]


def _families() -> dict[str, Callable[[], list[Check]]]:
    from tissuesim.verification import (
        cook,
        damage,
        dynamics,
        fibres,
        hertz,
        laws,
        patch,
        reactive_viscoelastic,
        viscoelastic,
    )

    return {
        "laws": laws.checks,
        "fibres": fibres.checks,
        "patch": patch.checks,
        "viscoelastic": viscoelastic.checks,
        "reactive": lambda: reactive_viscoelastic.checks() + damage.checks(),
        "dynamics": dynamics.checks,
        "cook": cook.checks,
        "hertz": hertz.checks,
    }


#: the families by name, in the order they run
FAMILIES = (
    "laws", "fibres", "patch", "viscoelastic", "reactive", "dynamics", "cook", "hertz",
)  # fmt: skip


def run(families: tuple[str, ...] | None = None) -> list[Check]:
    """Run the verification problems of ``families`` (default: all) and return their checks."""
    found = _families()
    out: list[Check] = []
    for name in families or FAMILIES:
        out.extend(found[name]())
    return out


def _tolerance(value: float) -> str:
    """1e-08 style, with one decimal where that is not exact (1.5e-01)."""
    text = f"{value:.0e}"
    return text if float(text) == value else f"{value:.1e}"


def table(checks: list[Check]) -> str:
    """The checks as a text table: problem, quantity, reference, result, error, tolerance,
    pass; a last line counts the passes."""
    head = ("problem", "quantity", "reference", "result", "error", "tolerance", "pass")
    rows = [
        (
            c.problem,
            c.quantity,
            f"{c.reference:.6g}",
            f"{c.result:.6g}",
            f"{c.error:.1e}",
            _tolerance(c.tolerance),
            "yes" if c.passed else "NO",
        )
        for c in checks
    ]
    widths = [max(len(r[i]) for r in [head, *rows]) for i in range(len(head))]
    lines = ["  ".join(v.ljust(w) for v, w in zip(r, widths, strict=True)).rstrip()
             for r in [head, *rows]]  # fmt: skip
    lines.insert(1, "  ".join("-" * w for w in widths))
    passed = sum(c.passed for c in checks)
    lines.append(f"{passed} of {len(checks)} checks pass")
    return "\n".join(lines)
