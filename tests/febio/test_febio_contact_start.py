"""Issue 42: FEBio's contact surfaces that start touching (its usual set-up: two hex8 blocks
stacked face on face under sliding-elastic) failed after six halvings with raw contact-library
lines; now the converter moves the secondary surface by the barrier's dhat into its body, says
so in one warning line, and the model runs without a halved step to the closed form of two
stacked blocks in uniaxial strain (the same stress in both). And (co35) a support name given
twice, or a <bc> on nodes of two bodies, is made unique in the converted scene."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

from tissuesim.cli import main
from tissuesim.febio import convert_febio
from tissuesim.febio.contact_start import DHAT
from tissuesim.febio.model import FebError
from tissuesim.febio.reader import read_feb
from tissuesim.materials import NeoHookean
from tissuesim.mesh import read_mesh
from tissuesim.scene.loader import load_febio, load_scene

pytest.importorskip("ipctk")

MODEL = Path(__file__).parent / "models" / "contact_touching.feb"
DHAT_HERE = DHAT * float(np.sqrt(2.0))  # the contact surfaces span the unit square
PRESS = 0.05  # the top of 'upper' moves down by this (the model's <bc name="press">)
LOWER_TOP = range(10, 19)  # the node ids of 'lower''s top face (its contact surface)


def _p_zz(youngs_modulus: float, stretch: float) -> float:
    law = NeoHookean(youngs_modulus=youngs_modulus, poisson_ratio=0.3)
    return float(law.evaluate(np.diag([1.0, 1.0, stretch])[None], 1).stress[0, 2, 2])


def _closed_form(press: float) -> float:
    """The press's force on the two blocks (0.5 high each, 'lower' E = 1e4, 'upper' 2e4) held
    laterally: the same P_zz in both, their heights summing to 1 - press."""

    def gap(s1: float) -> float:
        return _p_zz(1e4, s1) - _p_zz(2e4, 2.0 * (1.0 - press) - s1)

    return _p_zz(1e4, brentq(gap, 0.5, 1.0))


def _run(feb: Path, out: Path, capfd) -> tuple[dict, str]:
    code = main(["run", str(feb), "--out", str(out), "--quiet"])
    said = capfd.readouterr()
    assert code == 0, said.err
    return json.loads((out / "summary.json").read_text()), said.out + said.err


def test_touching_surfaces_are_set_apart_in_one_warning_line(tmp_path, capsys):
    assert main(["convert", str(MODEL), str(tmp_path / "scene.toml")]) == 0
    lines = capsys.readouterr().err.strip().splitlines()
    (line,) = [s for s in lines if "contact" in s and "changed" in s]
    contact = next(i for i, s in enumerate(MODEL.read_text().splitlines(), 1) if "<contact " in s)
    assert line.startswith(f"tissuesim: warning: changed: {MODEL}:{contact} <contact>: ")
    assert "'upper_bottom' and 'lower_top' start touching" in line
    assert f"moved {DHAT_HERE:.3g} (model units) into its body" in line
    assert "barrier needs them apart" in line
    text = (tmp_path / "scene.toml").read_text()
    assert f"dhat = {DHAT_HERE!r}" in text and "# changed: " in text
    lower = read_mesh(tmp_path / "scene.lower.msh").points
    upper = read_mesh(tmp_path / "scene.upper.msh").points
    top = np.isclose(lower[:, 2], 0.5 - DHAT_HERE, rtol=0, atol=1e-15)
    assert top.sum() == 9  # 'lower''s top face moved down by dhat, exactly
    assert set(np.round(lower[~top, 2], 12)) == {0.0}  # its base stays
    assert set(np.round(upper[:, 2], 12)) == {0.5, 1.0}  # the primary's body stays


def test_touching_blocks_run_to_the_closed_form_without_a_halving(tmp_path, capfd):
    summary, output = _run(MODEL, tmp_path / "out", capfd)
    assert [s["substeps"] for s in summary["steps"]] == [1, 1]  # no halved step
    assert "[ipctk]" not in output and "[warning]" not in output  # no raw library lines
    for step, press in zip(summary["steps"], (PRESS / 2, PRESS), strict=True):
        force = -step["extra"]["forces"]["press"][2]
        expected = -_closed_form(press)
        # the offset's effect: the press moved by dhat more or less (3 % at the end)
        effect = abs(_closed_form(press + DHAT_HERE) - _closed_form(press))
        assert abs(force - expected) < effect
        assert force == pytest.approx(expected, rel=5e-3)  # measured: 1.9e-3 at the end
        assert step["extra"]["forces"]["base"][2] == pytest.approx(force, rel=1e-8)


def test_touching_blocks_run_as_the_same_blocks_built_dhat_apart(tmp_path):
    """The converter's move is the whole difference: the model written with 'lower''s top face
    dhat below 'upper''s (no warning; its scene given the same dhat) gives the same forces."""
    text = MODEL.read_text()
    for node in LOWER_TOP:
        text, n = re.subn(rf'(<node id="{node}">[^<]*),0\.5<', rf"\g<1>,{0.5 - DHAT_HERE!r}<", text)
        assert n == 1
    apart = tmp_path / "apart.feb"
    apart.write_text(text)
    assert main(["convert", str(apart), str(tmp_path / "apart.toml")]) == 0
    scene = (tmp_path / "apart.toml").read_text()
    assert "dhat" not in scene and "# changed" not in scene  # it needed no move
    (tmp_path / "apart.toml").write_text(
        scene.replace("[contact]\n", f"[contact]\ndhat = {DHAT_HERE!r}\n")
    )
    forces = []
    for scene in (load_febio(MODEL), load_scene(tmp_path / "apart.toml")):
        sim = scene.simulation
        sim.step()
        forces.append(sim.step().extra["forces"])
    for name in ("press", "base", "hold", "lower.contact.upper"):
        np.testing.assert_allclose(forces[0][name], forces[1][name], rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize("names", ["split", "twice", "none"])
def test_support_names_are_unique_in_the_converted_scene(names, tmp_path):
    """co35: a <bc> on the nodes of two bodies is written once per body under one name (the
    loader refused the second); two <bc> may also share a name, or have none."""
    text = MODEL.read_text()
    if names == "twice":  # two <bc> named "hold", on different node sets
        text = text.replace('<bc name="base"', '<bc name="hold"')
    elif names == "none":
        text = re.sub(r'<bc name="\w+" ', "<bc ", text)
    feb = tmp_path / "model.feb"
    feb.write_text(text)
    scene = tmp_path / "scene.toml"
    assert main(["convert", str(feb), str(scene)]) == 0
    written = re.findall(r'^name = "([^"]+)"', scene.read_text(), flags=re.M)
    supports = [n for n in written if n not in ("lower", "upper")]
    assert len(supports) == len(set(supports))
    expected = {
        "split": ["hold", "base", "hold.upper", "press"],
        "twice": ["hold", "hold.lower", "hold.upper", "press"],
        "none": [],
    }[names]
    assert supports == expected
    sim = load_scene(scene).simulation
    sim.step()
    sim.step()
    assert sim.history[-1].converged


def test_the_secondary_surface_moves_into_its_own_body(tmp_path):
    """With the pair's roles swapped, 'upper''s bottom face is the one moved: up, into
    'upper'; 'lower' stays as written."""
    text = MODEL.read_text()
    old = "<primary>upper_bottom</primary>\n      <secondary>lower_top</secondary>"
    assert old in text
    feb = tmp_path / "swapped.feb"
    feb.write_text(text.replace(old, old.replace("upper_bottom", "@").replace("lower_top",
                   "upper_bottom").replace("@", "lower_top")))  # fmt: skip
    with pytest.warns(UserWarning, match="the secondary 'upper_bottom' \\(9 nodes\\) is moved"):
        convert_febio(feb, tmp_path / "scene.toml")
    lower = read_mesh(tmp_path / "scene.lower.msh").points
    upper = read_mesh(tmp_path / "scene.upper.msh").points
    assert set(np.round(lower[:, 2], 12)) == {0.0, 0.5}
    bottom = np.isclose(upper[:, 2], 0.5 + DHAT_HERE, rtol=0, atol=1e-15)
    assert bottom.sum() == 9 and set(np.round(upper[~bottom, 2], 12)) == {1.0}


def test_frictionless_touching_blocks_run_as_febio_does_by_its_penalty(tmp_path, capfd):
    """Without friction, FEBio's sliding contact converts to tissuesim's penalty contact as
    FEBio enforces it (contact/penalty/): the touching surfaces stay where they are (no
    move, no warning) and, augmented (AUGLAG, tolerance 1e-8), the press's force is the
    closed form of the stacked blocks to 1e-6 at both steps."""
    text = MODEL.read_text().replace(
        "<fric_coeff>0.01</fric_coeff>\n      <penalty>1</penalty>",
        "<fric_coeff>0</fric_coeff>\n      <laugon>AUGLAG</laugon>\n      <penalty>1e5</penalty>"
        "\n      <tolerance>1e-8</tolerance>\n      <maxaug>50</maxaug>",
    )
    assert "AUGLAG" in text
    feb = tmp_path / "penalty.feb"
    feb.write_text(text)
    assert main(["convert", str(feb), str(tmp_path / "scene.toml")]) == 0
    said = capfd.readouterr()
    scene = (tmp_path / "scene.toml").read_text()
    assert "changed" not in said.err and "[[penalty_contact]]" in scene
    assert 'integration = "gauss"' in scene and 'area = "current"' in scene
    summary, _ = _run(feb, tmp_path / "out", capfd)
    for step, press in zip(summary["steps"], (PRESS / 2, PRESS), strict=True):
        force = step["extra"]["forces"]["press"][2]
        assert force == pytest.approx(_closed_form(press), rel=1e-6)


def test_a_tied_elastic_pair_runs_as_a_tied_penalty_contact(tmp_path, capfd):
    """FEBio's tied-elastic converts to a tied [[penalty_contact]]; augmented (AUGLAG 1e-8),
    the pressed blocks give the closed form to 1e-6 as the sliding pair does."""
    text = (
        MODEL.read_text()
        .replace('<contact type="sliding-elastic"', '<contact type="tied-elastic"')
        .replace(
            "<fric_coeff>0.01</fric_coeff>\n      <penalty>1</penalty>",
            "<laugon>AUGLAG</laugon>\n      <penalty>1e5</penalty>\n"
            "      <tolerance>1e-8</tolerance>\n      <maxaug>50</maxaug>",
        )
    )
    assert "tied-elastic" in text and "AUGLAG" in text
    feb = tmp_path / "tied.feb"
    feb.write_text(text)
    assert main(["convert", str(feb), str(tmp_path / "scene.toml")]) == 0
    assert "tied = true" in (tmp_path / "scene.toml").read_text()
    summary, _ = _run(feb, tmp_path / "out", capfd)
    force = summary["steps"][-1]["extra"]["forces"]["press"][2]
    assert force == pytest.approx(_closed_form(PRESS), rel=1e-6)


def test_a_sticky_pair_converts_to_a_sticky_penalty_contact_on_nodes(tmp_path):
    """FEBio's sticky contact: a [[penalty_contact]] on the primary's nodes with sticky = true
    and its snap_tol and max_traction; a gap_offset is refused in one line."""
    text = (
        MODEL.read_text()
        .replace('<contact type="sliding-elastic"', '<contact type="sticky"')
        .replace(
            "<fric_coeff>0.01</fric_coeff>\n      <penalty>1</penalty>",
            "<penalty>1e5</penalty>\n      <snap_tol>0.01</snap_tol>\n"
            "      <max_traction>50</max_traction>",
        )
    )
    feb = tmp_path / "sticky.feb"
    feb.write_text(text)
    assert main(["convert", str(feb), str(tmp_path / "scene.toml")]) == 0
    scene = (tmp_path / "scene.toml").read_text()
    for line in ("sticky = true", 'integration = "nodes"', "snap_tolerance = 0.01",
                 "max_traction = 50.0"):  # fmt: skip
        assert line in scene
    feb.write_text(text.replace("<snap_tol>", "<gap_offset>0.1</gap_offset>\n      <snap_tol>"))
    with pytest.raises(FebError) as info:
        read_feb(feb)
    assert "\n" not in str(info.value) and "gap_offset" in str(info.value)
