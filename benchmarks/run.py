"""tissuesim performance suite: one Newton iteration, split by phase, against the linear solve
alone and against FElupe and scikit-fem on the same mesh and energy.

    python benchmarks/run.py                      # default sizes
    python benchmarks/run.py --quick              # tiny sizes, a smoke test (CI)
    python benchmarks/run.py --sizes2d 71 224 --sizes3d 12 26 --peers --out benchmarks/results

Each figure is the median of --repeat runs, with BLAS and OpenMP limited to one thread
(threadpoolctl) because the machines have 2 cores and oversubscription distorts timings.
Writes results.json and results.md into --out.
"""

from __future__ import annotations

import argparse
import json
import platform
import resource
import time
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_info, threadpool_limits

import tissuesim as ts
from tissuesim.constraints.dirichlet import DirichletCondition
from tissuesim.energies.loads import ExternalForce
from tissuesim.mesh import select
from tissuesim.model import Model
from tissuesim.solve.linear import make_linear_solver
from tissuesim.solve.newton import NewtonOptions, minimize


def median_time(fn, repeat: int):
    times, out = [], None
    for _ in range(repeat):
        start = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - start)
    return float(np.median(times)), out


def make_mesh(dim: int, n: int):
    if dim == 2:
        return ts.rectangle(lower=(0, 0), upper=(1, 1), divisions=(n, n))
    return ts.box(lower=(0, 0, 0), upper=(1, 1, 1), divisions=(n, n, n))


def deformed_state(mesh):
    """A smooth, non-trivial state: 2 % stretch along x plus a small bending wave."""
    X = mesh.points
    u = np.zeros_like(X)
    u[:, 0] = 0.02 * X[:, 0]
    u[:, 1] = 0.01 * np.sin(np.pi * X[:, 0])
    return u


def newton_iteration_breakdown(dim: int, n: int, solver_name: str, repeat: int) -> dict:
    mesh = make_mesh(dim, n)
    material = ts.NeoHookean(youngs_modulus=1e3, poisson_ratio=0.3)
    start = time.perf_counter()
    model = Model(mesh, material, 1.0)
    left = select.vertices_on_plane(mesh, 0, 0.0)
    model.set_conditions([DirichletCondition(left, lambda X, t: np.zeros_like(X))])
    setup = time.perf_counter() - start
    x = (mesh.points + deformed_state(mesh)).ravel()
    K, pattern = model.kinematics, model.pattern
    t = {}
    t["F"], F = median_time(lambda: K.deformation_gradients(x), repeat)
    t["material"], resp = median_time(lambda: material.evaluate(F, 2), repeat)
    t["local_gradient"], gl = median_time(lambda: K.stress_to_gradient(resp.stress), repeat)
    t["local_hessian"], hl = median_time(lambda: K.tangent_to_hessian(resp.tangent), repeat)

    def scatter():
        data = np.zeros(pattern.nnz)
        pattern.accumulate(data, 0, hl)
        g = np.bincount(K.stencil.ravel(), weights=gl.ravel(), minlength=pattern.n)
        return data, g

    t["scatter"], (data, g) = median_time(scatter, repeat)
    t["elimination"], _ = median_time(lambda: model.elimination.apply(data, g), repeat)
    solver, reason = make_linear_solver(solver_name, model.n_dofs, dim)
    A = pattern.matrix(data)
    solver.factorize(A)  # symbolic analysis, once per mesh (not part of an iteration)

    def solve():
        solver.factorize(A)
        return solver.solve(-g)

    t["linear_solve"], dx = median_time(solve, repeat)
    t["line_search_eval"], _ = median_time(lambda: model.evaluate(x + dx, 1, False), repeat)
    kernels = t["F"] + t["material"] + t["local_gradient"] + t["local_hessian"]

    # The whole iteration as the solver runs it: one Newton iteration of ``minimize``.
    f = np.zeros((mesh.n_points, dim))
    f[select.vertices_on_plane(mesh, 0, 1.0), 1] = -1e-3
    load = ExternalForce(f.ravel())

    def evaluate(y, order, project):
        return model.evaluate(y, order, project, (load,))

    options = NewtonOptions(max_iterations=1, hessian_projection="never")

    def one_iteration():
        return minimize(
            evaluate,
            x,
            model.elimination,
            solver,
            options,
            force_scale=model.force_scale,
            length_scale=model.length_scale,
        )

    whole, (_, record) = median_time(one_iteration, repeat)
    # one_iteration also evaluates the gradient at the start, which a running Newton reuses
    start_eval, _ = median_time(lambda: evaluate(x, 1, False), repeat)
    iteration = whole - start_eval
    other = iteration - kernels - t["scatter"] - t["elimination"] - t["linear_solve"]
    other -= t["line_search_eval"] * len(record.step_lengths)
    return {
        "dim": dim,
        "divisions": n,
        "elements": mesh.n_cells,
        "dofs": model.n_dofs,
        "nnz": pattern.nnz,
        "setup_s": setup,
        "kernels_s": kernels,
        **{f"{k}_s": v for k, v in t.items()},
        "other_s": max(other, 0.0),
        "iteration_s": iteration,
        "solver": solver.name,
        "solver_reason": reason,
        "iteration_over_solve": iteration / t["linear_solve"],
    }


def peak_memory_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def markdown(rows: list[dict], peers: list[dict], command: str) -> str:
    lines = [
        f"Machine: {platform.platform()}, {platform.processor() or 'cpu'}, "
        f"Python {platform.python_version()}, 1 BLAS thread.",
        f"Command: `{command}`",
        "",
        "| dim | elements | DOFs | solver | kernels | scatter | elimination | linear solve | "
        "line search | other | iteration | iteration / solve |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for r in rows:
        lines.append(
            f"| {r['dim']}D | {r['elements']} | {r['dofs']} | {r['solver']} | "
            f"{r['kernels_s']:.3f} | {r['scatter_s']:.3f} | {r['elimination_s']:.4f} | "
            f"{r['linear_solve_s']:.3f} | {r['line_search_eval_s']:.3f} | {r['other_s']:.3f} | "
            f"{r['iteration_s']:.3f} | {r['iteration_over_solve']:.2f} |"
        )
    if peers:
        lines += [
            "",
            "| dim | elements | library | assembly (vector + matrix) | solve | total | "
            "tissuesim assembly | assembly ratio (peer / tissuesim) |",
            "| --- | --- | --- | --- | --- | --- | --- | --- |",
        ]
        for p in peers:
            lines.append(
                f"| {p['dim']}D | {p['elements']} | {p['library']} {p.get('version', '')} | "
                f"{p['assembly_s']:.3f} | {p['solve_s']:.3f} | {p['total_s']:.3f} | "
                f"{p['tissuesim_assembly_s']:.3f} | {p['assembly_ratio']:.1f} |"
            )
    return "\n".join(lines) + "\n"


def run_peers(dim: int, n: int, repeat: int, ours: dict) -> list[dict]:
    import sys

    sys.path.insert(0, str(Path(__file__).parent))
    import peers  # benchmarks/peers.py

    mesh = make_mesh(dim, n)
    material = ts.NeoHookean(youngs_modulus=1e3, poisson_ratio=0.3)
    u = deformed_state(mesh)
    fixed = (select.vertices_on_plane(mesh, 0, 0.0)[:, None] * dim + np.arange(dim)).ravel()
    out = []
    ours_assembly = ours["kernels_s"] + ours["scatter_s"]
    for name, fn in (("felupe", peers.felupe_iteration), ("scikit-fem", peers.skfem_iteration)):
        try:
            r = fn(mesh.points, mesh.cells, material.mu, material.lam, u, fixed, repeat=repeat)
        except ImportError as exc:
            print(f"skipping {name}: {exc}")
            continue
        assembly = r["assembly_vector"] + r["assembly_matrix"]
        out.append(
            {
                "dim": dim,
                "elements": mesh.n_cells,
                "library": name,
                "version": r.get("version", ""),
                "assembly_s": assembly,
                "solve_s": r["solve"],
                "total_s": r["total"],
                "tissuesim_assembly_s": ours_assembly,
                "assembly_ratio": assembly / ours_assembly,
                "tissuesim_iteration_s": ours["iteration_s"],
            }
        )
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--quick", action="store_true", help="tiny sizes, one repeat")
    parser.add_argument("--sizes2d", type=int, nargs="*", default=[71, 224, 500])
    parser.add_argument("--sizes3d", type=int, nargs="*", default=[12, 26, 36])
    parser.add_argument("--solver", default="auto")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--peers", action="store_true", help="also time FElupe and scikit-fem")
    parser.add_argument("--out", default="benchmarks/results")
    args = parser.parse_args()
    if args.quick:
        args.sizes2d, args.sizes3d, args.repeat = [8], [3], 1
    command = (
        "python benchmarks/"
        + Path(__file__).name
        + " "
        + " ".join(a for a in __import__("sys").argv[1:])
    )
    rows, peer_rows = [], []
    with threadpool_limits(1):
        for dim, sizes in ((2, args.sizes2d), (3, args.sizes3d)):
            for n in sizes:
                row = newton_iteration_breakdown(dim, n, args.solver, args.repeat)
                row["peak_rss_mb"] = peak_memory_mb()
                rows.append(row)
                print(
                    f"{dim}D {row['elements']:>8} elements: iteration {row['iteration_s']:.3f} s,"
                    f" solve {row['linear_solve_s']:.3f} s ({row['solver']}), ratio "
                    f"{row['iteration_over_solve']:.2f}",
                    flush=True,
                )
                if args.peers:
                    peer_rows += run_peers(dim, n, args.repeat, row)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    result = {
        "machine": platform.platform(),
        "python": platform.python_version(),
        "threadpools": threadpool_info(),
        "command": command,
        "rows": rows,
        "peers": peer_rows,
    }
    (out / "results.json").write_text(json.dumps(result, indent=2, default=str))
    (out / "results.md").write_text(markdown(rows, peer_rows, command))
    print(markdown(rows, peer_rows, command))


if __name__ == "__main__":
    main()
