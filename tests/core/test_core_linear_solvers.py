"""Every linear solver on the same Newton matrices: accuracy, indefinite matrices, reuse of the
analysis across refactorisations, the AMG's rigid-body modes and lagged hierarchy, and the
automatic choice."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from tissuesim.constraints.dirichlet import DirichletCondition
from tissuesim.materials import NeoHookean
from tissuesim.mesh import box, rectangle, select
from tissuesim.model import Model
from tissuesim.solve import linear
from tissuesim.solve.linear import (
    CGSolver,
    NotPositiveDefiniteError,
    SuperLUSolver,
    make_linear_solver,
    rigid_body_modes,
)

AVAILABLE = {
    "pardiso": linear.has_pardiso(),
    "cholmod": linear.has_cholmod(),
    "splu": True,
    "cg": True,
    "amg": linear.has_pyamg(),
}
SOLVERS = [
    pytest.param(n, marks=pytest.mark.skipif(not ok, reason=f"{n} not installed"))
    for n, ok in AVAILABLE.items()
]


def newton_system(dim, n, stretch=0.02, seed=0):
    mesh = (
        rectangle(lower=(0, 0), upper=(1, 1), divisions=(n, n))
        if dim == 2
        else box(lower=(0, 0, 0), upper=(1, 1, 1), divisions=(n, n, n))
    )
    model = Model(mesh, NeoHookean(youngs_modulus=1e3, poisson_ratio=0.3), 1.0)
    left = select.vertices_on_plane(mesh, 0, 0.0)
    model.set_conditions([DirichletCondition(left, lambda X, t: np.zeros_like(X))])
    rng = np.random.default_rng(seed)
    x = mesh.points * (1 + stretch) + 1e-3 * rng.standard_normal(mesh.points.shape)
    x[left] = mesh.points[left]
    acc = model.evaluate(x.ravel(), 2, False)
    model.elimination.apply(acc.hessian, acc.gradient)
    return mesh, model, acc


@pytest.mark.parametrize("name", SOLVERS)
@pytest.mark.parametrize("dim", [2, 3])
def test_solver_solves_newton_system_and_reuses_analysis(name, dim):
    mesh, model, acc = newton_system(dim, 10 if dim == 2 else 4)
    solver, reason = make_linear_solver(name, model.n_dofs, dim, mesh.points)
    assert reason == "requested"
    A = model.pattern.matrix(acc.hessian)
    for scale in (1.0, 1.3):  # a second factorisation of new values on the same pattern
        data = acc.hessian * scale
        A = model.pattern.matrix(data)
        solver.factorize(A)
        b = -acc.gradient
        x = solver.solve(b)
        assert np.linalg.norm(A @ x - b) <= 1e-7 * np.linalg.norm(b)


@pytest.mark.parametrize(
    "name",
    [p for p in SOLVERS if p.values[0] in ("pardiso", "cholmod")],
)
def test_direct_solvers_refuse_indefinite_matrices(name):
    _, model, acc = newton_system(2, 6)
    solver, _ = make_linear_solver(name, model.n_dofs, 2)
    solver.factorize(model.pattern.matrix(acc.hessian))  # SPD: fine
    data = acc.hessian.copy()
    data[model.pattern.diagonal[7]] = -abs(data[model.pattern.diagonal[7]]) * 10
    with pytest.raises(NotPositiveDefiniteError):
        solver.factorize(model.pattern.matrix(data))


@pytest.mark.parametrize("dim", [2, 3])
def test_rigid_body_modes_span_the_null_space_at_rest(dim):
    mesh = rectangle(divisions=(4, 3)) if dim == 2 else box(divisions=(2, 2, 2))
    model = Model(mesh, NeoHookean(youngs_modulus=1e3, poisson_ratio=0.3), 1.0)
    K = model.pattern.matrix(model.evaluate(mesh.points.ravel(), 2, False).hessian)
    B = rigid_body_modes(mesh.points)
    assert B.shape == (mesh.n_points * dim, 3 if dim == 2 else 6)
    assert np.linalg.matrix_rank(B) == B.shape[1]
    assert np.abs(K @ B).max() < 1e-10 * abs(K).max()


@pytest.mark.skipif(not linear.has_pyamg(), reason="pyamg not installed")
def test_amg_hierarchy_is_lagged_and_rebuilt_when_stale():
    mesh, model, acc = newton_system(3, 5)
    solver = CGSolver("amg", points=mesh.points, rebuild_growth=2.0)
    b = -acc.gradient
    for scale in (1.0, 1.01, 0.99):  # nearly the same matrix: one hierarchy serves all
        solver.factorize(model.pattern.matrix(acc.hessian * scale))
        solver.solve(b)
    assert solver.stats.setups == 1 and solver.stats.solves == 3
    # a very different SPD matrix, D A D with D jumping by 1e3 across the body, makes the
    # old hierarchy stale
    D = np.where(np.repeat(mesh.points[:, 0], 3) > 0.5, 1e3, 1.0)
    rows = np.repeat(np.arange(model.pattern.n), np.diff(model.pattern.indptr))
    A = model.pattern.matrix(acc.hessian * D[rows] * D[model.pattern.indices])
    solver.factorize(A)
    x = solver.solve(b)
    assert np.linalg.norm(A @ x - b) <= 1e-7 * np.linalg.norm(b)
    assert solver.stats.setups == 2
    always = CGSolver("amg", points=mesh.points, rebuild_growth=1.0)
    for _ in range(2):
        always.factorize(model.pattern.matrix(acc.hessian))
        always.solve(b)
    assert always.stats.setups == 2


@pytest.mark.skipif(not linear.has_pyamg(), reason="pyamg not installed")
def test_rigid_body_modes_cut_amg_iterations():
    mesh, model, acc = newton_system(3, 6)
    A, b = model.pattern.matrix(acc.hessian), -acc.gradient
    counts = []
    for points in (None, mesh.points):
        solver = CGSolver("amg", points=points)
        solver.factorize(A)
        solver.solve(b)
        counts.append(solver.stats.iterations)
    assert counts[1] < 0.6 * counts[0]


def test_automatic_choice_and_its_reason(monkeypatch):
    for flag in ("has_pardiso", "has_cholmod", "has_pyamg"):
        monkeypatch.setattr(linear, flag, lambda: False)
    solver, reason = make_linear_solver("auto", 1000, 2)
    assert solver.name == "splu" and "SuperLU" in reason
    solver, reason = make_linear_solver("auto", 10**6, 3)
    assert solver.name == "cg+jacobi" and "no pyamg" in reason
    # mid-size 3D FEM without a fast direct solver: CG (benchmarks/solver_choice.py), not SuperLU
    vertices = np.zeros((6_000 // 3, 3))
    solver, reason = make_linear_solver("auto", 6_000, 3, vertices)
    assert solver.name == "cg+jacobi" and "beats SuperLU" in reason
    solver, _ = make_linear_solver("auto", 900, 3, np.zeros((300, 3)))
    assert solver.name == "splu"  # tiny 3D: SuperLU is as fast and exact
    solver, _ = make_linear_solver("auto", 6_000, 3)  # no vertices (frames): SuperLU
    assert solver.name == "splu"
    monkeypatch.setattr(linear, "has_pyamg", lambda: True)
    solver, reason = make_linear_solver("auto", 10**6, 3, np.zeros((10**6 // 3, 3)))
    assert solver.name == "cg+amg" and "pyamg" in reason
    solver, reason = make_linear_solver("auto", 6_000, 3, vertices)
    assert solver.name == "cg+amg" and "beats SuperLU" in reason
    # several bodies (no vertices for the rigid-body modes): AMG only without a direct solver
    solver, reason = make_linear_solver("auto", 10**5, 3)
    assert solver.name == "cg+amg" and "several bodies" in reason
    monkeypatch.setattr(linear, "has_cholmod", lambda: True)
    monkeypatch.setattr(linear, "CholmodSolver", linear.SuperLUSolver)  # stands in for it
    solver, reason = make_linear_solver("auto", 10**5, 3)
    assert "cholmod available" in reason
    solver, reason = make_linear_solver("auto", 10**5, 3, np.zeros((10**5 // 3, 3)))
    assert solver.name == "cg+amg"  # one body: its rigid-body modes, AMG-CG
    monkeypatch.setattr(linear, "has_cholmod", lambda: False)
    # nearly incompressible (nu = 0.49: lambda/mu = 49): CG would crawl, a direct solver at any size
    solver, reason = make_linear_solver("auto", 10**5, 3, vertices, volumetric_ratio=49.0)
    assert solver.name == "splu" and "nearly incompressible" in reason
    solver, reason = make_linear_solver("auto", 10**5, 3, vertices, volumetric_ratio=9.0)
    assert solver.name == "cg+amg"  # nu = 0.45: lambda/mu = 9, CG still fine
    solver, reason = make_linear_solver("auto", 10**5, 3, vertices, quadratic=True)
    assert solver.name == "splu" and "quadratic" in reason
    with pytest.raises(ValueError, match="linear_solver must be one of"):
        make_linear_solver("umfpack", 10, 2)
    with pytest.raises(ValueError, match=r"tissuesim\[fast\]"):
        make_linear_solver("pardiso", 10, 2)
    with pytest.raises(ValueError, match="libsuitesparse-dev"):
        make_linear_solver("cholmod", 10, 2)


def test_superlu_matches_dense_solve():
    _, model, acc = newton_system(2, 5)
    A = model.pattern.matrix(acc.hessian)
    solver, _ = make_linear_solver("splu", model.n_dofs, 2)
    solver.factorize(A)
    solver.factorize(A)  # second time: reuses the ordering
    x = solver.solve(-acc.gradient)
    np.testing.assert_allclose(x, np.linalg.solve(A.toarray(), -acc.gradient), rtol=1e-8)
    assert sp.issparse(A)


def test_superlu_reused_ordering_has_the_fill_of_a_fresh_one():
    """The second factorisation reuses the first one's fill-reducing ordering: it must be the
    same ordering (fill within 1 %), not its inverse (which multiplied the fill on a 3D mesh)."""
    _, model, acc = newton_system(3, 6)
    rng = np.random.default_rng(0)
    n = model.n_dofs
    shuffle = rng.permutation(n)  # a numbering far from any good ordering
    A = model.pattern.matrix(acc.hessian).tocsr()[shuffle][:, shuffle]
    solver, _ = make_linear_solver("splu", n, 3)
    solver.factorize(A)
    fresh = solver._lu.L.nnz + solver._lu.U.nnz
    solver.factorize(A)
    reused = solver._lu.L.nnz + solver._lu.U.nnz
    assert reused <= 1.01 * fresh
    b = -acc.gradient[shuffle]
    np.testing.assert_allclose(A @ solver.solve(b), b, atol=1e-9 * np.abs(b).max())


def test_superlu_pivots_on_the_diagonal_and_reports_a_singular_matrix_as_not_definite():
    """Newton's matrix is SPD (shifted when not): SuperLU keeps diagonal pivots, so a stiff
    entry does not pull pivots off the diagonal, and an exactly singular matrix is a
    NotPositiveDefiniteError, which makes Newton shift the matrix, not a crash."""
    import scipy.sparse as sp

    from tissuesim.solve.linear import NotPositiveDefiniteError, SuperLUSolver

    rng = np.random.default_rng(0)
    B = sp.random(60, 60, density=0.1, random_state=1)
    A = (B @ B.T + sp.identity(60) * 1e-3).tocsr()
    A[3, 3] += 1e9  # a stiff entry, as a barrier or a near-incompressible volume gives
    solver = SuperLUSolver()
    solver.factorize(A.tocsr())
    b = rng.standard_normal(60)
    x = solver.solve(b)
    assert np.linalg.norm(A @ x - b) <= 1e-6 * np.linalg.norm(b)
    with pytest.raises(NotPositiveDefiniteError):
        SuperLUSolver().factorize(sp.csr_matrix(np.array([[1.0, 1.0], [1.0, 1.0]])))


def _spd_matrix(n: int, seed: int) -> sp.csr_matrix:
    rng = np.random.default_rng(seed)
    B = sp.random(n, n, density=0.05, random_state=rng)
    return (B @ B.T + sp.eye(n) * n * 0.1).tocsr()


def _local_update(n: int, dofs: np.ndarray, seed: int) -> sp.csr_matrix:
    """A PSD matrix over ``dofs`` only (contact's Hessian: a few vertices, stiff)."""
    rng = np.random.default_rng(seed)
    L = rng.standard_normal((len(dofs), 3))
    block = 1e3 * (L @ L.T)
    rows, cols = np.meshgrid(dofs, dofs, indexing="ij")
    return sp.csr_matrix((block.ravel(), (rows.ravel(), cols.ravel())), shape=(n, n))


def test_a_reused_factor_applies_a_local_update_by_woodbury_without_refactorising():
    from tissuesim.solve.reuse import ReusedFactorSolver

    n = 80
    K = _spd_matrix(n, 1)
    b = np.random.default_rng(2).standard_normal(n)
    solver = ReusedFactorSolver(SuperLUSolver(), woodbury=True)
    C1 = _local_update(n, np.array([3, 4, 5, 40]), 3)
    solver.factorize((K + C1).tocsr(), update=C1)
    x = solver.solve(b)  # factorises K alone, applies C1 by Woodbury: exact
    assert np.allclose((K + C1) @ x, b, rtol=0, atol=1e-10 * np.linalg.norm(b))
    assert solver.stats.factorizations == 1 and not solver.factor_holds_update
    assert np.allclose(solver.factored_matrix.toarray(), K.toarray())
    # the contact moves to other DOFs and stiffens: the factor is kept, CG preconditioned
    # with K + C2 converges at once (a factor holding C1 failed CG and was made again)
    C2 = _local_update(n, np.array([4, 5, 6, 7, 70]), 4)
    solver.factorize((K + 1.001 * C2).tocsr(), update=1.001 * C2)
    x = solver.solve(b)
    assert np.allclose((K + 1.001 * C2) @ x, b, rtol=0, atol=1e-5 * np.linalg.norm(b))
    assert solver.stats.factorizations == 1 and solver.stats.cg_iterations <= 2
    plain = ReusedFactorSolver(SuperLUSolver())  # SuperLU: no Woodbury by default
    plain.factorize((K + C1).tocsr())
    plain.solve(b)
    plain.factorize((K + 1.001 * C2).tocsr())
    plain.solve(b)
    assert plain.stats.factorizations == 2


def test_a_reused_factor_takes_a_too_large_update_into_the_factor(monkeypatch):
    from tissuesim.solve import reuse

    monkeypatch.setattr(reuse, "MAX_UPDATE_DOFS", 3)
    n = 40
    K = _spd_matrix(n, 5)
    C = _local_update(n, np.array([1, 2, 3, 4, 5]), 6)
    solver = reuse.ReusedFactorSolver(SuperLUSolver(), woodbury=True)
    solver.factorize((K + C).tocsr(), update=C)
    b = np.ones(n)
    x = solver.solve(b)
    assert solver.factor_holds_update
    assert np.allclose((K + C) @ x, b, atol=1e-10)


def test_the_kept_factor_columns_are_bounded(monkeypatch):
    from tissuesim.solve import reuse

    monkeypatch.setattr(reuse, "MAX_KEPT_COLUMNS", 5)
    n = 30
    K = _spd_matrix(n, 8)
    solver = SuperLUSolver()
    solver.factorize(K)
    columns = reuse.FactorColumns()
    inverse = np.linalg.inv(K.toarray())
    columns.take(solver.solve, n, np.array([1, 2, 3]))
    X = columns.take(solver.solve, n, np.array([4, 5, 6]))  # 6 > 5: the old ones let go
    assert len(columns.slot) == 3 and columns.solved == 3
    assert np.allclose(X, inverse[:, [4, 5, 6]], atol=1e-12)


def test_a_stale_factor_is_replaced_once_its_extra_iterations_cost_a_fresh_one():
    from tissuesim.solve import reuse

    n = 60
    K = _spd_matrix(n, 9)
    drift = sp.diags(np.random.default_rng(10).uniform(0.5, 1.5, n) * n * 0.1)
    b = np.ones(n)

    def run(refactor_after: int) -> tuple[list[int], list[np.ndarray]]:
        solver = reuse.ReusedFactorSolver(SuperLUSolver(), max_cg=50)
        solver.refactor_after = refactor_after
        made, solutions = [], []
        for k in range(12):  # a matrix drifting away from the first factor's
            A = (K + 0.15 * k * drift).tocsr()
            solver.factorize(A)
            x = solver.solve(b)
            assert np.allclose(A @ x, b, rtol=0, atol=1e-5 * np.linalg.norm(b))
            made.append(solver.stats.factorizations)
            solutions.append(x)
        return made, solutions

    never, _ = run(10**9)
    assert never[-1] == 1  # CG on the first factor all along
    ruled, solutions = run(4)
    assert 1 < ruled[-1] < 12  # refreshed, but not every solve
    again, repeated = run(4)  # counts, not timings: the same schedule, the same bits
    assert again == ruled
    assert all(np.array_equal(x, y) for x, y in zip(solutions, repeated, strict=True))


def test_a_factor_refreshed_in_a_background_thread_is_swapped_in_when_ready():
    """``background=True``: once the kept factor costs extra CG iterations, a fresh one is
    made in a thread while the solves go on with the old one (each to the tolerance), and it
    is swapped in at the next matrix after it is ready; the factor it replaces is kept as the
    spare for the next one."""
    from tissuesim.solve import reuse

    n = 60
    K = _spd_matrix(n, 9)
    drift = sp.diags(np.random.default_rng(10).uniform(0.5, 1.5, n) * n * 0.1)
    b = np.ones(n)
    solver = reuse.ReusedFactorSolver(SuperLUSolver(), max_cg=50, background=True)
    versions = []
    for k in range(12):
        A = (K + 0.15 * k * drift).tocsr()
        solver.factorize(A)
        x = solver.solve(b)
        assert np.linalg.norm(A @ x - b) <= 1.01e-6 * np.linalg.norm(b)
        job = solver._background[2]
        if job is not None:
            job.result()  # ready before the next matrix: swapped in there
        versions.append(solver.version)
    assert versions[-1] > 2  # fresh factors came from the thread
    assert solver.stats.factorizations == versions[-1]
    kept, spare = solver.direct, solver._background[1]
    assert spare is not None and spare is not kept


@pytest.mark.skipif(not linear.has_pardiso(), reason="needs pypardiso")
def test_a_pardiso_solver_let_go_of_frees_its_memory():
    """PARDISO's memory is not Python's: the solver's finalizer frees it. It held the solver
    itself, so no PardisoSolver was ever collected (FEBio's solver makes one per stiffness
    reformation: 17 GB in FEBio's co40 before the run was killed)."""
    import gc

    from tissuesim.solve.linear import PardisoSolver

    A = sp.diags([-1.0, 2.5, -1.0], [-1, 0, 1], shape=(30, 30)).tocsr()
    solver = PardisoSolver()
    solver.factorize(A)
    assert np.allclose(A @ solver.solve(np.ones(30)), 1.0)
    release = solver._finalizer
    del solver
    gc.collect()
    assert not release.alive
