"""One Newton iteration of compressible Neo-Hookean P1 elasticity in peer FEM libraries.

For a mesh given as ``points`` (n, d) and ``cells`` (m, d + 1) (P1 triangles in plane strain or P1
tetrahedra) and a displacement ``u`` (n, d), each function times the three parts of one Newton
iteration of the library as its documentation recommends:

* ``assembly_vector``: the internal force vector (gradient of the total elastic energy w.r.t. the
  nodal positions), dense, vertex-major (dof a*d + i);
* ``assembly_matrix``: the tangent stiffness matrix as a scipy sparse matrix;
* ``solve``: the Newton step on the free DOFs, ``K11 du1 = -r1`` (du = 0 on ``fixed_dofs``), with
  ``scipy.sparse.linalg.spsolve`` for both peers (SuperLU with COLAMD ordering unless
  scikit-umfpack is installed; FElupe's ``fem.solve.solve`` and scikit-fem's ``skfem.solve``
  both default to it). Partitioning/condensing the system is part of ``solve``.

The energy is the standard compressible Neo-Hookean law (the one of ``tissuesim.NeoHookean``)

    psi = mu/2 (I1 - 3) - mu ln J + lam/2 (ln J)^2

in 3D and in 2D plane strain (F33 = 1, so I1 = |F_2x2|^2 + 1 and J = det F_2x2). Per unit
thickness in 2D. Each function returns medians over ``repeat`` iterations at the same state (the
state is not updated, so every repetition does the same work) plus the one-time ``setup`` (mesh,
region/basis, field construction). The peers are optional: ``pip install felupe scikit-fem``.

Run ``python benchmarks/peers.py`` for a small 2D and 3D demo; ``--sizes`` for the benchmark sizes.
"""

from __future__ import annotations

import statistics
import time
from typing import Any

import numpy as np

__all__ = ["felupe_iteration", "skfem_iteration", "benchmark_state"]

_INSTALL = "pip install felupe scikit-fem"


def _import_felupe():
    try:
        import felupe
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise ImportError(
            f"the FElupe peer benchmark needs FElupe, which is not installed ({exc}); "
            f"install the optional peers with `{_INSTALL}`"
        ) from exc
    return felupe


def _import_skfem():
    try:
        import skfem
        import skfem.helpers
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise ImportError(
            f"the scikit-fem peer benchmark needs scikit-fem, which is not installed ({exc}); "
            f"install the optional peers with `{_INSTALL}`"
        ) from exc
    return skfem


def _check(points, cells, u, fixed_dofs):
    points = np.ascontiguousarray(points, dtype=float)
    cells = np.ascontiguousarray(cells, dtype=np.int64)
    n, d = points.shape
    if d not in (2, 3) or cells.ndim != 2 or cells.shape[1] != d + 1:
        raise ValueError(
            f"expected points (n, 2) with triangles (m, 3) or points (n, 3) with tetrahedra "
            f"(m, 4); got points {points.shape}, cells {cells.shape}"
        )
    u = np.ascontiguousarray(u, dtype=float).reshape(n, d)
    fixed = np.unique(np.asarray(fixed_dofs, dtype=np.int64).ravel())
    if fixed.size and (fixed[0] < 0 or fixed[-1] >= n * d):
        raise ValueError(f"fixed_dofs must lie in [0, {n * d}); got {fixed[[0, -1]]}")
    free = np.setdiff1d(np.arange(n * d, dtype=np.int64), fixed)
    return points, cells, u, fixed, free


def _spsolve():
    from scipy.sparse.linalg import spsolve

    try:  # spsolve uses UMFPACK when scikit-umfpack is importable (use_umfpack=True default)
        import scikits.umfpack  # noqa: F401

        name = "scipy.sparse.linalg.spsolve (UMFPACK via scikit-umfpack)"
    except ImportError:
        name = "scipy.sparse.linalg.spsolve (SuperLU, COLAMD)"
    return spsolve, name


def _result(times: dict[str, list[float]], setup: float, version: str, gradient, solver: str):
    out: dict[str, Any] = {k: statistics.median(v) for k, v in times.items()}
    parts = zip(times["assembly_vector"], times["assembly_matrix"], times["solve"], strict=True)
    out["total"] = statistics.median([a + b + c for a, b, c in parts])
    out["setup"] = setup
    out["version"] = version
    out["gradient"] = gradient
    out["solver"] = solver
    return out


def felupe_iteration(
    points: np.ndarray,
    cells: np.ndarray,
    mu: float,
    lam: float,
    u: np.ndarray,
    fixed_dofs: np.ndarray,
    repeat: int = 3,
    *,
    return_system: bool = False,
    solver: str = "spsolve",
    solve: bool = True,
) -> dict:
    """Time one FElupe Newton iteration; medians in seconds (see the module docstring).

    solver: "spsolve" (FElupe's default) or "pardiso" (``pypardiso.spsolve``, the fast solver
    FElupe's docs suggest; its cached factorisation is dropped before every solve so that each
    repetition really factorises). solve=False times the assembly only (solve reported as NaN).

    API: ``fem.Mesh`` -> ``fem.RegionTriangle``/``fem.RegionTetra`` (their default 1-point
    quadrature, exact for P1) -> ``fem.FieldPlaneStrain(region, dim=2)`` in 2D or
    ``fem.Field(region, dim=3)`` in 3D, as a ``FieldContainer`` -> ``fem.SolidBody`` with
    ``fem.NeoHookeCompressible(mu, lmbda)``, whose energy is exactly
    mu/2 (tr C - 3) - mu ln J + lam/2 ln(J)^2 (``fem.NeoHooke`` is the isochoric-volumetric
    split, a different law). The iteration follows ``fem.newtonrhapson``:
    ``solid.assemble.vector(field)`` (kinematics + stress + integration, converted to a dense
    vector as ``newtonrhapson`` does), ``solid.assemble.matrix()`` (reuses the kinematics), then
    ``fem.solve.partition`` + ``fem.solve.solve(..., solver=spsolve)``.

    With ``return_system=True`` the result also holds "matrix" (the tangent, scipy CSR,
    vertex-major) and "step" (the Newton step du, (n*d,)).
    """
    fem = _import_felupe()
    points, cells, u, fixed, free = _check(points, cells, u, fixed_dofs)
    d = points.shape[1]
    spsolve, solver_name = _spsolve()
    if solver == "pardiso":
        import pypardiso

        def spsolve(A, b):  # noqa: F811 - the pardiso variant
            pypardiso.ps.remove_stored_factorization()
            return pypardiso.spsolve(A, b)

        solver_name = "pypardiso.spsolve (MKL PARDISO)"

    t0 = time.perf_counter()
    if d == 2:
        mesh = fem.Mesh(points, cells, "triangle")
        region = fem.RegionTriangle(mesh)
        field = fem.FieldContainer([fem.FieldPlaneStrain(region, dim=2)])
    else:
        mesh = fem.Mesh(points, cells, "tetra")
        region = fem.RegionTetra(mesh)
        field = fem.FieldContainer([fem.Field(region, dim=3)])
    field[0].values[:] = u
    solid = fem.SolidBody(fem.NeoHookeCompressible(mu=mu, lmbda=lam), field)
    setup = time.perf_counter() - t0

    times: dict[str, list[float]] = {"assembly_vector": [], "assembly_matrix": [], "solve": []}
    for _ in range(max(1, int(repeat))):
        t0 = time.perf_counter()
        r = solid.assemble.vector(field).toarray()[:, 0]
        t1 = time.perf_counter()
        K = solid.assemble.matrix()
        t2 = time.perf_counter()
        if solve:
            system = fem.solve.partition(field, K, free, fixed, r)
            u0 = system[1]  # current prescribed values: ext0 = u0 keeps them fixed (du = 0 there)
            du = fem.solve.solve(*system, ext0=u0, solver=spsolve)
        t3 = time.perf_counter() if solve else t2 + float("nan")
        times["assembly_vector"].append(t1 - t0)
        times["assembly_matrix"].append(t2 - t1)
        times["solve"].append(t3 - t2)

    out = _result(times, setup, fem.__version__, np.asarray(r, dtype=float), solver_name)
    if return_system:
        out["matrix"] = K.tocsr()
        out["step"] = np.asarray(du, dtype=float).ravel()
    return out


def _skfem_material(helpers, grad_u: np.ndarray, mu: float, lam: float):
    """F, ln J, F^-T at the quadrature points from grad u of shape (d, d, m, q)."""
    d = grad_u.shape[0]
    F = grad_u + np.eye(d).reshape(d, d, 1, 1)
    J = helpers.det(F)
    FinvT = helpers.transpose(helpers.inv(F))
    return F, np.log(J), FinvT


def _skfem_stress(F, lnJ, FinvT, mu, lam):
    # P = dpsi/dF = mu F + (lam ln J - mu) F^-T
    return mu * F + (lam * lnJ - mu) * FinvT


def _skfem_tangent(F, lnJ, FinvT, mu, lam):
    # A_ijkl = d2psi/dF_ij dF_kl
    #        = mu d_ik d_jl + lam G_ij G_kl - (lam ln J - mu) G_il G_kj,  G = F^-T
    d = F.shape[0]
    eye = np.eye(d)
    A = lam * np.einsum("ij...,kl...->ijkl...", FinvT, FinvT)
    A -= (lam * lnJ - mu) * np.einsum("il...,kj...->ijkl...", FinvT, FinvT)
    A += mu * np.einsum("ik,jl->ijkl", eye, eye)[..., None, None]
    return A


def skfem_iteration(
    points: np.ndarray,
    cells: np.ndarray,
    mu: float,
    lam: float,
    u: np.ndarray,
    fixed_dofs: np.ndarray,
    repeat: int = 3,
    *,
    return_system: bool = False,
    inline: bool = False,
    intorder: int = 1,
    solve: bool = True,
) -> dict:
    """Time one scikit-fem Newton iteration; medians in seconds (see the module docstring).

    API: ``skfem.MeshTri``/``MeshTet(points.T, cells.T)`` -> ``skfem.Basis(mesh,
    ElementVector(ElementTriP1()/ElementTetP1()), intorder=1)`` (1 point per cell, exact for P1;
    the default intorder=2 would use 3/4 points for the same result) -> the displacement
    interpolated with ``basis.interpolate(u)`` -> ``asm(LinearForm)`` and ``asm(BilinearForm)``
    written with ``skfem.helpers`` (grad, det, inv, transpose, ddot), following the hyperelastic
    example (docs/examples/ex36.py) with the compressible Neo-Hookean law above -> ``skfem.solve(
    *skfem.condense(K, -r, D=fixed_dofs))`` (its default solver, ``solver_direct_scipy``, is
    ``scipy.sparse.linalg.spsolve``). Plane strain needs no extra term: with F33 = 1 the 2x2
    forms are exact.

    ``inline=False`` (default) evaluates P and the tangent A once per iteration at the quadrature
    points and passes them to the forms as extra arrays (w["P"], w["A"]); ``inline=True``
    evaluates the material inside the forms as ex36 does, which scikit-fem repeats for each of
    the (d(d+1))^2 local basis-function pairs of the bilinear form (much slower).

    ElementVector numbers nodal DOFs interleaved (2a, 2a+1 / 3a, 3a+1, 3a+2), i.e. vertex-major,
    so no reordering is needed. With ``return_system=True`` the result also holds "matrix"
    (scipy CSR) and "step" (the Newton step du, (n*d,)).
    """
    skfem = _import_skfem()
    from skfem.helpers import ddot, grad

    helpers = skfem.helpers
    points, cells, u, fixed, free = _check(points, cells, u, fixed_dofs)
    d = points.shape[1]
    _, solver_name = _spsolve()  # skfem.solver_direct_scipy() calls the same spsolve

    if inline:

        @skfem.LinearForm
        def internal_force(v, w):
            F, lnJ, FinvT = _skfem_material(helpers, grad(w["u"]), mu, lam)
            return ddot(_skfem_stress(F, lnJ, FinvT, mu, lam), grad(v))

        @skfem.BilinearForm
        def tangent(du, v, w):
            F, lnJ, FinvT = _skfem_material(helpers, grad(w["u"]), mu, lam)
            A = _skfem_tangent(F, lnJ, FinvT, mu, lam)
            return np.einsum("ijkl...,kl...,ij...->...", A, grad(du), grad(v))

    else:

        @skfem.LinearForm
        def internal_force(v, w):
            return ddot(w["P"], grad(v))

        @skfem.BilinearForm
        def tangent(du, v, w):
            return np.einsum("ijkl...,kl...,ij...->...", w["A"], grad(du), grad(v))

    t0 = time.perf_counter()
    # (d, n) / (d+1, m) C-contiguous, as scikit-fem stores them (it copies and logs otherwise)
    pT, cT = np.ascontiguousarray(points.T), np.ascontiguousarray(cells.T)
    if d == 2:
        mesh = skfem.MeshTri(pT, cT)
        element = skfem.ElementVector(skfem.ElementTriP1())
    else:
        mesh = skfem.MeshTet(pT, cT)
        element = skfem.ElementVector(skfem.ElementTetP1())
    basis = skfem.Basis(mesh, element, intorder=intorder)
    x = u.ravel().copy()  # interleaved nodal DOFs == vertex-major
    setup = time.perf_counter() - t0

    times: dict[str, list[float]] = {"assembly_vector": [], "assembly_matrix": [], "solve": []}
    for _ in range(max(1, int(repeat))):
        t0 = time.perf_counter()
        uh = basis.interpolate(x)
        if inline:
            r = skfem.asm(internal_force, basis, u=uh)
        else:
            kin = _skfem_material(helpers, grad(uh), mu, lam)
            r = skfem.asm(internal_force, basis, P=_skfem_stress(*kin, mu, lam))
        t1 = time.perf_counter()
        if inline:
            K = skfem.asm(tangent, basis, u=uh)
        else:
            K = skfem.asm(tangent, basis, A=_skfem_tangent(*kin, mu, lam))
        t2 = time.perf_counter()
        if solve:
            du = skfem.solve(*skfem.condense(K, -r, D=fixed), solver=skfem.solver_direct_scipy())
        t3 = time.perf_counter() if solve else t2 + float("nan")
        times["assembly_vector"].append(t1 - t0)
        times["assembly_matrix"].append(t2 - t1)
        times["solve"].append(t3 - t2)

    version = getattr(skfem, "__version__", None)
    if version is None:
        from importlib.metadata import version as _v

        version = _v("scikit-fem")
    out = _result(times, setup, version, np.asarray(r, dtype=float), solver_name)
    if return_system:
        out["matrix"] = K.tocsr()
        out["step"] = np.asarray(du, dtype=float).ravel()
    return out


def benchmark_state(points: np.ndarray, stretch: float = 0.01, wiggle: float = 0.002):
    """A displacement (n, d): ``stretch`` uniaxial stretch along x plus a small smooth
    perturbation, and fixed DOFs (vertex-major) clamping every vertex on the xmin face.

    Deterministic, so every library sees the same state.
    """
    points = np.asarray(points, dtype=float)
    lo, hi = points.min(axis=0), points.max(axis=0)
    X = (points - lo) / np.where(hi > lo, hi - lo, 1.0)
    u = np.zeros_like(points)
    u[:, 0] = stretch * (points[:, 0] - lo[0])
    for i in range(points.shape[1]):
        phase = 1.0 + 0.7 * i
        u[:, i] += (
            wiggle
            * (hi - lo).max()
            * np.sin(np.pi * X[:, 0] + phase)
            * np.cos(2.0 * np.pi * X[:, (i + 1) % points.shape[1]] + phase)
        )
    d = points.shape[1]
    left = np.flatnonzero(np.isclose(points[:, 0], lo[0]))
    u[left] = 0.0
    fixed = (left[:, None] * d + np.arange(d)).ravel()
    return u, fixed


def _demo(sizes: str = "small") -> None:  # pragma: no cover - manual benchmark
    from threadpoolctl import threadpool_limits

    import tissuesim as ts

    if sizes == "small":
        meshes = [
            ("2D rectangle (16,16)", ts.rectangle(divisions=(16, 16))),
            ("3D box (6,6,6)", ts.box(divisions=(6, 6, 6))),
        ]
    else:
        meshes = [
            ("2D rectangle (224,224)", ts.rectangle(divisions=(224, 224))),
            ("3D box (20,20,20)", ts.box(divisions=(20, 20, 20))),
        ]
    mu, lam = 1.0e3, 4.0e3
    keys = ("setup", "assembly_vector", "assembly_matrix", "solve", "total")
    with threadpool_limits(1):
        for title, mesh in meshes:
            u, fixed = benchmark_state(mesh.points)
            print(f"{title}: {mesh.points.shape[0]} points, {mesh.cells.shape[0]} cells")
            for name, fn in (("felupe", felupe_iteration), ("scikit-fem", skfem_iteration)):
                try:
                    res = fn(mesh.points, mesh.cells, mu, lam, u, fixed, repeat=3)
                except ImportError as exc:
                    print(f"  {name}: skipped ({exc})")
                    continue
                cols = "  ".join(f"{k}={res[k]:.4f}s" for k in keys)
                print(f"  {name} {res['version']}: {cols}  [{res['solver']}]")


if __name__ == "__main__":  # pragma: no cover
    import sys

    _demo("large" if "--sizes" in sys.argv[1:] else "small")
