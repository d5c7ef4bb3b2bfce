"""tissuesim performance suite: one Newton iteration, split by phase, against the linear solve
alone, against FElupe and scikit-fem on the same mesh and energy, with scaling, memory and
explicit-stepping throughput.

    python benchmarks/run.py                      # the default sizes (about 20 minutes)
    python benchmarks/run.py --quick              # tiny sizes, a smoke test (CI)
    python benchmarks/run.py --sizes2d 71 224 --sizes3d 12 26 --peers --out benchmarks/results

Every measurement runs in its own subprocess with one thread for BLAS, OpenMP, MKL and Numba
(environment variables set before any import, plus threadpoolctl): the machines have 2 cores,
oversubscription distorts timings, and loading MKL (PARDISO) into a process was measured to
slow CHOLMOD's factorisation 1.75x, so solvers are never timed side by side in one process.
A subprocess also gives a clean peak memory. Each figure is the median of --repeat runs.
Writes results.json and results.md into --out.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

THREAD_ENV = {
    "OMP_NUM_THREADS": "1",
    "OPENBLAS_NUM_THREADS": "1",
    "MKL_NUM_THREADS": "1",
    "NUMBA_NUM_THREADS": "1",
}
E, NU, DENSITY = 1e3, 0.3, 1.0


# -- workers (run in subprocesses) ----------------------------------------------------------------
def _rss_mb(field: str) -> float:
    """VmRSS (current) or VmHWM (peak) of this process in MiB, from /proc (Linux)."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith(field + ":"):
            return float(line.split()[1]) / 1024.0
    return float("nan")


def _median_time(fn, repeat: int):
    import numpy as np

    times, out = [], None
    for _ in range(repeat):
        start = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - start)
    return float(np.median(times)), out


def _problem(dim: int, n: int, backend: str = "auto", material: str = "neo_hookean"):
    """Structured mesh, a model clamped at x = 0, a deformed state and an end load."""
    import numpy as np

    import tissuesim as ts
    from tissuesim.constraints.dirichlet import DirichletCondition
    from tissuesim.energies.loads import ExternalForce
    from tissuesim.mesh import select
    from tissuesim.model import Model

    if dim == 2:
        mesh = ts.rectangle(lower=(0, 0), upper=(1, 1), divisions=(n, n))
    else:
        mesh = ts.box(lower=(0, 0, 0), upper=(1, 1, 1), divisions=(n, n, n))
    law = ts.make_material(material, youngs_modulus=E, poisson_ratio=NU)
    start = time.perf_counter()
    model = Model(mesh, law, DENSITY, backend=backend)
    left = select.vertices_on_plane(mesh, 0, 0.0)
    model.set_conditions([DirichletCondition(left, lambda X, t: np.zeros_like(X))])
    setup = time.perf_counter() - start
    X = mesh.points
    u = np.zeros_like(X)  # 2 % stretch along x plus a small bending wave
    u[:, 0] = 0.02 * X[:, 0]
    u[:, 1] = 0.01 * np.sin(np.pi * X[:, 0])
    f = np.zeros((mesh.n_points, dim))
    f[select.vertices_on_plane(mesh, 0, 1.0), 1] = -1e-3
    return mesh, model, u, ExternalForce(f.ravel()), setup


def worker_iteration(
    dim: int,
    n: int,
    backend: str,
    solver_name: str,
    repeat: int,
    material: str = "neo_hookean",
    time_step: float | None = None,
) -> dict:
    """Phases of one Newton iteration and the whole iteration as ``minimize`` runs it.
    time_step: None for a quasistatic iteration, else Backward Euler's (inertia added)."""
    import numpy as np

    from tissuesim.energies.mass import Inertia
    from tissuesim.solve.linear import make_linear_solver
    from tissuesim.solve.newton import NewtonOptions, minimize

    base_rss = _rss_mb("VmRSS")
    mesh, model, u, load, setup = _problem(dim, n, backend, material)
    x = (mesh.points + u).ravel()
    t: dict[str, float] = {}
    energies = (load,)
    if time_step is not None:  # Backward Euler from rest at the undeformed state
        energies += (Inertia(model.mass, mesh.points.ravel().copy(), time_step),)

    def evaluate(y, order, project):
        return model.evaluate(y, order, project, energies)

    evaluate(x, 2, False)  # JIT load / compile outside the timings
    t["assembly"], acc = _median_time(lambda: evaluate(x, 2, False), repeat)
    t["gradient"], _ = _median_time(lambda: evaluate(x, 1, False), repeat)

    def eliminate():
        h, g = acc.hessian.copy(), acc.gradient.copy()
        model.elimination.apply(h, g)
        return h, g

    copy_s, _ = _median_time(lambda: (acc.hessian.copy(), acc.gradient.copy()), repeat)
    t["elimination"], (h, g) = _median_time(eliminate, repeat)
    t["elimination"] = max(t["elimination"] - copy_s, 0.0)
    solver, reason = make_linear_solver(solver_name, model.n_dofs, dim, mesh.points)
    A = model.pattern.matrix(h)
    solver.factorize(A)  # symbolic analysis / AMG hierarchy: once per mesh, not per iteration
    solver.solve(-g)

    def solve():
        solver.factorize(A)
        return solver.solve(-g)

    t["linear_solve"], dx = _median_time(solve, repeat)
    t["line_search_eval"] = t["gradient"]  # a trial point costs one order-1 evaluation

    options = NewtonOptions(max_iterations=1, hessian_projection="never")

    def one_iteration():
        return minimize(evaluate, x, model.elimination, solver, options,
                        force_scale=model.force_scale, length_scale=model.length_scale)  # fmt: skip

    one_iteration()  # warm-up
    whole, (_, record) = _median_time(one_iteration, repeat)
    iteration = whole - t["gradient"]  # minimize's start evaluation, which Newton reuses
    trials = len(record.step_lengths) and int(round(np.log2(1 / record.step_lengths[0]))) + 1
    other = iteration - t["assembly"] - t["elimination"] - t["linear_solve"]
    other -= t["line_search_eval"] * trials
    peak = _rss_mb("VmHWM")
    row = {
        "dim": dim,
        "divisions": n,
        "elements": mesh.n_cells,
        "vertices": mesh.n_points,
        "dofs": model.n_dofs,
        "nnz": model.pattern.nnz,
        "backend": model.backend,
        "material": material,
        "scheme": "quasistatic" if time_step is None else f"backward_euler h={time_step:g}",
        "setup_s": setup,
        **{f"{k}_s": v for k, v in t.items()},
        "line_search_trials": trials,
        "other_s": other,
        "iteration_s": iteration,
        "solver": solver.name,
        "solver_reason": reason,
        "cg_iterations": getattr(getattr(solver, "stats", None), "iterations", None),
        "peak_mb": peak,
        "peak_bytes_per_element": (peak - base_rss) * 2**20 / mesh.n_cells,
    }
    # The NumPy path's kernel/scatter split (after the peak: its temporaries are larger)
    K, pattern, material = model.kinematics, model.pattern, model.material
    s: dict[str, float] = {}
    s["F"], F = _median_time(lambda: K.deformation_gradients(x), repeat)
    s["material"], resp = _median_time(lambda: material.evaluate(F, 2), repeat)
    s["local_gradient"], gl = _median_time(lambda: K.stress_to_gradient(resp.stress), repeat)
    s["local_hessian"], hl = _median_time(lambda: K.tangent_to_hessian(resp.tangent), repeat)

    def scatter():
        data = np.zeros(pattern.nnz)
        pattern.accumulate(data, 0, hl)
        return np.bincount(K.stencil.ravel(), weights=gl.ravel(), minlength=pattern.n)

    s["scatter"], _ = _median_time(scatter, repeat)
    row["numpy_kernels_s"] = s["F"] + s["material"] + s["local_gradient"] + s["local_hessian"]
    row["numpy_scatter_s"] = s["scatter"]
    return row


def worker_solve(dim: int, n: int, solver_name: str, repeat: int) -> dict:
    """One solver alone on the iteration's (eliminated) matrix."""
    import numpy as np

    from tissuesim.solve.linear import make_linear_solver

    base_rss = _rss_mb("VmRSS")
    mesh, model, u, load, _ = _problem(dim, n)
    acc = model.evaluate((mesh.points + u).ravel(), 2, False, (load,))
    model.elimination.apply(acc.hessian, acc.gradient)
    A, b = model.pattern.matrix(acc.hessian), -acc.gradient
    solver, _ = make_linear_solver(solver_name, model.n_dofs, dim, mesh.points)
    start = time.perf_counter()
    solver.factorize(A)
    x = solver.solve(b)
    first = time.perf_counter() - start

    def again():
        solver.factorize(A)
        return solver.solve(b)

    per_iteration, x = _median_time(again, repeat)
    stats = getattr(solver, "stats", None)
    return {
        "solver": solver.name,
        "first_s": first,  # includes the analysis / AMG setup
        "per_iteration_s": per_iteration,  # analysis reused (AMG: hierarchy lagged)
        "residual": float(np.linalg.norm(A @ x - b) / np.linalg.norm(b)),
        "cg_iterations_per_solve": (stats.iterations / stats.solves) if stats else None,
        "peak_mb": _rss_mb("VmHWM") - base_rss,
    }


def worker_peer(dim: int, n: int, library: str, repeat: int, solve: bool) -> dict:
    import numpy as np

    sys.path.insert(0, str(Path(__file__).parent))
    import peers  # benchmarks/peers.py

    from tissuesim.mesh import select

    mesh, model, u, _, _ = _problem(dim, n)
    fixed = (select.vertices_on_plane(mesh, 0, 0.0)[:, None] * dim + np.arange(dim)).ravel()
    mu, lam = model.material.mu, model.material.lam
    if library == "felupe":
        r = peers.felupe_iteration(mesh.points, mesh.cells, mu, lam, u, fixed, repeat, solve=solve)
    elif library == "felupe+pardiso":
        r = peers.felupe_iteration(mesh.points, mesh.cells, mu, lam, u, fixed, repeat,
                                   solver="pardiso", solve=solve)  # fmt: skip
    else:
        r = peers.skfem_iteration(mesh.points, mesh.cells, mu, lam, u, fixed, repeat, solve=solve)
    return {
        "library": library,
        "version": r["version"],
        "assembly_s": r["assembly_vector"] + r["assembly_matrix"],
        "solve_s": r["solve"] if solve else None,
        "total_s": r["total"] if solve else None,
        "peer_solver": r["solver"],
    }


def worker_explicit(dim: int, n: int, steps: int) -> dict:
    """Symplectic Euler at half the CFL step: vertex updates per second."""
    import numpy as np

    import tissuesim as ts
    from tissuesim.time.integrators.stability import critical_time_step

    mesh, model, u, _, _ = _problem(dim, n)
    material = ts.NeoHookean(youngs_modulus=E, poisson_ratio=NU)
    sim = ts.Simulation(mesh, material, density=DENSITY, integrator="symplectic_euler",
                        time_step=1.0)  # fmt: skip
    sim.time_step = 0.5 * critical_time_step(sim.model)
    sim.add_dirichlet(np.flatnonzero(mesh.points[:, 0] == 0.0))
    sim.add_gravity((0.0, -9.81) if dim == 2 else (0.0, -9.81, 0.0))
    sim.step()  # JIT load outside the timing
    start = time.perf_counter()
    for _ in range(steps):
        sim.step()
    elapsed = time.perf_counter() - start
    return {
        "dim": dim,
        "elements": mesh.n_cells,
        "vertices": mesh.n_points,
        "backend": sim.model.backend,
        "steps": steps,
        "time_per_step_s": elapsed / steps,
        "vertex_updates_per_s": mesh.n_points * steps / elapsed,
        "element_updates_per_s": mesh.n_cells * steps / elapsed,
    }


WORKERS = {
    "iteration": worker_iteration,
    "solve": worker_solve,
    "peer": worker_peer,
    "explicit": worker_explicit,
}


# -- driver ---------------------------------------------------------------------------------------
def spawn(kind: str, **kwargs) -> dict:
    """Run one worker in a fresh single-threaded subprocess; its JSON result or an error."""
    env = {**os.environ, **THREAD_ENV}
    cmd = [sys.executable, str(Path(__file__).resolve()), "--worker", kind, json.dumps(kwargs)]
    proc = subprocess.run(cmd, capture_output=True, text=True, env=env)
    if proc.returncode != 0:
        tail = proc.stderr.strip().splitlines()[-3:]
        return {"error": f"{kind} {kwargs} failed: " + " | ".join(tail)}
    return json.loads(proc.stdout.strip().splitlines()[-1])


def candidate_solvers(
    dim: int, dofs: int, max_direct_dofs_3d: int, requested: list[str] | None = None
) -> list[str]:
    from tissuesim.solve import linear

    if requested:
        return requested
    direct_ok = dim == 2 or dofs <= max_direct_dofs_3d
    names = []
    if linear.has_pardiso() and direct_ok:
        names.append("pardiso")
    if linear.has_cholmod() and direct_ok:
        names.append("cholmod")
    if not (linear.has_pardiso() or linear.has_cholmod()) and direct_ok:
        names.append("splu")
    if dim == 3:
        names += (["amg"] if linear.has_pyamg() else []) + ["cg"]
    return names


def fit_exponent(elements: list[int], times: list[float]) -> float | None:
    import numpy as np

    if len(elements) < 2:
        return None
    return float(np.polyfit(np.log(elements), np.log(times), 1)[0])


def markdown(result: dict) -> str:
    rows, peers, explicit = result["rows"], result["peers"], result["explicit"]
    lines = [
        f"Machine: {result['machine']}, Python {result['python']}, one thread for BLAS, "
        f"OpenMP, MKL and Numba. Command: `{result['command']}`",
        "",
        f"Newton iteration ({result['rows'][0].get('material', '')}, "
        f"{result['rows'][0].get('scheme', '')}), seconds (median). `assembly` is energy + "
        "gradient + Hessian into the CSR pattern (with the numba backend, kernels and scatter "
        "are one fused loop; the NumPy path's split is in the last two columns). `best solve` "
        "is the fastest available solver alone on the same matrix, timed in its own process.",
        "",
        "| dim | elements | DOFs | backend | assembly | elimination | linear solve (solver) | "
        "line search | other | iteration | iteration / own solve | best solve (solver) | "
        "iteration / best solve | peak MB | bytes / element | NumPy kernels | NumPy scatter |",
        "| --- " * 17 + "|",
    ]
    for r in rows:
        if "error" in r:
            lines.append(f"| {r.get('dim', '?')}D | error: {r['error']} |")
            continue
        lines.append(
            f"| {r['dim']}D | {r['elements']:,} | {r['dofs']:,} | {r['backend']} | "
            f"{r['assembly_s']:.3f} | {r['elimination_s']:.4f} | "
            f"{r['linear_solve_s']:.3f} ({r['solver']}) | "
            f"{r['line_search_eval_s'] * r['line_search_trials']:.3f} | {r['other_s']:.3f} | "
            f"{r['iteration_s']:.3f} | {r['iteration_s'] / r['linear_solve_s']:.2f} | "
            f"{r['best_solve_s']:.3f} ({r['best_solver']}) | "
            f"**{r['iteration_over_best_solve']:.2f}** | {r['peak_mb']:.0f} | "
            f"{r['peak_bytes_per_element']:.0f} | {r['numpy_kernels_s']:.3f} | "
            f"{r['numpy_scatter_s']:.3f} |"
        )
    lines += ["", "Each solver alone on the same matrix (s; first = with analysis/setup):", ""]
    lines += ["| dim | elements | DOFs | solver | first | per iteration | CG its | peak MB |"]
    lines += ["| --- " * 8 + "|"]
    for r in rows:
        for s in r.get("solves", []):
            if "error" in s:
                lines.append(f"| {r['dim']}D | {r['elements']:,} | | error: {s['error']} |")
                continue
            its = s["cg_iterations_per_solve"]
            lines.append(
                f"| {r['dim']}D | {r['elements']:,} | {r['dofs']:,} | {s['solver']} | "
                f"{s['first_s']:.3f} | {s['per_iteration_s']:.3f} | "
                f"{'' if its is None else f'{its:.0f}'} | {s['peak_mb']:.0f} |"
            )
    if result["scaling"]:
        lines += ["", "Fitted exponent b of time ~ elements^b:", ""]
        lines += ["| dim | sizes | assembly | whole iteration |", "| --- | --- | --- | --- |"]
        for sc in result["scaling"]:
            a, it = sc["assembly_exponent"], sc["iteration_exponent"]
            lines.append(
                f"| {sc['dim']}D | {sc['sizes']} | {'-' if a is None else f'{a:.2f}'} | "
                f"{'-' if it is None else f'{it:.2f}'} |"
            )
    if peers:
        lines += ["", "Peers on the same mesh and energy (seconds):", ""]
        lines += [
            "| dim | elements | library | solver | assembly | solve | total | tissuesim assembly "
            "| tissuesim iteration | assembly ratio (peer / tissuesim) | iteration ratio |",
            "| --- " * 11 + "|",
        ]
        for p in peers:
            if "error" in p:
                lines.append(f"| {p.get('dim', '?')}D | {p.get('elements', '')} | error: "
                             f"{p['error']} |")  # fmt: skip
                continue
            solve = "-" if p["solve_s"] is None else f"{p['solve_s']:.3f}"
            total = "-" if p["total_s"] is None else f"{p['total_s']:.3f}"
            ratio = "-" if p["total_s"] is None else f"{p['total_s'] / p['ours_iteration_s']:.1f}"
            lines.append(
                f"| {p['dim']}D | {p['elements']:,} | {p['library']} {p['version']} | "
                f"{p['peer_solver']} | {p['assembly_s']:.3f} | {solve} | {total} | "
                f"{p['ours_assembly_s']:.3f} | {p['ours_iteration_s']:.3f} | "
                f"**{p['assembly_s'] / p['ours_assembly_s']:.1f}** | {ratio} |"
            )
    if explicit:
        lines += ["", "Explicit (symplectic Euler, lumped mass, half the CFL step):", ""]
        lines += ["| dim | elements | vertices | backend | time / step | vertex updates / s |"]
        lines += ["| --- " * 6 + "|"]
        for e in explicit:
            if "error" in e:
                lines.append(f"| error: {e['error']} |")
                continue
            lines.append(
                f"| {e['dim']}D | {e['elements']:,} | {e['vertices']:,} | {e['backend']} | "
                f"{e['time_per_step_s']:.4f} | {e['vertex_updates_per_s']:.3g} |"
            )
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--quick", action="store_true", help="tiny sizes, one repeat")
    parser.add_argument("--sizes2d", type=int, nargs="*", default=[71, 224, 500, 708])
    parser.add_argument("--sizes3d", type=int, nargs="*", default=[12, 26, 36, 44])
    parser.add_argument("--backend", default="auto", help="auto, numba or numpy")
    parser.add_argument("--solver", default="auto", help="the Newton iteration's linear solver")
    parser.add_argument("--material", default="neo_hookean",
                        help="law of the iteration table (peers: neo_hookean)")  # fmt: skip
    parser.add_argument("--time-step", type=float, default=None,
                        help="Backward Euler step (s); default: quasistatic")  # fmt: skip
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--peers", action="store_true", help="also time FElupe and scikit-fem")
    parser.add_argument("--peer-solve-max-elements", type=int, default=200_000,
                        help="above this, peers time assembly only (SuperLU is slow)")  # fmt: skip
    parser.add_argument("--max-direct-dofs-3d", type=int, default=160_000,
                        help="3D direct solvers are timed only up to this many DOFs")  # fmt: skip
    parser.add_argument("--explicit-steps", type=int, default=20)
    parser.add_argument("--solvers", nargs="*", default=None,
                        help="solvers timed alone (default: every fast one installed)")  # fmt: skip
    parser.add_argument("--out", default="benchmarks/results")
    parser.add_argument("--worker", nargs=2, help=argparse.SUPPRESS)
    parser.add_argument("--markdown-from", help="rewrite results.md from this results.json")
    args = parser.parse_args()
    if args.markdown_from:
        result = json.loads(Path(args.markdown_from).read_text())
        Path(args.markdown_from).with_name("results.md").write_text(markdown(result))
        return
    if args.worker:
        from threadpoolctl import threadpool_limits

        kind, kwargs = args.worker[0], json.loads(args.worker[1])
        with threadpool_limits(1):
            print(json.dumps(WORKERS[kind](**kwargs), default=float))
        return
    if args.quick:
        args.sizes2d, args.sizes3d, args.repeat, args.explicit_steps = [8], [3], 1, 2
    command = "python benchmarks/" + Path(__file__).name + " " + " ".join(sys.argv[1:])
    rows, peer_rows, explicit, scaling = [], [], [], []
    for dim, sizes in ((2, args.sizes2d), (3, args.sizes3d)):
        for n in sizes:
            row = spawn("iteration", dim=dim, n=n, backend=args.backend, solver_name=args.solver,
                        repeat=args.repeat, material=args.material,
                        time_step=args.time_step)  # fmt: skip
            row.setdefault("dim", dim)
            rows.append(row)
            if "error" in row:
                print(row["error"], flush=True)
                continue
            row["solves"] = [
                spawn("solve", dim=dim, n=n, solver_name=s, repeat=args.repeat)
                for s in candidate_solvers(dim, row["dofs"], args.max_direct_dofs_3d, args.solvers)
            ]
            ok = [s for s in row["solves"] if "error" not in s]
            best = min(ok, key=lambda s: s["per_iteration_s"])
            row["best_solver"], row["best_solve_s"] = best["solver"], best["per_iteration_s"]
            row["iteration_over_best_solve"] = row["iteration_s"] / best["per_iteration_s"]
            print(
                f"{dim}D {row['elements']:>9,} elements: iteration {row['iteration_s']:.3f} s "
                f"({row['solver']}), best solve {best['per_iteration_s']:.3f} s "
                f"({best['solver']}), ratio {row['iteration_over_best_solve']:.2f}, "
                f"assembly {row['assembly_s']:.3f} s",
                flush=True,
            )
            if args.peers:
                libraries = ["felupe", "scikit-fem"]
                from tissuesim.solve.linear import has_pardiso

                if has_pardiso():
                    libraries.insert(1, "felupe+pardiso")
                for library in libraries:
                    solve = row["elements"] <= args.peer_solve_max_elements or (
                        library == "felupe+pardiso" and dim == 2
                    )
                    p = spawn("peer", dim=dim, n=n, library=library, repeat=args.repeat,
                              solve=solve)  # fmt: skip
                    p.update(dim=dim, elements=row["elements"], ours_assembly_s=row["assembly_s"],
                             ours_iteration_s=row["iteration_s"])  # fmt: skip
                    peer_rows.append(p)
                    print(f"   {library}: {p.get('assembly_s', p.get('error'))}", flush=True)
            if row["elements"] >= 100_000 or args.quick:
                e = spawn("explicit", dim=dim, n=n, steps=args.explicit_steps)
                explicit.append(e)
        ok_rows = [r for r in rows if r.get("dim") == dim and "error" not in r]
        if ok_rows:
            scaling.append(
                {
                    "dim": dim,
                    "sizes": ", ".join(f"{r['elements']:,}" for r in ok_rows),
                    "assembly_exponent": fit_exponent(
                        [r["elements"] for r in ok_rows], [r["assembly_s"] for r in ok_rows]
                    ),
                    "iteration_exponent": fit_exponent(
                        [r["elements"] for r in ok_rows], [r["iteration_s"] for r in ok_rows]
                    ),
                }
            )
    import threadpoolctl

    result = {
        "machine": f"{platform.platform()} ({os.cpu_count()} CPUs)",
        "python": platform.python_version(),
        "threadpools": threadpoolctl.threadpool_info(),
        "command": command,
        "rows": rows,
        "peers": peer_rows,
        "explicit": explicit,
        "scaling": scaling,
    }
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "results.json").write_text(json.dumps(result, indent=2, default=str))
    (out / "results.md").write_text(markdown(result))
    print(markdown(result))
    if any("error" in r for r in rows + peer_rows + explicit):
        sys.exit(1)


if __name__ == "__main__":
    main()
