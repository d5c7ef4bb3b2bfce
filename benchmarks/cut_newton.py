"""Does a cut make the steps after it harder? Newton iterations per step of a run that cuts,
against the same run without the cut, step for step (like for like: the same scene, the same
steps, only the cut differs).

1. The shipped ``liver_resection`` example (and ``liver_wedge_resection``) over its cutting
   phase (t = 0.1 .. 0.24 s, before the lobe comes off and falls, which changes the motion
   itself): with the blade, and with the ``[[cuts]]`` table removed; and ``liver_instrument``
   over the same phase, the scalpel in contact with the liver against the same scalpel passing
   through it (``contact = false``); and, to see what the cut's small parts cost, the scalpel
   in contact with every element part's fraction raised to 5 % of its cell (no sliver).
2. The shipped ``strip_tearing`` (quasistatic): the steps from the tear on, torn against
   not torn (without ``[tearing]``), and torn with every element part raised to 5 %.
3. The organ of ``benchmarks/cut_cost.py`` (12 divisions: 10,368 tetrahedra; ellipsoid under
   gravity, Backward Euler) cut at step 4 by planes at several positions, chosen to pass close
   to nodes (copies of fractions down to 1e-7: the slivers a cut can make), then 8 more steps.

Per run: the mean and largest Newton iterations per step over the compared steps, and the
ratio of the means (cut / uncut). Also the explicit stability limit before and after the cut is
in ``benchmarks/explicit_limit.py``.

    python3 benchmarks/cut_newton.py      # writes benchmarks/results/cut_newton.md
"""

from __future__ import annotations

import tomllib
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from tissuesim.mesh.cutting.virtual_nodes import PlanarCut
from tissuesim.scene.loader import build_scene

HERE = Path(__file__).resolve().parent
EXAMPLES = HERE.parent / "src" / "tissuesim" / "examples"


def liver(cut: bool, steps: int = 24, name: str = "liver_resection") -> list[int]:
    """Newton iterations of each of the example's first ``steps`` steps."""
    path = EXAMPLES / f"{name}.toml"
    data = tomllib.loads(path.read_text())
    if not cut:
        del data["cuts"]
    sim = build_scene(data, base_dir=path.parent, source=str(path)).simulation
    return [sim.step().newton_iterations for _ in range(steps)]


def liver_instrument(contact: bool, steps: int = 24) -> list[int]:
    """Newton iterations of the first ``steps`` steps of the shipped ``liver_instrument``: the
    scalpel in contact with the liver, or passing through it (``contact = false``)."""
    path = EXAMPLES / "liver_instrument.toml"
    data = tomllib.loads(path.read_text())
    data["cuts"][0]["contact"] = contact
    sim = build_scene(data, base_dir=path.parent, source=str(path)).simulation
    return [sim.step().newton_iterations for _ in range(steps)]


def strip_tearing(tear: bool, steps: int = 100) -> tuple[list[int], int]:
    """Newton iterations of the shipped ``strip_tearing`` (quasistatic), with its ``[tearing]``
    table or without, and the first step whose report has two pieces (-1: none)."""
    path = EXAMPLES / "strip_tearing.toml"
    data = tomllib.loads(path.read_text())
    if not tear:
        del data["tearing"]
    sim = build_scene(data, base_dir=path.parent, source=str(path)).simulation
    its, parted = [], -1
    for k in range(steps):
        record = sim.step()
        its.append(record.newton_iterations)
        pieces = [c.get("pieces", 1) for c in record.extra.get("cuts", {}).values()]
        if parted < 0 and max(pieces, default=1) > 1:
            parted = k
    return its, parted


@contextmanager
def raised_fractions(floor: float = 0.05):
    """Within: every element part's volume fraction raised to at least ``floor`` of its cell,
    so a cut makes no sliver anywhere: a like-for-like of what the cut's small parts cost. A
    diagnostic only: the mass and stiffness are not kept."""
    import tissuesim.mesh.cutting.virtual_nodes as virtual_nodes

    copies = virtual_nodes._copies

    def raised(*args):
        parent, side, cut, fraction, extra = copies(*args)
        return parent, side, cut, np.maximum(fraction, floor), extra

    virtual_nodes._copies = raised
    try:
        yield
    finally:
        virtual_nodes._copies = copies


def organ_run(x: float | None, before: int = 4, after: int = 8) -> tuple[list[int], float]:
    """Newton iterations of the steps after step ``before``, cut there at x (None: no cut),
    and the smallest copy fraction the cut made."""
    import sys

    sys.path.insert(0, str(HERE))
    from cut_cost import organ

    sim = organ(12)
    for _ in range(before):
        sim.step()
    smallest = 1.0
    if x is not None:
        blade = PlanarCut(
            np.array([x, 0.0, 0.0]),
            np.array([1.0, 0.0, 0.0]),
            np.array([[x, -1, -1], [x, 1, -1], [x, 1, 1], [x, -1, 1]], dtype=float),
        )
        sim.cut_body(blade, body="organ")
        fractions = sim.bodies["organ"].mesh.cell_fractions
        smallest = float(fractions.min())
    return [sim.step().newton_iterations for _ in range(after)], smallest


def emit(lines: list[str], line: str) -> None:
    """Add a table row to ``lines`` and show it at once (the runs take minutes)."""
    lines.append(line)
    print(line, flush=True)


def row(name: str, cut: list[int], uncut: list[int], note: str = "") -> str:
    a, b = float(np.mean(cut)), float(np.mean(uncut))
    return (
        f"| {name} | {b:.2f} (max {max(uncut)}) | {a:.2f} (max {max(cut)}) | {a / b:.2f} | {note} |"
    )


def main() -> None:
    lines = [
        "# Newton iterations per step with and without a cut",
        "",
        "`python3 benchmarks/cut_newton.py`: the same run with and without the cut, over the",
        "same steps.",
        "",
        "| run | without the cut | with the cut | ratio | note |",
        "| --- | --- | --- | --- | --- |",
    ]
    with_cut, without = liver(True), liver(False)
    phase = slice(10, 24)  # t = 0.1 .. 0.24 s: the blade cutting, the lobe not yet off
    emit(
        lines,
        row("liver_resection, steps 11-24 (cutting)", with_cut[phase], without[phase],
            f"per step, cut: {with_cut[phase]}; uncut: {without[phase]}")
    )  # fmt: skip
    wedge = "liver_wedge_resection"
    with_cut, without = liver(True, name=wedge), liver(False, name=wedge)
    emit(
        lines,
        row("liver_wedge_resection, steps 11-24 (two crossing cuts)", with_cut[phase],
            without[phase], f"per step, cut: {with_cut[phase]}; uncut: {without[phase]}")
    )  # fmt: skip
    touching, passing = liver_instrument(True), liver_instrument(False)
    emit(
        lines,
        row("liver_instrument, steps 11-24: the scalpel in contact (with) against passing "
            "through (without)", touching[phase], passing[phase],
            f"per step, in contact: {touching[phase]}; passing through: {passing[phase]}")
    )  # fmt: skip
    with raised_fractions():
        floored = liver_instrument(True)
    emit(
        lines,
        row("liver_instrument, steps 11-24, scalpel in contact: the cut as it is (with) against "
            "every element part raised to 5 % of its cell (without: no sliver; a diagnostic, "
            "mass not kept)", touching[phase], floored[phase],
            f"per step, raised: {floored[phase]}")
    )  # fmt: skip
    torn, parted = strip_tearing(True)
    whole, _ = strip_tearing(False)
    after = slice(max(parted - 3, 0), len(torn))  # the crack's growth and the steps after
    emit(
        lines,
        row(f"strip_tearing, steps {after.start + 1}-{len(torn)} (the tear, parted at step "
            f"{parted + 1}, and after): torn (with) against not torn (without)", torn[after],
            whole[after], f"per step, torn: {torn[after]}")
    )  # fmt: skip
    with raised_fractions():
        floored, _ = strip_tearing(True)
    emit(
        lines,
        row("strip_tearing, the same steps: as it is (with) against every part raised to 5 % "
            "of its cell (without; a diagnostic)", torn[after], floored[after],
            f"per step, raised: {floored[after]}")
    )  # fmt: skip
    uncut, _ = organ_run(None)
    for x in (0.011, -0.02137, 0.0, 0.0301):
        cut, smallest = organ_run(x)
        emit(
            lines,
            row(f"organ cut at x = {1e3 * x:g} mm, 8 steps after", cut, uncut,
                f"smallest copy fraction {smallest:.2g}")
        )  # fmt: skip
        if smallest < 0.05:
            with raised_fractions():
                raised, _ = organ_run(x)
            emit(
                lines,
                row(f"organ cut at x = {1e3 * x:g} mm: as it is (with) against every part "
                    "raised to 5 % of its cell (without; a diagnostic)", cut, raised)
            )  # fmt: skip
    lines.append("")
    out = HERE / "results" / "cut_newton.md"
    out.write_text("\n".join(lines))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
