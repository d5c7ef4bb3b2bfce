"""Frames against tetrahedral FEM on a clamped cantilever: static tip deflection and the first
bending frequency.

The problem: a bar 0.4 x 0.4 x 2 m (z along the length), StVK with E = 1000 Pa, nu = 0,
density 1000 kg/m^3, clamped at z = 0, loaded at the free end z = 2 by a total dead force of
0.16 N in -y (FEM: traction 1 Pa on the z = 2 facets; frames: 0.16 / 64 N on each point of an
8 x 8 grid on the z = 2 face), solved quasistatically in one step. The reference is the project's
own tetrahedral FEM (``tissuesim.Simulation``) on box meshes n x n x 5n, with a Richardson
extrapolation (p = 2) from its two finest meshes.

Frames: one line of n rigid frames along z at x = y = 0.2 (``grid_frames``), integration points
on a regular grid (``sample_box``). Wendland-Shepard weights do not interpolate, so the clamp is
modelled two ways, both reported:

- ``fixed``: the frame at z = 0 is fixed (its neighbours' supports also reach the root face,
  which is then not clamped: too soft with many frames);
- ``springs k``: zero-length springs of stiffness k (N/m per point) from an 8 x 8 grid of
  root-face points (z = 0) to their rest positions (a soft clamp; large k locks the frames whose
  support reaches the root).

Frequencies: K v = omega^2 M v at rest on the free DOFs (FEM: consistent mass; frames: full
generalised mass, springs included in K), and from free vibration: release the static deflection
under a small (linear-regime) end load and time the tip's zero crossings (frames: explicit
symplectic Euler below the stability limit and Backward Euler; FEM: symplectic Euler with the
lumped mass on a coarse mesh). Euler-Bernoulli: f1 = 1.875^2 / (2 pi L^2) sqrt(E I / (rho A)).

    python benchmarks/frames_cantilever.py            # full run (a few minutes on 2 cores)
    python benchmarks/frames_cantilever.py --quick    # a smoke test (< 60 s)
    python benchmarks/frames_cantilever.py --out DIR  # write DIR/frames_cantilever.{json,md}
"""

from __future__ import annotations

import argparse
import json
import platform
import sys
import time
from pathlib import Path

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

E, NU, DENSITY = 1000.0, 0.0, 1000.0
A_SIDE, LENGTH = 0.4, 2.0
TOTAL_LOAD = 0.16  # N, in -y
SMALL_LOAD = 0.0016  # N, for the free-vibration initial deflection (linear regime)
TIP = np.array([0.2, 0.2, 2.0])

FULL = {
    "fem_divisions": [2, 4, 8, 12],
    "frame_counts": [2, 4, 8, 16, 32],
    "spacing": 0.05,
    "spring_stiffness": [1e3, 1e4],
    "repeat": 3,
    "fem_repeat": 3,
    "modal_frames": 16,
    "periods": 3.0,
    "be_steps_per_period": 200,
    "fem_vibration_divisions": 4,
    "max_explicit_steps": 20000,
}
QUICK = {
    "fem_divisions": [2, 4, 6],
    "frame_counts": [2, 4, 8],
    "spacing": 0.1,
    "spring_stiffness": [1e3],
    "repeat": 2,
    "fem_repeat": 2,
    "modal_frames": 8,
    "periods": 2.0,
    "be_steps_per_period": 100,
    "fem_vibration_divisions": 2,
    "max_explicit_steps": 8000,
}


def euler_bernoulli_frequency() -> float:
    inertia = A_SIDE**4 / 12.0
    area = A_SIDE**2
    return 1.875**2 / (2 * np.pi * LENGTH**2) * np.sqrt(E * inertia / (DENSITY * area))


def euler_bernoulli_tip() -> float:
    return TOTAL_LOAD * LENGTH**3 / (3 * E * A_SIDE**4 / 12.0)


def material():
    from tissuesim.materials import make_material

    return make_material("stvk", youngs_modulus=E, poisson_ratio=NU)


def face_grid(z: float, n: int = 8) -> np.ndarray:
    g = (np.arange(n) + 0.5) / n * A_SIDE
    X, Y = np.meshgrid(g, g)
    return np.stack([X.ravel(), Y.ravel(), np.full(X.size, z)], axis=1)


def median_time(fn, repeat: int):
    times, out = [], None
    for _ in range(repeat):
        start = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - start)
    return float(np.median(times)), out


def crossing_frequency(times: np.ndarray, y: np.ndarray) -> tuple[float, int]:
    """Frequency (Hz) from the zero crossings of y(t) (linear interpolation), fitted as a line
    through the crossing times: consecutive crossings are half a period apart."""
    s = np.sign(y)
    idx = np.flatnonzero(s[:-1] * s[1:] < 0)
    crossings = times[idx] - y[idx] * (times[idx + 1] - times[idx]) / (y[idx + 1] - y[idx])
    if crossings.size < 2:
        return float("nan"), int(crossings.size)
    half_period = np.polyfit(np.arange(crossings.size), crossings, 1)[0]
    return float(1.0 / (2.0 * half_period)), int(crossings.size)


def fitted_frequency(times: np.ndarray, y: np.ndarray, f0: float) -> tuple[float, float]:
    """Least-squares fit y ~ exp(-s t) (a cos 2 pi f t + b sin 2 pi f t) + c from f0: (f, s).

    Less sensitive than the zero crossings to the higher modes the release also excites (their
    contributions are nearly orthogonal over a few periods); s captures numerical damping."""
    from scipy.optimize import least_squares

    scale = np.abs(y).max() or 1.0

    def residual(p):
        a, b, f, s, c = p
        w = 2 * np.pi * f * times
        return (np.exp(-s * times) * (a * np.cos(w) + b * np.sin(w)) + c - y) / scale

    fit = least_squares(residual, [y[0], 0.0, f0, 0.0, 0.0], x_scale=[scale, scale, f0, f0, scale])
    return float(fit.x[2]), float(fit.x[3])


# -- FEM ------------------------------------------------------------------------------------------
def fem_simulation(nd: int, load: float, integrator: str = "quasistatic", time_step: float = 1.0):
    from tissuesim import Simulation
    from tissuesim.mesh import box
    from tissuesim.mesh.queries.boundary import boundary_facets
    from tissuesim.mesh.queries.select import vertices_on_plane

    mesh = box([0, 0, 0], [A_SIDE, A_SIDE, LENGTH], (nd, nd, 5 * nd))
    sim = Simulation(mesh, material(), density=DENSITY, integrator=integrator, time_step=time_step)
    sim.add_dirichlet(vertices_on_plane(mesh, axis=2, value=0.0))
    if load:
        facets = boundary_facets(mesh.cells)
        end = facets[np.all(np.isclose(mesh.points[facets][:, :, 2], LENGTH), axis=1)]
        sim.add_traction(end, [0.0, -load / A_SIDE**2, 0.0])
    tip = int(np.argmin(np.linalg.norm(mesh.points - TIP, axis=1)))
    assert np.allclose(mesh.points[tip], TIP), "the mesh needs a vertex at the tip centre"
    return sim, tip


def fem_static(nd: int, repeat: int) -> dict:
    from tissuesim.time.state import State

    start = time.perf_counter()
    sim, tip = fem_simulation(nd, TOTAL_LOAD)
    setup = time.perf_counter() - start
    rest = sim.state

    def solve():
        sim.state = State(0.0, rest.x.copy(), rest.v.copy())
        return sim.step()

    solve_s, record = median_time(solve, repeat)
    free = sim.model.n_dofs - sim.model.prescribed.dofs.size
    return {
        "divisions": [nd, nd, 5 * nd],
        "tets": int(sim.mesh.n_cells),
        "dofs": int(sim.model.n_dofs),
        "free_dofs": int(free),
        "tip_deflection": float(-sim.displacement[tip, 1]),
        "newton_iterations": int(record.newton_iterations),
        "setup_s": setup,
        "solve_s": solve_s,
        "linear_solver": record.linear_solver,
    }


def _bending_pair(vals: np.ndarray, translations) -> tuple[float, float]:
    """The two lowest eigenvalues whose modes move the tip centre sideways most: the two
    bending modes. On the tetrahedral mesh they bend along the diagonals x = +-y and differ by a
    few percent (mesh anisotropy); for the frames they coincide."""
    found = []
    for k in np.argsort(vals):
        tip, nodes = translations(k)  # tip centre (3,), all node translations (m, 3)
        if np.linalg.norm(tip[:2]) > 0.5 * np.linalg.norm(nodes, axis=1).max():
            found.append(float(vals[k]))
        if len(found) == 2:
            return found[0], found[1]
    raise RuntimeError("fewer than two bending modes among the computed eigenpairs")


def _hz(lam: float) -> float:
    return float(np.sqrt(lam) / (2 * np.pi))


def _factor(A: sp.csc_matrix):
    """A solve with A: CHOLMOD when scikit-sparse is installed, else SciPy's SuperLU."""
    try:
        from sksparse.cholmod import cholesky
    except ImportError:
        return spla.splu(A).solve
    return cholesky(A)


def fem_modal(nd: int) -> dict:
    sim, tip = fem_simulation(nd, 0.0)
    model = sim.model
    x = sim.state.x
    start = time.perf_counter()
    K = sp.csr_matrix(model.pattern.matrix(model.evaluate(x, 2, False).hessian))
    M = sp.csr_matrix(model.mass.matrix())
    free = np.ones(model.n_dofs, dtype=bool)
    free[model.prescribed.dofs] = False
    Kf = K[free][:, free].tocsc()
    Mf = M[free][:, free].tocsc()
    factor = _factor(Kf)
    op = spla.LinearOperator(Kf.shape, matvec=factor, dtype=float)
    vals, vecs = spla.eigsh(Kf, k=6, M=Mf, sigma=0.0, which="LM", OPinv=op)
    full = np.zeros((model.n_dofs, vecs.shape[1]))
    full[free] = vecs

    def translations(k):
        u = full[:, k].reshape(-1, 3)
        return u[tip], u

    lam1, lam2 = _bending_pair(vals, translations)
    out = {
        "divisions": [nd, nd, 5 * nd],
        "free_dofs": int(free.sum()),
        "frequency_hz": _hz(lam1),
        "partner_frequency_hz": _hz(lam2),
        "pair_mean_hz": 0.5 * (_hz(lam1) + _hz(lam2)),
        "eigen_s": time.perf_counter() - start,
    }
    lumped = np.asarray(model.mass.lumped)[free]
    Ml = sp.diags(lumped).tocsc()
    vals_l, vecs_l = spla.eigsh(Kf, k=6, M=Ml, sigma=0.0, which="LM", OPinv=op)
    full[:] = 0.0
    full[free] = vecs_l
    lam1, lam2 = _bending_pair(vals_l, translations)
    out["lumped_frequency_hz"] = _hz(lam1)
    out["lumped_pair_mean_hz"] = 0.5 * (_hz(lam1) + _hz(lam2))
    return out


def fem_free_vibration(nd: int, periods: float, f_guess: float) -> dict:
    """Symplectic Euler (lumped mass) from the static deflection under SMALL_LOAD."""
    from tissuesim.time.integrators.stability import critical_time_step
    from tissuesim.time.state import State
    from tissuesim.time.steps import explicit_step

    static, tip = fem_simulation(nd, SMALL_LOAD)
    static.step()
    x0 = static.state.x.copy()
    sim, _ = fem_simulation(nd, 0.0, integrator="symplectic_euler", time_step=1.0)
    h = 0.5 * critical_time_step(sim.model)
    steps = int(np.ceil(periods / f_guess / h))
    state = State(0.0, x0, np.zeros_like(x0))
    rest_y = sim.mesh.points[tip, 1]
    times, ys = [0.0], [x0[3 * tip + 1] - rest_y]
    start = time.perf_counter()
    for _ in range(steps):
        outcome = explicit_step(sim.system, state, h, energies=sim.step_energies, limit=float)
        if not outcome.converged:
            raise RuntimeError(outcome.reason)
        state = outcome.state
        times.append(state.time)
        ys.append(state.x[3 * tip + 1] - rest_y)
    wall = time.perf_counter() - start
    f_cross, n_cross = crossing_frequency(np.array(times), np.array(ys))
    f, _ = fitted_frequency(np.array(times), np.array(ys), f_cross)
    return {
        "divisions": [nd, nd, 5 * nd],
        "integrator": "symplectic_euler (lumped mass)",
        "time_step": h,
        "steps": steps,
        "steps_per_period": 1.0 / (f_guess * h),
        "crossings": n_cross,
        "crossing_frequency_hz": f_cross,
        "frequency_hz": f,
        "wall_s": wall,
    }


# -- frames ---------------------------------------------------------------------------------------
def frame_simulation(
    n: int,
    spacing: float,
    clamp: str,
    k: float,
    load: float,
    integrator: str = "quasistatic",
    time_step: float = 1.0,
):
    from tissuesim.frames.placement import grid_frames
    from tissuesim.frames.sampling import sample_box
    from tissuesim.simulation import Simulation

    frames = grid_frames([0.2, 0.2, 0.0], [0.2, 0.2, LENGTH], (1, 1, n))
    samples = sample_box([0, 0, 0], [A_SIDE, A_SIDE, LENGTH], spacing)
    sim = Simulation.from_frames(
        frames, samples, material(), density=DENSITY, integrator=integrator, time_step=time_step
    )
    if clamp == "fixed":
        sim.fix_frames(sim.frames_where(lambda X: X[:, 2] < 1e-9))
    else:
        sim.add_spring(face_grid(0.0), k)
    if load:
        face = face_grid(LENGTH)
        sim.add_point_forces(face, [0.0, -load / face.shape[0], 0.0])
    sim.embed("tip", TIP[None])
    return sim


def clamp_label(clamp: str, k: float) -> str:
    return "fixed frame" if clamp == "fixed" else f"springs k={k:g}"


def clamps(config) -> list[tuple[str, float]]:
    return [("fixed", 0.0)] + [("springs", float(k)) for k in config["spring_stiffness"]]


def frames_static(n: int, spacing: float, clamp: str, k: float, repeat: int) -> dict:
    from tissuesim.time.state import State

    start = time.perf_counter()
    sim = frame_simulation(n, spacing, clamp, k, TOTAL_LOAD)
    setup = time.perf_counter() - start
    rest = sim.state

    def solve():
        sim.state = State(0.0, rest.x.copy(), rest.v.copy())
        return sim.step()

    solve_s, record = median_time(solve, repeat)
    d = {**sim.describe(), **sim.describe()["bodies"]["body"]}
    return {
        "clamp": clamp_label(clamp, k),
        "frames": n,
        "dofs": int(d["n_dofs"]),
        "free_dofs": int(d["n_dofs"] - d["prescribed_dofs"]),
        "integration_points": int(d["integration_points"]),
        "frames_per_point": d["frames_per_point"]["mean"],
        "tip_deflection": float(TIP[1] - sim.embedded_positions("tip")[0, 1]),
        "newton_iterations": int(record.newton_iterations),
        "setup_s": setup,
        "solve_s": solve_s,
    }


def frame_matrices(sim):
    model = sim.model
    z = model.rest_config()
    acc = model.evaluate(z, 2, False, model.spring_energies(0.0))
    K = model.assembly.q_pattern.matrix(acc.hessian)
    M = model.tangent_mass(z)
    free = np.ones(model.n_dofs, dtype=bool)
    free[model.prescribed_dofs] = False
    return K, M, free


def frames_modal(n: int, spacing: float, clamp: str, k: float) -> dict:
    from scipy.linalg import eigh

    sim = frame_simulation(n, spacing, clamp, k, 0.0)
    K, M, free = frame_matrices(sim)
    Kf = K[free][:, free].toarray()
    Mf = M[free][:, free].toarray()
    Kf = 0.5 * (Kf + Kf.T)
    vals, vecs = eigh(Kf, 0.5 * (Mf + Mf.T))
    full = np.zeros((K.shape[0], vecs.shape[1]))
    full[free] = vecs
    t = sim.model.frame_type.tangent_size
    tip_frame = int(np.argmin(np.linalg.norm(sim.rest_frames - TIP, axis=1)))

    def translations(j):
        u = full[:, j].reshape(-1, t)[:, :3]
        return u[tip_frame], u

    lam1, lam2 = _bending_pair(vals, translations)
    lam_max = float(vals.max())
    return {
        "clamp": clamp_label(clamp, k),
        "frames": n,
        "free_dofs": int(free.sum()),
        "frequency_hz": _hz(lam1),
        "partner_frequency_hz": _hz(lam2),
        "critical_time_step": float(2.0 / np.sqrt(lam_max)),
    }


def frames_free_vibration(
    n: int,
    spacing: float,
    clamp: str,
    k: float,
    integrator: str,
    steps_per_period: float | None,
    periods: float,
    f_guess: float,
    h_crit: float,
    max_explicit_steps: int,
) -> dict:
    from tissuesim.time.state import State

    static = frame_simulation(n, spacing, clamp, k, SMALL_LOAD)
    static.step()
    z0 = static.state.x.copy()
    if integrator == "explicit":
        h = 0.8 * h_crit
    else:
        h = 1.0 / (f_guess * steps_per_period)
    steps = int(np.ceil(periods / f_guess / h))
    if integrator == "explicit" and steps > max_explicit_steps:
        return {
            "clamp": clamp_label(clamp, k),
            "frames": n,
            "integrator": integrator,
            "time_step": h,
            "steps": steps,
            "skipped": f"{steps} explicit steps needed (> {max_explicit_steps}): the springs "
            "make the stability limit small",
        }
    sim = frame_simulation(n, spacing, clamp, k, 0.0, integrator=integrator, time_step=h)
    sim.state = State(0.0, z0, np.zeros(sim.model.n_dofs))
    tip = sim.embedded["tip"]
    times, ys = [0.0], [tip.positions(z0)[0, 1] - TIP[1]]
    newton = 0
    start = time.perf_counter()
    if integrator == "explicit":
        # the step function itself: Simulation.step() also evaluates energies and point
        # fields for its record every step, which would dominate the cost here
        from tissuesim.time.steps import explicit_step

        state = sim.state
        for _ in range(steps):
            outcome = explicit_step(sim.system, state, h, energies=sim.step_energies, limit=float)
            if not outcome.converged:
                raise RuntimeError(outcome.reason)
            state = outcome.state
            times.append(state.time)
            ys.append(tip.positions(state.x)[0, 1] - TIP[1])
    else:
        for _ in range(steps):
            record = sim.step()
            newton += record.newton_iterations
            times.append(sim.time)
            ys.append(sim.embedded_positions("tip")[0, 1] - TIP[1])
    wall = time.perf_counter() - start
    f_cross, n_cross = crossing_frequency(np.array(times), np.array(ys))
    f, decay = fitted_frequency(np.array(times), np.array(ys), f_cross)
    ys = np.array(ys)
    return {
        "clamp": clamp_label(clamp, k),
        "frames": n,
        "integrator": integrator,
        "time_step": h,
        "steps": steps,
        "steps_per_period": 1.0 / (f_guess * h),
        "crossings": n_cross,
        "crossing_frequency_hz": f_cross,
        "frequency_hz": f,
        "decay_rate_per_s": decay,
        "amplitude_ratio_last_period": float(
            np.abs(ys[-int(len(ys) / periods) :]).max() / abs(ys[0])
        ),
        "newton_iterations_per_step": newton / steps if integrator != "explicit" else 0.0,
        "wall_s": wall,
    }


# -- driver ---------------------------------------------------------------------------------------
def run(config: dict, log) -> dict:
    f_eb = euler_bernoulli_frequency()
    data = {
        "problem": {
            "size_m": [A_SIDE, A_SIDE, LENGTH],
            "material": "stvk",
            "youngs_modulus_pa": E,
            "poisson_ratio": NU,
            "density_kg_m3": DENSITY,
            "total_end_load_n": TOTAL_LOAD,
            "free_vibration_load_n": SMALL_LOAD,
            "euler_bernoulli_tip_deflection_m": euler_bernoulli_tip(),
            "euler_bernoulli_frequency_hz": f_eb,
        },
        "config": config,
        "machine": {"python": sys.version.split()[0], "platform": platform.platform()},
    }
    fem = []
    for nd in config["fem_divisions"]:
        row = fem_static(nd, config["fem_repeat"])
        log(f"FEM {row['divisions']}: tip {row['tip_deflection']:.5f}, {row['solve_s']:.2f} s")
        fem.append(row)
    fine, coarse = fem[-1], fem[-2]
    ratio = fine["divisions"][0] / coarse["divisions"][0]
    richardson = fine["tip_deflection"] + (fine["tip_deflection"] - coarse["tip_deflection"]) / (
        ratio**2 - 1
    )
    for row in fem:
        row["error_vs_finest"] = abs(row["tip_deflection"] - fine["tip_deflection"]) / abs(
            fine["tip_deflection"]
        )
        row["error_vs_richardson"] = abs(row["tip_deflection"] - richardson) / abs(richardson)
    frames = []
    for clamp, k in clamps(config):
        for n in config["frame_counts"]:
            row = frames_static(n, config["spacing"], clamp, k, config["repeat"])
            row["error_vs_finest_fem"] = abs(row["tip_deflection"] - fine["tip_deflection"]) / abs(
                fine["tip_deflection"]
            )
            row["error_vs_richardson"] = abs(row["tip_deflection"] - richardson) / abs(richardson)
            log(
                f"frames {row['clamp']} n={n}: tip {row['tip_deflection']:.5f}, "
                f"{row['solve_s']:.3f} s"
            )
            frames.append(row)
    data["static"] = {
        "fem_reference": {
            "finest_divisions": fine["divisions"],
            "finest_tip_deflection": fine["tip_deflection"],
            "richardson_tip_deflection": richardson,
        },
        "fem": fem,
        "frames": frames,
    }

    # -- frequencies --
    fem_modes = []
    for nd in config["fem_divisions"]:
        row = fem_modal(nd)
        log(f"FEM modal {row['divisions']}: {row['frequency_hz']:.5f} Hz")
        fem_modes.append(row)
    f_fem_fine = fem_modes[-1]["frequency_hz"]
    n_modal = config["modal_frames"]
    frame_modes, vibration = [], []
    for clamp, k in clamps(config):
        modal = frames_modal(n_modal, config["spacing"], clamp, k)
        log(f"frames modal {modal['clamp']} n={n_modal}: {modal['frequency_hz']:.5f} Hz")
        frame_modes.append(modal)
        for integrator, spp in (
            ("explicit", None),
            ("backward_euler", config["be_steps_per_period"]),
        ):
            row = frames_free_vibration(
                n_modal,
                config["spacing"],
                clamp,
                k,
                integrator,
                spp,
                config["periods"],
                modal["frequency_hz"],
                modal["critical_time_step"],
                config["max_explicit_steps"],
            )
            if "skipped" in row:
                log(f"frames {integrator} {row['clamp']}: skipped, {row['skipped']}")
                vibration.append(row)
                continue
            log(
                f"frames {integrator} {row['clamp']}: {row['frequency_hz']:.5f} Hz "
                f"({row['steps']} steps, {row['wall_s']:.1f} s)"
            )
            vibration.append(row)
    # FEM at a resolution with at least as many free DOFs as the modal frames model
    frame_free = frame_modes[0]["free_dofs"]
    matched = next((r for r in fem_modes if r["free_dofs"] >= frame_free), fem_modes[-1])
    for row in frame_modes + [r for r in vibration if "skipped" not in r]:
        row["rel_diff_vs_fem_matched"] = row["frequency_hz"] / matched["frequency_hz"] - 1
        row["rel_diff_vs_fem_finest"] = row["frequency_hz"] / f_fem_fine - 1
        row["rel_diff_vs_euler_bernoulli"] = row["frequency_hz"] / f_eb - 1
    for row in fem_modes:
        row["rel_diff_vs_fem_finest"] = row["frequency_hz"] / f_fem_fine - 1
        row["rel_diff_vs_euler_bernoulli"] = row["frequency_hz"] / f_eb - 1
    nd_v = config["fem_vibration_divisions"]
    own = next(r for r in fem_modes if r["divisions"][0] == nd_v)
    fem_vib = fem_free_vibration(nd_v, config["periods"], own["lumped_frequency_hz"])
    # a release in y excites both diagonal bending modes equally: the tip beats at their mean
    fem_vib["own_lumped_pair_mean_hz"] = own["lumped_pair_mean_hz"]
    fem_vib["rel_diff_vs_own_lumped_pair_mean"] = (
        fem_vib["frequency_hz"] / own["lumped_pair_mean_hz"] - 1
    )
    log(f"FEM symplectic {fem_vib['divisions']}: {fem_vib['frequency_hz']:.5f} Hz")
    data["frequency"] = {
        "euler_bernoulli_hz": f_eb,
        "fem_matched_divisions": matched["divisions"],
        "fem_finest_hz": f_fem_fine,
        "fem_modal": fem_modes,
        "frames_modal": frame_modes,
        "frames_free_vibration": vibration,
        "fem_free_vibration": fem_vib,
    }
    return data


def _table(headers: list[str], rows: list[list]) -> str:
    def fmt(v):
        if isinstance(v, float):
            return f"{v:.4g}"
        return str(v)

    lines = ["| " + " | ".join(headers) + " |", "|" + "---|" * len(headers)]
    lines += ["| " + " | ".join(fmt(v) for v in row) + " |" for row in rows]
    return "\n".join(lines)


def markdown(data: dict) -> str:
    p, s, f = data["problem"], data["static"], data["frequency"]
    ref = s["fem_reference"]
    pct = lambda v: f"{100 * v:.2f} %"  # noqa: E731
    out = [
        "# Frames vs tetrahedral FEM: clamped cantilever",
        "",
        f"Bar {p['size_m']} m, StVK E = {p['youngs_modulus_pa']:g} Pa, nu = "
        f"{p['poisson_ratio']:g}, density {p['density_kg_m3']:g} kg/m^3, end load "
        f"{p['total_end_load_n']:g} N in -y, one quasistatic step. Tip = deflection of the point "
        f"(0.2, 0.2, 2). FEM reference: finest mesh {ref['finest_divisions']} "
        f"{ref['finest_tip_deflection']:.5f} m, Richardson (p = 2) "
        f"{ref['richardson_tip_deflection']:.5f} m; Euler-Bernoulli "
        f"{p['euler_bernoulli_tip_deflection_m']:.5f} m. Times are medians of repeated solves "
        "from rest (seconds).",
        "",
        "## FEM (tetrahedra, quasistatic)",
        "",
        _table(
            [
                "divisions",
                "tets",
                "DOFs",
                "tip (m)",
                "err vs finest",
                "err vs Richardson",
                "Newton its",
                "time/solve (s)",
            ],
            [
                [
                    "x".join(map(str, r["divisions"])),
                    r["tets"],
                    r["dofs"],
                    r["tip_deflection"],
                    pct(r["error_vs_finest"]),
                    pct(r["error_vs_richardson"]),
                    r["newton_iterations"],
                    r["solve_s"],
                ]
                for r in s["fem"]
            ],
        ),
        "",
        "## Frames (rigid, one line along z, quasistatic)",
        "",
        _table(
            [
                "clamp",
                "frames",
                "DOFs",
                "integration pts",
                "frames/pt",
                "tip (m)",
                "err vs finest FEM",
                "err vs Richardson",
                "Newton its",
                "time/solve (s)",
            ],
            [
                [
                    r["clamp"],
                    r["frames"],
                    r["dofs"],
                    r["integration_points"],
                    r["frames_per_point"],
                    r["tip_deflection"],
                    pct(r["error_vs_finest_fem"]),
                    pct(r["error_vs_richardson"]),
                    r["newton_iterations"],
                    r["solve_s"],
                ]
                for r in s["frames"]
            ],
        ),
        "",
        "## First bending frequency",
        "",
        f"Euler-Bernoulli: {f['euler_bernoulli_hz']:.5f} Hz. FEM 'matched' resolution (the "
        f"coarsest with at least the frames' free DOFs): "
        f"{'x'.join(map(str, f['fem_matched_divisions']))}.",
        "",
        "### Eigenvalues at rest (K v = omega^2 M v, free DOFs)",
        "",
        "f1 is the lowest bending mode, f1' its partner (the tetrahedral meshes bend along the "
        "diagonals x = +-y with slightly different stiffness; for the line of frames the two "
        "coincide). Relative differences are of f1.",
        "",
        _table(
            [
                "model",
                "free DOFs",
                "f1 (Hz)",
                "f1' (Hz)",
                "vs FEM matched",
                "vs FEM finest",
                "vs Euler-Bernoulli",
            ],
            [
                [
                    "FEM " + "x".join(map(str, r["divisions"])) + " consistent",
                    r["free_dofs"],
                    r["frequency_hz"],
                    r["partner_frequency_hz"],
                    "",
                    pct(r["rel_diff_vs_fem_finest"]),
                    pct(r["rel_diff_vs_euler_bernoulli"]),
                ]
                for r in f["fem_modal"]
            ]
            + [
                [
                    f"frames n={r['frames']}, {r['clamp']}",
                    r["free_dofs"],
                    r["frequency_hz"],
                    r["partner_frequency_hz"],
                    pct(r["rel_diff_vs_fem_matched"]),
                    pct(r["rel_diff_vs_fem_finest"]),
                    pct(r["rel_diff_vs_euler_bernoulli"]),
                ]
                for r in f["frames_modal"]
            ],
        ),
        "",
        "### Free vibration (release of a small static deflection; damped-sinusoid fit of the tip)",
        "",
        _table(
            [
                "model",
                "integrator",
                "time step (s)",
                "steps/period",
                "steps",
                "f1 (Hz)",
                "f1 zero crossings (Hz)",
                "vs FEM matched",
                "vs FEM finest",
                "amplitude last period",
                "wall (s)",
            ],
            [
                [
                    f"frames n={r['frames']}, {r['clamp']}",
                    r["integrator"],
                    r["time_step"],
                    r["steps_per_period"],
                    r["steps"],
                    r["frequency_hz"],
                    r["crossing_frequency_hz"],
                    pct(r["rel_diff_vs_fem_matched"]),
                    pct(r["rel_diff_vs_fem_finest"]),
                    r["amplitude_ratio_last_period"],
                    r["wall_s"],
                ]
                if "skipped" not in r
                else [
                    f"frames n={r['frames']}, {r['clamp']}",
                    r["integrator"],
                    r["time_step"],
                    "",
                    r["steps"],
                    "skipped",
                    r["skipped"],
                    "",
                    "",
                    "",
                    "",
                ]
                for r in f["frames_free_vibration"]
            ],
        ),
        "",
        (
            lambda r: (
                f"FEM {'x'.join(map(str, r['divisions']))}, {r['integrator']}: time step "
                f"{r['time_step']:.4g} s ({r['steps_per_period']:.0f} steps/period, {r['steps']} "
                f"steps, {r['wall_s']:.1f} s): f1 = {r['frequency_hz']:.5f} Hz, "
                f"{pct(r['rel_diff_vs_own_lumped_pair_mean'])} from the mean of its own two "
                f"lumped-mass bending eigenfrequencies ({r['own_lumped_pair_mean_hz']:.5f} Hz; "
                "a release in y excites both diagonal bending modes of the tetrahedral mesh)."
            )
        )(f["fem_free_vibration"]),
        "",
    ]
    return "\n".join(out)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="small sizes, a smoke test")
    parser.add_argument(
        "--out",
        type=Path,
        default=Path(__file__).resolve().parent / "results",
        help="folder for frames_cantilever.json and .md",
    )
    parser.add_argument("--repeat", type=int, help="repeats per frames solve (median)")
    args = parser.parse_args(argv)
    config = dict(QUICK if args.quick else FULL)
    if args.repeat:
        config["repeat"] = config["fem_repeat"] = args.repeat
    start = time.perf_counter()

    def log(msg):
        print(f"[{time.perf_counter() - start:7.1f} s] {msg}", flush=True)

    data = run(config, log)
    data["wall_s"] = time.perf_counter() - start
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "frames_cantilever.json").write_text(json.dumps(data, indent=2))
    (args.out / "frames_cantilever.md").write_text(markdown(data))
    log(f"wrote {args.out / 'frames_cantilever.json'} and .md")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
