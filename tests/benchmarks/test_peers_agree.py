"""The peer benchmarks (benchmarks/peers.py) compute what tissuesim computes.

FElupe and scikit-fem are optional (``pip install felupe scikit-fem``), not installed in CI, so
these tests skip there. Where they are installed, each peer's internal force vector and tangent
matrix at the same displacement must equal tissuesim's NeoHookean gradient and Hessian (the
same energy, vertex-major DOFs a*d + i) to ~1e-8 relative, in 2D plane strain and in 3D, and
the Newton steps on the free DOFs must agree too.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

import tissuesim as ts
from tissuesim.model import Model

MU, LAM = 1.7e3, 5.3e3
RTOL = 1e-8


def _load_peers():
    path = Path(__file__).resolve().parents[2] / "benchmarks" / "peers.py"
    spec = importlib.util.spec_from_file_location("tissuesim_benchmarks_peers", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


peers = _load_peers()

MESHES = {
    "2d": lambda: ts.rectangle(lower=(0.0, 0.0), upper=(2.0, 1.0), divisions=(6, 4)),
    "3d": lambda: ts.box(lower=(0.0, 0.0, 0.0), upper=(1.0, 0.5, 0.8), divisions=(3, 2, 3)),
}


@pytest.fixture(scope="module", params=sorted(MESHES))
def reference(request):
    mesh = MESHES[request.param]()
    points, cells = mesh.points, mesh.cells
    u, fixed = peers.benchmark_state(points, stretch=0.02, wiggle=0.01)
    model = Model(ts.Mesh(points, cells), ts.NeoHookean(shear_modulus=MU, lame_lambda=LAM), 1.0)
    x = (points + u).ravel()
    gradient = np.asarray(model.evaluate(x, 1, False).gradient, dtype=float)
    hessian = sp.csr_matrix(model.pattern.matrix(model.evaluate(x, 2, False).hessian))
    free = np.setdiff1d(np.arange(x.size), fixed)
    step = np.zeros(x.size)
    step[free] = sp.linalg.spsolve(hessian[free][:, free].tocsc(), -gradient[free])
    return dict(
        points=points, cells=cells, u=u, fixed=fixed, gradient=gradient, hessian=hessian, step=step
    )


def _check_peer(result, ref):
    g, H = ref["gradient"], ref["hessian"]
    assert result["gradient"].shape == g.shape
    assert np.linalg.norm(g) > 0.0
    err_g = np.linalg.norm(result["gradient"] - g) / np.linalg.norm(g)
    assert err_g < RTOL, f"internal force differs from tissuesim: relative error {err_g:.2e}"
    K = sp.csr_matrix(result["matrix"])
    assert K.shape == H.shape
    err_K = sp.linalg.norm(K - H) / sp.linalg.norm(H)
    assert err_K < RTOL, f"tangent differs from tissuesim: relative Frobenius error {err_K:.2e}"
    s = ref["step"]
    err_s = np.linalg.norm(result["step"] - s) / np.linalg.norm(s)
    assert err_s < 1e-6, f"Newton step differs from tissuesim's: relative error {err_s:.2e}"
    for key in ("assembly_vector", "assembly_matrix", "solve", "total", "setup"):
        assert result[key] >= 0.0
    assert isinstance(result["version"], str) and isinstance(result["solver"], str)


def test_felupe_agrees_with_tissuesim(reference):
    pytest.importorskip("felupe")
    r = reference
    result = peers.felupe_iteration(
        r["points"], r["cells"], MU, LAM, r["u"], r["fixed"], repeat=1, return_system=True
    )
    _check_peer(result, r)


@pytest.mark.parametrize("inline", [False, True], ids=["precomputed", "inline"])
def test_skfem_agrees_with_tissuesim(reference, inline):
    pytest.importorskip("skfem")
    r = reference
    result = peers.skfem_iteration(
        r["points"],
        r["cells"],
        MU,
        LAM,
        r["u"],
        r["fixed"],
        repeat=1,
        return_system=True,
        inline=inline,
    )
    _check_peer(result, r)
