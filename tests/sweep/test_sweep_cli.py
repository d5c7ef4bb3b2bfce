"""``tissuesim sweep``: bad input is one line naming the key and the fix, exit 2; a study runs
to its report and table."""

from __future__ import annotations

import json

import pytest

from tissuesim.cli import main


@pytest.mark.parametrize(
    "vary, says",
    [
        (
            "material.youngs_modulu=1e3,2e3",
            "--vary material.youngs_modulu: [material] has no key 'youngs_modulu'; "
            "did you mean 'youngs_modulus'?",
        ),
        ("dirichlet[pul].name=a", "has no entry named 'pul'; did you mean 'pull'?"),
        (
            "material.youngs_modulus=1e3:5e3:x",
            "--vary material.youngs_modulus=1e3:5e3:x: the count N must be an integer >= 1",
        ),
        ("material.youngs_modulus=1e3:", "malformed range; write a list"),
        ("material.youngs_modulus", "write KEY=VALUES"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(bar_scene, tmp_path, capsys, vary, says):
    code = main(["sweep", str(bar_scene), "--vary", vary, "--out", str(tmp_path / "s")])
    err = capsys.readouterr().err
    assert code == 2
    assert err.startswith("tissuesim: error: ") and err.count("\n") == 1
    assert says in err
    assert not (tmp_path / "s").exists()  # refused before anything was written


def test_an_unknown_executor_is_refused(bar_scene, tmp_path, capsys):
    args = ["sweep", str(bar_scene), "--vary", "material.youngs_modulus=1e3,2e3"]
    code = main([*args, "--out", str(tmp_path / "s"), "--executor", "slurm"])
    assert code == 2
    assert "--executor 'slurm': choose local" in capsys.readouterr().err


def test_a_study_from_the_command_line(bar_scene, tmp_path, capsys):
    out = tmp_path / "s"
    args = [
        "sweep",
        str(bar_scene),
        "--vary",
        "material.youngs_modulus=500:2000",  # an interval: sampled by Sobol by default
        "--vary",
        "material.poisson_ratio=0.3,0.7",  # 0.7 is refused by the law: those runs fail
        "--samples",
        "2",
        "--out",
        str(out),
        "--workers",
        "1",
        "--fields",
        "displacement",
        "--no-render",
        "--quiet",
    ]
    assert main(args) == 0
    captured = capsys.readouterr()
    assert captured.err == ""  # --quiet
    report = json.loads(captured.out)
    assert report["runs"] == 4 and report["completed"] == 2 and report["failed"] == 2
    assert "poisson_ratio" in report["first_failure"]
    assert report["table"] == [str(out / "runs.csv"), str(out / "runs.parquet")]
    study = json.loads((out / "study.json").read_text())
    assert study["sampler"] == "sobol" and study["seed"] == 0
    assert sorted(p.name for p in (out / "fields").iterdir()) == [
        "r00000.h5",
        "r00001.h5",
        "rest.h5",
    ]
    pq = pytest.importorskip("pyarrow.parquet")
    from tissuesim.sweep import load_table

    assert pq.read_table(out / "runs.parquet").to_pylist() == load_table(out)
    assert main(args) == 0  # again: everything is there, nothing runs
    assert json.loads(capsys.readouterr().out)["completed"] == 2


def test_the_guide_s_command_varies_keys_the_shipped_scene_has():
    """docs/guide/sweeps.md's first command: its keys and values are valid for palpation."""
    import re
    import shlex
    from pathlib import Path

    from tissuesim.sweep.samples import make_samples, parameters
    from tissuesim.sweep.study import read_scene_data

    page = Path(__file__).resolve().parents[2] / "docs" / "guide" / "sweeps.md"
    command = re.search(r"```bash\n(.*?)```", page.read_text(), flags=re.S).group(1)
    line = " ".join(command.split("\\\n")).splitlines()[3]
    words = shlex.split(line)
    assert words[:3] == ["tissuesim", "sweep", "palpation"]
    vary = [words[i + 1] for i, w in enumerate(words) if w == "--vary"]
    data, _ = read_scene_data("palpation")
    runs = make_samples(parameters(vary, data), 256, "sobol", 1)
    assert len(runs) == 256 and len(vary) == 2
