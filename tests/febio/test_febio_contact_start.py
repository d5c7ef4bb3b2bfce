"""Issue 42: FEBio's contact surfaces that start touching (its usual set-up: two hex8 blocks
stacked face on face under sliding-elastic) failed after six halvings with raw contact-library
lines on tissuesim's barrier; FEBio's sliding contacts now convert to FEBio's own penalty /
augmented-Lagrangian enforcement (friction too), which takes touching surfaces as they are, and
run to the closed form of two stacked blocks in uniaxial strain (the same stress in both). And
(co35) a support name given twice, or a <bc> on nodes of two bodies, is made unique in the
converted scene."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

from tissuesim.cli import main
from tissuesim.febio.model import FebError
from tissuesim.febio.reader import read_feb
from tissuesim.materials import NeoHookean
from tissuesim.scene.loader import load_scene

pytest.importorskip("ipctk")

MODEL = Path(__file__).parent / "models" / "contact_touching.feb"
PRESS = 0.05  # the top of 'upper' moves down by this (the model's <bc name="press">)


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
    supports = [n for n in written if n not in ("lower", "upper", "contact1")]
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


@pytest.mark.parametrize("kind", ["sliding-elastic", "sliding-node-on-facet"])
def test_a_frictional_pair_converts_to_the_penalty_contact_with_febios_friction(
    kind, tmp_path, capfd
):
    """fric_coeff 0.2 on the stacked blocks: the pair is the penalty contact with friction 0.2
    (node-on-facet: its fric_penalty the stick's penalty; sliding-elastic: the normal one), and
    the press's force is the closed form (the blocks are held laterally: friction carries
    nothing) to 1e-6."""
    text = (
        MODEL.read_text()
        .replace(
            "<fric_coeff>0.01</fric_coeff>\n      <penalty>1</penalty>",
            "<fric_coeff>0.2</fric_coeff>\n      <fric_penalty>1e4</fric_penalty>\n"
            "      <laugon>AUGLAG</laugon>\n      <penalty>1e5</penalty>"
            "\n      <tolerance>1e-8</tolerance>\n      <maxaug>50</maxaug>",
        )
        .replace('type="sliding-elastic"', f'type="{kind}"')
    )
    feb = tmp_path / "friction.feb"
    feb.write_text(text)
    assert main(["convert", str(feb), str(tmp_path / "scene.toml")]) == 0
    scene = (tmp_path / "scene.toml").read_text()
    assert "friction = 0.2" in scene
    assert ("friction_penalty = 10000.0" in scene) == (kind == "sliding-node-on-facet")
    summary, _ = _run(feb, tmp_path / "out", capfd)
    force = summary["steps"][-1]["extra"]["forces"]["press"][2]
    assert force == pytest.approx(_closed_form(PRESS), rel=1e-6)


def test_a_sliding_elastic_pair_in_tension_converts_and_other_contacts_refuse_it(tmp_path):
    """tension = 1 on FEBio's sliding-elastic: the penalty contact with tension = true; on a
    frictional pair (FEBio refuses it too) and on a node-on-facet pair (no such parameter in
    FEBio) one line each."""
    base = MODEL.read_text().replace(
        "<fric_coeff>0.01</fric_coeff>", "<fric_coeff>0</fric_coeff>\n      <tension>1</tension>"
    )
    assert "<tension>1</tension>" in base
    feb = tmp_path / "tension.feb"
    feb.write_text(base)
    assert main(["convert", str(feb), str(tmp_path / "scene.toml")]) == 0
    assert "tension = true" in (tmp_path / "scene.toml").read_text()
    for text, message in [
        (base.replace("<fric_coeff>0</fric_coeff>", "<fric_coeff>0.2</fric_coeff>"),
         "tension = 1 with friction"),
        (base.replace('type="sliding-elastic"', 'type="sliding-node-on-facet"'),
         "tension = 1 on a sliding-node-on-facet contact"),
    ]:  # fmt: skip
        feb.write_text(text)
        with pytest.raises(FebError) as info:
            read_feb(feb)
        assert "\n" not in str(info.value) and message in str(info.value)
