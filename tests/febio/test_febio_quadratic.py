"""FEBio's hex20 and hex27 (tests/febio/models/hex*.feb, written in FEBio's node order): the
reader's permutation onto tissuesim's (VTK's) order, homogeneous stretches against the laws'
closed forms, a cantilever against hex8 and beam theory, and misnumbered elements refused."""

from __future__ import annotations

import re
import warnings
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

from tissuesim.febio import FebError, febio_scene, load_febio, read_feb
from tissuesim.febio.mesh_sections import PERMUTATIONS
from tissuesim.mesh.cells.tensor_quadratic import NODES

MODELS = Path(__file__).parent / "models"

#: FEBio's HEX27_LUT (FECore/FESolidElementShape.cpp): per node, the 1D quadratic of r, s, t
#: its shape function takes, 0: r (r - 1) / 2 (node at -1), 1: r (r + 1) / 2 (+1), 2: 1 - r^2
#: (0); its first 20 rows are FEHex20::shape_fnc's nodes (same file)
HEX27_LUT = [
    (0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1),
    (2, 0, 0), (1, 2, 0), (2, 1, 0), (0, 2, 0), (2, 0, 1), (1, 2, 1), (2, 1, 1), (0, 2, 1),
    (0, 0, 2), (1, 0, 2), (1, 1, 2), (0, 1, 2), (2, 0, 2), (1, 2, 2), (2, 1, 2), (0, 2, 2),
    (2, 2, 0), (2, 2, 1), (2, 2, 2),
]  # fmt: skip


def _run(path: Path, steps: int):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a lowered cantilever leaves nodes unused
        scene = load_febio(path)
    sim = scene.simulation
    for _ in range(steps):
        record = sim.step()
    return sim, record


@pytest.mark.parametrize("kind", ["hexahedron20", "hexahedron27"])
def test_permutation_matches_febios_node_coordinates(kind):
    """tissuesim's node k is FEBio's node PERMUTATIONS[k]: the same reference point."""
    febio = np.array([[-1.0, 1.0, 0.0][i] for row in HEX27_LUT for i in row]).reshape(27, 3)
    ours = NODES[kind]
    febio = febio[: len(ours)]
    found = [int(np.flatnonzero((febio == x).all(axis=1))[0]) for x in ours]
    fe_type = {"hexahedron20": "hex20", "hexahedron27": "hex27"}[kind]
    expected = PERMUTATIONS.get(fe_type, np.arange(len(ours)))
    assert found == expected.tolist()


def _stretches(sim) -> np.ndarray:
    x, X = sim.positions, sim.body("body").mesh.points
    return np.array([np.polyfit(X[:, i], x[:, i], 1)[0] for i in range(3)])


def test_hex20_uniaxial_neo_hookean_matches_the_closed_form():
    """Two hex20 (2 x 1 x 1) stretched to 1.2 through their quad8 face: FEBio's neo-Hookean
    P_xx with P_yy = 0, the lateral stretch homogeneous, midside nodes included."""
    sim, record = _run(MODELS / "hex20_uniaxial.feb", 2)
    E, nu, stretch = 1e4, 0.3, 1.2
    mu, lam = E / (2 * (1 + nu)), E * nu / ((1 + nu) * (1 - 2 * nu))
    t = brentq(lambda t: mu * (t - 1 / t) + lam * np.log(stretch * t * t) / t, 0.5, 1.0)
    P_xx = mu * (stretch - 1 / stretch) + lam * np.log(stretch * t * t) / stretch
    assert abs(record.extra["forces"]["pull"][0]) == pytest.approx(P_xx, rel=1e-9)
    X = sim.body("body").mesh.points
    assert len(X) == 32
    assert np.allclose(sim.positions, X * [stretch, t, t], atol=1e-9)


def test_hex27_uniaxial_mooney_rivlin_runs_febios_displacement_element():
    """Two hex27 through their quad9 face: FEBio runs an uncoupled law on hex27 as
    elastic-solid (no three-field element), so the scene's formulation is the displacement
    one; the state is the law's uniaxial one (P_yy = P_zz = 0, pull = P_xx)."""
    data, _ = febio_scene(read_feb(MODELS / "hex27_uniaxial.feb"), "x")
    assert data["simulation"]["formulation"] == "displacement"
    sim, record = _run(MODELS / "hex27_uniaxial.feb", 2)
    stretch = _stretches(sim)
    X = sim.body("body").mesh.points
    assert len(X) == 45
    assert np.allclose(sim.positions, X * stretch, atol=1e-9)
    P = sim.body("body").model.material.evaluate(np.diag(stretch)[None], 1).stress[0]
    assert stretch[0] == pytest.approx(1.2) and stretch[1] < 0.95
    assert np.allclose([P[1, 1], P[2, 2]], 0.0, atol=1e-6 * P[0, 0])
    assert abs(record.extra["forces"]["pull"][0]) == pytest.approx(P[0, 0], rel=1e-6)


def _lowered(text: str, kind: str) -> str:
    """The hex27 model as hex20 or hex8: FEBio's hex20 (hex8) is hex27's first 20 (8) nodes,
    quad8 (quad4) quad9's first 8 (4)."""
    nv, facet, nf = {"hex20": (20, "quad8", 8), "hex8": (8, "quad4", 4)}[kind]
    text = text.replace('type="hex27"', f'type="{kind}"')
    text = re.sub(
        r'(<elem id="\d+">)([\d,]+)', lambda m: m[1] + ",".join(m[2].split(",")[:nv]), text
    )
    return re.sub(
        r'<quad9( id="\d+">)([\d,]+)</quad9>',
        lambda m: f"<{facet}{m[1]}{','.join(m[2].split(',')[:nf])}</{facet}>",
        text,
    )


def test_cantilever_quadratic_hexahedra_bend_as_a_beam_where_hex8_locks(tmp_path):
    """A 10 x 1 x 1 cantilever of 4 elements, clamped, a dead shear traction of total 0.25 on
    its tip (quad9 / quad8 / quad4 facets): the tip deflection against Timoshenko's
    F L^3 / 3EI + F L / (5/6 G A) = 0.1008 (the clamp and the 3D root make the exact solution
    a little stiffer). hex8 (fully integrated, one element through the depth) locks in shear;
    hex20 and hex27 come within 5 %, hex27's richer space the closer."""
    text = (MODELS / "hex27_cantilever.feb").read_text()
    E, nu, F, L = 1e4, 0.3, 0.25, 10.0
    beam = F * L**3 / (3 * E / 12) + F * L / (5 / 6 * E / (2 * (1 + nu)))
    tip = {}
    for kind in ("hex27", "hex20", "hex8"):
        feb = tmp_path / f"{kind}.feb"
        feb.write_text(text if kind == "hex27" else _lowered(text, kind))
        sim, record = _run(feb, 1)
        X = sim.body("body").mesh.points
        end = np.abs(X[:, 0] - L) < 1e-9
        tip[kind] = -(sim.positions - X)[end, 2].mean()
        assert record.extra["forces"]["clamp"][2] == pytest.approx(F, rel=1e-9)
    assert tip["hex8"] < 0.35 * beam
    assert 0.95 * beam < tip["hex20"] < tip["hex27"] < beam


MISNUMBERED = {
    "hex27 in VTK's order": ("hex27_uniaxial", [*range(20), 23, 21, 20, 22, 24, 25, 26]),
    "hex27 centre and a face centre": ("hex27_uniaxial", [*range(24), 26, 25, 24]),
    "hex20 two midside nodes": ("hex20_uniaxial", [*range(8), 9, 8, *range(10, 20)]),
    "hex20 two corners": ("hex20_uniaxial", [1, 0, *range(2, 20)]),
}  # fmt: skip


@pytest.mark.parametrize("case", sorted(MISNUMBERED))
def test_misnumbered_quadratic_hexahedra_are_refused_at_their_element(case, tmp_path):
    name, perm = MISNUMBERED[case]
    text = (MODELS / f"{name}.feb").read_text()
    lines = text.splitlines()
    first = next(i for i, s in enumerate(lines, 1) if '<elem id="1">' in s)
    text = re.sub(
        r'(<elem id="1">)([\d,]+)',
        lambda m: m[1] + ",".join(np.array(m[2].split(","))[perm]),
        text,
    )
    feb = tmp_path / "bad.feb"
    feb.write_text(text)
    with pytest.raises(FebError) as info:
        read_feb(feb)
    said = str(info.value)
    assert "\n" not in said and f"bad.feb:{first} <elem>" in said
    assert "not in FEBio's order" in said and "1 such elements" in said
