"""SuperLU factorisation time and fill against nu: partial pivoting versus the diagonal pivoting
tissuesim uses, on the Hessian Newton factorises for a plane-strain Cook's membrane.

The Hessian (neo-Hookean, mu = 80.194, clamped edge removed) of an n x n Cook mesh (2 n^2
triangles; n = 100: 20,000), at rest and at the loaded solution (100 N, 4 load steps), is
factorised by

  * SciPy's default ``splu(A)``: COLAMD ordering, partial pivoting (DiagPivotThresh = 1),
  * tissuesim before issue 14: MMD on A^T + A, SymmetricMode, DiagPivotThresh = 1, and
  * tissuesim's ``SuperLUSolver`` now (``solve/linear.py``): the same with DiagPivotThresh = 0
    (the matrix is symmetric positive definite, shifted when it is not).

Medians of ``--repeats`` runs (the default path at most once per nu when it takes > 20 s).

    python3 benchmarks/superlu_pivoting.py --divisions 100 --nu 0.3 0.45 0.49 0.499 0.4999
writes benchmarks/results/superlu_pivoting.md.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np
import scipy.sparse.linalg as spla

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))
sys.path.insert(0, str(ROOT / "benchmarks"))

from cook_membrane import MU, cook_mesh  # noqa: E402

from tissuesim.materials.registry import make_material  # noqa: E402
from tissuesim.model import Model  # noqa: E402
from tissuesim.solve.linear import SuperLUSolver  # noqa: E402


def free_hessian(
    n: int, nu: float, order: int = 1, formulation: str = "displacement", loaded: bool = False
):
    mesh = cook_mesh(n)
    if order == 2:
        from tissuesim.mesh.cells.elevate import elevate_mesh

        mesh = elevate_mesh(mesh)
    material = make_material("neo_hookean", youngs_modulus=2 * MU * (1 + nu), poisson_ratio=nu)
    model = Model(mesh, material, np.ones(mesh.n_cells), backend="numpy", formulation=formulation)
    x = mesh.points.ravel()
    if loaded:
        from cook_membrane import solve

        x = solve(mesh, material, formulation, 100.0, 4).ravel()
    H = model.pattern.matrix(model.evaluate(x, 2, False).hessian)
    clamped = np.flatnonzero(mesh.points[:, 0] < 1e-9)
    fixed = np.zeros(model.n_dofs, bool)
    fixed[(clamped[:, None] * 2 + np.arange(2)).ravel()] = True
    free = np.flatnonzero(~fixed)
    return H[free][:, free].tocsr(), mesh.n_cells


def timed(fn, repeats: int, slow: float = 20.0):
    times, out = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
        if times[-1] > slow:
            break
    return statistics.median(times), len(times), out


def capped(A, repeats: int, limit: float, **kwargs) -> str:
    """'seconds (runs) | fill' of splu(A, **kwargs) in a child process, or '> limit s' when it
    has not finished by then (partial pivoting can take minutes)."""
    import multiprocessing as mp

    ctx = mp.get_context("fork")
    queue = ctx.Queue()

    def child():
        t, k, lu = timed(lambda: spla.splu(A.tocsc(), **kwargs), repeats)
        queue.put(f"{t:.3f} ({k}) | {(lu.L.nnz + lu.U.nnz) / 1e6:.2f}")

    proc = ctx.Process(target=child)
    proc.start()
    proc.join(limit)
    if proc.is_alive():
        proc.terminate()
        proc.join()
        return f"> {limit:.0f} | -"
    return queue.get()


def factorisations(A, cells, state, nu, order, form, repeats, limit=120.0) -> str:
    """One table row: the three factorisations of A."""
    default = capped(A, repeats, limit)
    before = capped(A, repeats, limit, permc_spec="MMD_AT_PLUS_A", options={"SymmetricMode": True})
    solver = SuperLUSolver()

    def ours():
        solver._perm = None  # a fresh analysis each time, as the first Newton iteration
        solver.factorize(A)
        return solver._lu

    t_ours, k_ours, lu2 = timed(ours, repeats)
    fill_ours = lu2.L.nnz + lu2.U.nnz
    b = np.ones(A.shape[0])
    residual = np.linalg.norm(A @ solver.solve(b) - b) / np.linalg.norm(b)
    label = f"P{order}" + (" mean dilatation" if form == "mean_dilatation" else "")
    row = (
        f"| {state} | {nu} | {label} | {cells} | {A.shape[0]} | {default} | {before} "
        f"| {t_ours:.3f} ({k_ours}) | {fill_ours / 1e6:.2f} | {residual:.1e} |"
    )
    return row


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--divisions", type=int, default=100)
    ap.add_argument("--nu", type=float, nargs="+", default=[0.3, 0.45, 0.49, 0.499, 0.4999])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--out", default=str(ROOT / "benchmarks/results/superlu_pivoting.md"))
    args = ap.parse_args(argv)
    rows = []
    cases = [(nu, 1, "displacement") for nu in args.nu]
    cases += [(args.nu[-1], 1, "mean_dilatation"), (args.nu[-1], 2, "mean_dilatation")]
    for state, nu, order, form in [("rest", *c) for c in cases] + [("loaded", *c) for c in cases]:
        n = args.divisions if order == 1 else args.divisions // 2
        A, cells = free_hessian(n, nu, order, form, loaded=state == "loaded")
        rows.append(factorisations(A, cells, state, nu, order, form, args.repeats))
        print(rows[-1], flush=True)
    text = [
        "# SuperLU on Cook's membrane Hessians: partial vs diagonal pivoting",
        "",
        f"`python3 benchmarks/superlu_pivoting.py --divisions {args.divisions} --nu "
        f"{' '.join(map(str, args.nu))} --repeats {args.repeats}`",
        "",
        "Seconds per factorisation (median; runs in brackets; '> 120': stopped after 120 s), "
        "fill = nnz(L) + nnz(U) in millions.",
        "P2 rows use n/2 divisions (about the same DOFs); residual |A x - b| / |b| of tissuesim's.",
        "",
        "| state | nu | element | cells | DOFs | SciPy default s | fill | before s | fill | "
        "tissuesim s | fill | residual |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
        *rows,
        "",
    ]
    Path(args.out).write_text("\n".join(text))
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
