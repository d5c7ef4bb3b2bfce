"""``tissuesim verify``: every shipped verification problem passes, the table and the JSON
say so, and a deliberately wrong reference makes the command exit 1."""

import json

import tissuesim.verification.laws as laws
from tissuesim.cli import main
from tissuesim.verification import run, table


def test_every_problem_passes():
    checks = run()
    assert len(checks) >= 3 * len(laws.LAWS) + 3 + 4
    failed = [c for c in checks if not c.passed]
    assert failed == []
    assert table(checks).splitlines()[-1] == f"{len(checks)} of {len(checks)} checks pass"


#: the fibre-reinforced laws have no closed form in the verification set yet
NOT_YET = {"holzapfel_gasser_ogden", "hgo_unconstrained", "trans_iso_mooney_rivlin"}


def test_every_registered_law_is_verified():
    from tissuesim.materials import MATERIALS

    assert set(MATERIALS) - NOT_YET <= set(laws.LAWS)


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
