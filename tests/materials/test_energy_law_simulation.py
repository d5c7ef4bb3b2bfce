"""A law from its energy in a simulation: the same displacement as the hand-written law on both
assembly backends, and the generated Numba kernel's fused assembly equal to the NumPy path."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("sympy")

import tissuesim as ts  # noqa: E402
from tissuesim.backend import numba_available  # noqa: E402
from tissuesim.mesh import select  # noqa: E402
from tissuesim.model import Model  # noqa: E402

NH = "mu/2*(I1 - 3) - mu*log(J) + lam/2*log(J)**2"
MR = "c1*(I1b - 3) + c2*(I2b - 3) + k/2*log(J)**2"
NH_C = "mu/2*(C11 + C22 + C33 - 3) - mu*log(J) + lam/2*log(J)**2"
BACKENDS = ["numpy", pytest.param("numba", marks=pytest.mark.skipif(
    not numba_available(), reason="numba not installed"))]  # fmt: skip


def _stretch(mesh, material, backend):
    """A bar clamped at x = 0 and pulled 30 % along x at x = 1, quasistatic, 3 steps."""
    sim = ts.Simulation(mesh, material, integrator="quasistatic", time_step=1.0, backend=backend)
    sim.fix(select.vertices_on_plane(mesh, axis=0, value=0.0))
    d = mesh.dim
    pull = np.eye(d)[0] * 0.1

    def move(X, t):
        return np.tile(pull * t, (len(X), 1))

    sim.add_dirichlet(select.vertices_on_plane(mesh, axis=0, value=1.0), move)
    for _ in range(3):
        sim.step()
    return sim.displacement


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize(
    "mesh",
    [
        ts.box(upper=(1.0, 0.3, 0.3), divisions=(6, 2, 2)),
        ts.rectangle(upper=(1.0, 0.3), divisions=(8, 3)),
    ],  # fmt: skip
    ids=["3d", "2d"],
)
def test_same_displacement_as_the_hand_written_law(mesh, backend):
    cases = [
        (ts.EnergyLaw(NH, mu=400.0, lam=600.0), ts.NeoHookean(shear_modulus=400.0,
                                                                lame_lambda=600.0)),
        (ts.EnergyLaw(MR, c1=300.0, c2=100.0, k=1e4), ts.MooneyRivlin(c1=300.0, c2=100.0, k=1e4)),
    ]  # fmt: skip
    for ours, theirs in cases:
        u, v = _stretch(mesh, ours, backend), _stretch(mesh, theirs, backend)
        assert np.abs(v).max() > 0.05
        assert np.abs(u - v).max() <= 1e-12 * np.abs(v).max()


@pytest.mark.skipif(not numba_available(), reason="numba not installed")
@pytest.mark.parametrize("psi", [NH, MR, NH_C], ids=["invariants", "isochoric", "components"])
@pytest.mark.parametrize(
    "mesh",
    [
        ts.box(divisions=(3, 3, 3)),
        ts.rectangle(divisions=(5, 5)),
        ts.box(divisions=(2, 2, 2), order=2),
        ts.box(divisions=(2, 2, 2), element="hex"),
    ],  # fmt: skip
    ids=["tet", "tri", "tet10", "hex"],
)
def test_fused_kernel_equals_the_numpy_path(psi, mesh):
    params = {"mu": 400.0, "lam": 600.0} if psi != MR else {"c1": 300.0, "c2": 100.0, "k": 1e4}
    law = ts.EnergyLaw(psi, **params)
    rng = np.random.default_rng(1)
    x = 1.05 * mesh.points.ravel() + 0.004 * rng.standard_normal(mesh.points.size)
    density = np.ones(mesh.n_cells)
    fused = Model(mesh, law, density=density, backend="numba")
    plain = Model(mesh, law, density=density, backend="numpy")
    assert fused.elastic.fused and not plain.elastic.fused
    a, b = fused.evaluate(x, 2, False), plain.evaluate(x, 2, False)
    assert a.value == pytest.approx(b.value, rel=1e-13)
    for p, q in ((a.gradient, b.gradient), (a.hessian, b.hessian)):
        assert np.abs(p - q).max() <= 1e-13 * np.abs(q).max()
    # an inverted element: +inf energy, as on the NumPy path (the line search backs off)
    y = x.copy().reshape(-1, mesh.dim)
    y[mesh.cells[0, 0]] = y[mesh.cells[0, 1]] + (y[mesh.cells[0, 1]] - y[mesh.cells[0, 0]])
    assert np.isinf(fused.evaluate(y.ravel(), 1, False).value)
    assert np.isinf(plain.evaluate(y.ravel(), 1, False).value)
