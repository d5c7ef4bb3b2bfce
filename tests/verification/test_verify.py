"""``tissuesim verify``: every shipped verification problem passes, the table and the JSON
say so, and a deliberately wrong reference makes the command exit 1."""

import json

import pytest

import tissuesim.verification.cook as cook
import tissuesim.verification.fibres as fibres
import tissuesim.verification.hertz as hertz
import tissuesim.verification.laws as laws
from tissuesim.cli import main
from tissuesim.verification import run, table
from tissuesim.verification.check import FAMILIES
from tissuesim.verification.result import Check


def test_every_problem_passes():
    """The whole set, run once in the suite (about 5 s; its Hertz check is looked at here too,
    as xdist would run a shared fixture once per worker)."""
    from tissuesim.verification import damage, reactive_viscoelastic

    checks = run()
    reactive = len(reactive_viscoelastic.checks()) + len(damage.checks())
    expected = 3 * len(laws.LAWS) + len(fibres.CASES) + 3 + reactive + 4 + 2 + len(cook.CASES)
    assert len(checks) == expected + 2
    failed = [c for c in checks if not c.passed]
    assert failed == []
    assert table(checks).splitlines()[-1] == f"{len(checks)} of {len(checks)} checks pass"
    assert {c.problem.split(",")[0] for c in checks} >= {
        "Cook's membrane", "Hertz sphere", "holzapfel_gasser_ogden", "trans_iso_mooney_rivlin",
    }  # fmt: skip
    _hertz_check_is_sharp([c for c in checks if c.problem.startswith("Hertz")])
    _press_check_is_sharp([c for c in checks if c.problem.startswith("Rigid plane")])


def test_every_registered_law_is_verified():
    from tissuesim.materials import MATERIALS

    assert set(MATERIALS) <= set(laws.LAWS) | {case[0] for case in fibres.CASES}


def test_the_fibre_checks_see_the_switch_off():
    """A closed form whose fibres also bear compression (no Macaulay bracket) fails exactly the
    checks where a family is compressed; one with the families' angle wrong fails the rest."""

    def hgo_without_switch(fibres_, i1, i4s):
        p = fibres._HGO
        d = []
        for i4 in i4s:
            E = p["kappa"] * (i1 - 3.0) + (1.0 - 3.0 * p["kappa"]) * (i4 - 1.0)
            d.append(p["k1"] * E * fibres.math.exp(p["k2"] * E * E))
        return p["c"] / 2 + p["kappa"] * sum(d), 0.0, [(1 - 3 * p["kappa"]) * v for v in d]

    hgo = [c for c in fibres.CASES if c[0] == "holzapfel_gasser_ogden"]
    wrong = [(*c[:4], hgo_without_switch, c[5]) for c in hgo]
    passed = {c.quantity: c.passed for c in fibres.checks(wrong)}
    assert [q for q, ok in passed.items() if not ok] == [
        q for q in passed if "compressed" in q
    ] and len(passed) - sum(passed.values()) == 2
    tilted = [(*c[:5], fibres._families(25.0, False)) for c in hgo if "along" in c[1]]
    assert not fibres.checks(tilted)[0].passed


def test_cooks_reference_belongs_to_the_middle_of_the_loaded_edge():
    """23.96 is met at (48, 52); the upper corner, with the same reference, is 4 % off and
    fails; a reference 0.5 % off fails too."""
    label, stress, E, nu, traction, _, n, ref, tol = cook.CASES[0]
    corner = (label, stress, E, nu, traction, (48.0, 60.0), n, ref, tol)
    middle_off = (label, stress, E, nu, traction, (48.0, 52.0), n, ref * 1.005, tol)
    results = cook.checks((corner, middle_off))
    assert [c.passed for c in results] == [False, False]
    assert 0.03 < results[0].error < 0.05


def _hertz_check_is_sharp(found: list) -> None:
    # F = 4/3 E / (1 - nu^2) sqrt(R) d^1.5 at d = 100 um, worked out by hand
    assert hertz.hertz_force(1e-4) == pytest.approx(4 / 3 * 1e4 / 0.91 * 0.1 * 1e-6, rel=1e-12)
    (check,) = found
    assert 0.9e-4 < float(check.quantity.split("=")[1].split()[0]) * 1e-6 < 1.0e-4
    assert check.result > check.reference  # the coarse mesh is stiff
    # Hertz with E for E* (no 1 - nu^2), or the quarter's share: both fail
    tol = hertz.TOL
    for factor in (1 - 0.3**2, 0.25):
        wrong = Check(check.problem, check.quantity, factor * check.reference, check.result, tol)
        assert not wrong.passed


def _press_check_is_sharp(found: list) -> None:
    """Issue 41: the Hertz row passed at 13 % against 20 %. The flat press is exact for Q1
    elements: its force is met to 1e-4 (it reads 2.5e-5); the modulus E for the oedometric
    M (factor 1.35), or the depth off by the barrier's dhat (1e-3), fail it."""
    (check,) = found
    assert check.tolerance == hertz.PRESS_TOL == 1e-4 and check.error < 1e-4
    assert hertz.press_force(1e-4) == pytest.approx(1e4 * 0.7 / (1.3 * 0.4) * 0.01 * 1e-4)
    for factor in (1.3 * 0.4 / 0.7, 1 - hertz.PRESS_DHAT / 1e-4):
        wrong = Check(check.problem, check.quantity, factor * check.reference, check.result, 1e-4)
        assert not wrong.passed


def test_the_hertz_row_says_what_it_checks():
    """The Hertz row names its mesh's error and its tolerance is within 3 % of it."""
    assert hertz.TOL == 0.15
    d, force = hertz.indentation()
    ratio = force / hertz.hertz_force(d)
    assert ratio == pytest.approx(1.126, abs=0.001)  # the "+12.6 %" its name says
    assert hertz.TOL - 0.03 < ratio - 1 < hertz.TOL


def test_verify_prints_no_warning(capsys):
    """Cook's membrane is in the benchmark's own units: no "60 m across" units warning."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert main(["verify", "--only", "cook"]) == 0
    assert "warning" not in capsys.readouterr().err


def test_every_family_can_be_chosen(capsys):
    assert main(["verify", "--only", "fibres", "--only", "cook"]) == 0
    out = capsys.readouterr().out
    assert f"{len(fibres.CASES) + len(cook.CASES)} of" in out
    assert set(FAMILIES) == {
        "laws", "fibres", "patch", "viscoelastic", "reactive", "dynamics", "cook", "hertz",
    }  # fmt: skip


def test_the_reactive_family_checks_the_history_laws(capsys):
    """FEBio's reactive viscoelasticity (types I and II) and damage (load, unload, reload,
    hold) against their closed forms, as tissuesim verify prints them."""
    from tissuesim.verification import damage, reactive_viscoelastic

    checks = reactive_viscoelastic.checks() + damage.checks()
    assert checks and all(c.passed for c in checks)
    assert main(["verify", "--only", "reactive"]) == 0
    assert f"{len(checks)} of {len(checks)}" in capsys.readouterr().out


def test_the_dynamics_checks_pass_and_fail_backward_euler():
    """Newmark passes both; Backward Euler, first order and damped, fails both tolerances."""
    from tissuesim.verification import dynamics

    assert all(c.passed for c in dynamics.checks())
    drop, fallen = dynamics.free_fall("backward_euler")
    start, end = dynamics.swing("backward_euler")
    assert abs(fallen - drop) > 1e-3 * drop and abs(end - start) > 1e-3 * start


def test_the_command_prints_the_table_and_json(capsys):
    assert main(["verify", "--only", "patch"]) == 0
    out = capsys.readouterr().out
    assert out.splitlines()[0].split() == [
        "problem", "quantity", "reference", "result", "error", "tolerance", "pass",
    ]  # fmt: skip
    assert "3 of 3 checks pass" in out
    assert main(["verify", "--only", "patch", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["passed"] is True and len(data["checks"]) == 3
    assert set(data["checks"][0]) >= {"problem", "reference", "result", "error", "pass"}


def test_a_wrong_reference_fails_the_command(monkeypatch, capsys):
    params, closed = laws.LAWS["neo_hookean"]

    def wrong():
        uni, bi, shear = closed()
        return uni * (1 + 1e-6), bi, shear

    monkeypatch.setattr(laws, "LAWS", {"neo_hookean": (params, wrong)})
    assert main(["verify", "--only", "laws"]) == 1
    out = capsys.readouterr().out
    assert "NO" in out and "2 of 3 checks pass" in out
