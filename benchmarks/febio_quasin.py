"""FEBio's nonlinear solver replayed on tissuesim's forces: where FEBio's recorded norm of a
Newmark model (ms01, ms02, dy02) stops.

FEBio's ``FESolidSolver2::Quasin`` ends a step's iterations once the last increment du_k
(after its line search) has |du_k|^2 <= dtol^2 |U|^2 (U the step's increment so far) and
|du_k . R_k| <= etol |du_0 . R_0| (the TestSuite's decks: dtol 1e-3, etol 1e-2), with BFGS
updates (``BFGSSolver``: at most max_ups - 1 between reformations, reformed at each step's
start, when the energy norm grows, or when the update's condition number passes cmax) and
its line search (``FELineSearch``: lstol 0.9, lsmin 0.01, lsiter 5). Its solution is
therefore off its converged one by what those tolerances leave, and in undamped Newmark
vibration the steps' leftovers add up.

This script runs that loop, line for line, on the FEBio deck's body as tissuesim converts it:
the internal force and its exact tangent (``Model.evaluate``), the consistent mass, the loads
(``Model.external_force``), the prescribed values at the step's end (their increment entered
as FEBio's m_Fd, -K_fp du_p, in the first residual), Newmark's kinematics
(``FESolidSolver2::UpdateKinematics``), a_0 = M^-1 f(0) in a model dynamic from t = 0
(``InitAccelerations``) and rest after a static step. With the deck's tolerances the norm is
FEBio's recorded one (ms01, ms02, dy02: to 12 digits, and FEBio's number of equilibrium
iterations exactly); with tight ones (``--tight``) it is tissuesim's. One FEM body, no contact;
an adaptive step is its dtmax (FEBio's steps in dy02).

    python benchmarks/febio_quasin.py /tmp/ts_verify/ms01.feb [--tight] [--gold gold.py]
"""

from __future__ import annotations

import argparse
import ast
import sys
import warnings
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import scipy.sparse.linalg as spla

#: FEBio's defaults where the deck's first <solver> does not say
SETTINGS = {"dtol": 1e-3, "etol": 1e-2, "lstol": 0.9, "lsmin": 0.01, "lsiter": 5,
            "max_ups": 10, "cmax": 1e5, "beta": 0.25, "gamma": 0.5}  # fmt: skip


def deck_settings(path: Path) -> dict:
    """The first <solver>'s tolerances, line search, BFGS and Newmark values."""
    out = dict(SETTINGS)
    solver = ET.parse(path).getroot().find(".//solver")
    for key in out:
        node = None if solver is None else solver.find(f".//{key}")
        if node is not None and node.text:
            out[key] = type(out[key])(float(node.text))
    return out


class Quasin:
    """FEBio's Quasin on one FEM body (module docstring); ``iterations`` counts FEBio's
    equilibrium iterations."""

    def __init__(self, sim, settings: dict) -> None:
        self.sim, self.s = sim, settings
        self.body = sim.body()
        self.model = self.body.model
        self.M = self.model.mass.matrix().tocsr()
        self.iterations = 0

    def force(self, x):
        return self.model.evaluate(x, 1, False).gradient

    def tangent(self, x):
        return self.model.pattern.matrix(self.model.evaluate(x, 2, False).hessian).tocsr()

    def step(self, x_n, v_n, a_n, t1: float, dt: float, dynamic: bool):
        s, M = self.s, self.M
        beta, gamma = s["beta"], s["gamma"]
        free = np.ones(x_n.size, dtype=bool)
        free[self.model.prescribed_dofs] = False
        x_p = self.sim.system.apply_prescribed(x_n.copy(), t1)  # the prescribed at t_{n+1}
        f_ext = self.model.external_force(t1)

        def acceleration(c):
            return (c - x_n) / (beta * dt * dt) - v_n / (beta * dt) - a_n * (0.5 / beta - 1.0)

        def config(U):
            c = x_p.copy()
            c[free] = x_n[free] + U
            return c

        def residual(c):
            r = f_ext - self.force(c)
            if dynamic:
                r -= M @ acceleration(c)
            return r[free]

        def reform(c):
            K = self.tangent(c)
            if dynamic:
                K = K + M / (beta * dt * dt)
            return K, spla.splu(K[free][:, free].tocsc())

        U = np.zeros(int(free.sum()))
        K, lu = reform(x_n)  # at the step's start, the prescribed not moved yet
        R0 = residual(x_n) - K[free][:, ~free] @ (x_p - x_n)[~free]  # + FEBio's m_Fd
        V, W = [], []
        n_iter = 0
        while True:
            tmp = R0.copy()  # BFGSSolver::SolveEquations
            for v, w in zip(reversed(V), reversed(W), strict=True):
                tmp += v * (w @ tmp)
            ui = lu.solve(tmp)
            for v, w in zip(V, W, strict=True):
                ui += w * (v @ ui)
            step, R1 = self.line_search(ui, R0, lambda a, U=U, ui=ui: residual(config(U + a * ui)))
            if n_iter == 0:
                norm_Ei = norm_Em = abs(ui @ R0)
            du = step * ui
            U = U + du
            norm_u, norm_U, norm_E1 = du @ du, U @ U, abs(du @ R1)
            converged = (norm_u <= s["dtol"] ** 2 * norm_U and norm_E1 <= s["etol"] * norm_Ei
                         and step >= s["lsmin"] and norm_E1 <= norm_Em)  # fmt: skip
            if not converged and R1 @ R1 < 1e-20:
                converged = True
            n_iter += 1
            if converged:
                break
            if n_iter > 500:
                raise RuntimeError(f"no convergence in the step to t = {t1:g}")
            force_reform = step < s["lsmin"]
            if not force_reform and norm_E1 > norm_Em:  # diverging: reform
                norm_Em = norm_Ei = norm_E1
                force_reform = True
            updated = False
            if not force_reform and s["max_ups"] > 0 and len(V) < s["max_ups"] - 1:
                D, G, H = step * ui, R0 - R1, R0 * step  # BFGSSolver::Update
                dg, dh = D @ G, D @ H
                c = np.sqrt(abs(dg / dh))
                if c <= s["cmax"]:
                    V.append(-H * c - G)
                    W.append(D / dg)
                    updated = True
            if not updated:
                K, lu = reform(config(U))
                V, W = [], []
            R0 = R1
        self.iterations += n_iter
        x1 = config(U)
        if not dynamic:
            return x1, np.zeros_like(x1), np.zeros_like(x1)
        a1 = acceleration(x1)
        return x1, v_n + dt * ((1.0 - gamma) * a_n + gamma * a1), a1

    def line_search(self, ui, R0, residual_at):
        """FELineSearch::DoLineSearch from s = 1: (s, the residual there)."""
        s_ = self.s
        step, r0 = 1.0, ui @ R0
        smin, rmin, n = step, abs(r0), 0
        while True:
            R1 = residual_at(step)
            if step < s_["lsmin"]:
                return 0.5, residual_at(0.5)
            r1 = ui @ R1
            if n == 0 or abs(r1) < rmin:
                smin, rmin = step, abs(r1)
            r = 0.0 if abs(r1) < 1e-17 else abs(r1 / r0)
            if r <= s_["lstol"]:
                return step, R1
            a = r0 / r1
            A, B = 1.0 + a * (step - 1.0), a * step * step
            D = B * B - 4.0 * A * B
            if D >= 0:
                step = (B + np.sqrt(D)) / (2.0 * A)
                if step < 0:
                    step = max((B - np.sqrt(D)) / (2.0 * A), 0.0)
            else:
                step = 0.5 * B / A
            n += 1
            if n >= s_["lsiter"]:
                return smin, residual_at(smin)


def run(path: Path, settings: dict) -> tuple[float, int, float]:
    """(solution norm over the last step's free DOFs, equilibrium iterations, end time)."""
    from tissuesim.febio import load_febio

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = load_febio(path)
    sim = scene.simulation
    solver = Quasin(sim, settings)
    model, body = solver.model, solver.body
    x = sim.state.x.copy()
    rest = x.copy()
    v, a = np.zeros_like(x), np.zeros_like(x)
    t = 0.0
    for phase in sim.schedule.phases:
        dt, steps = phase.time_step, phase.steps
        dtmax = getattr(phase.adaptive, "dtmax", None)
        if dtmax is not None and dtmax < dt:
            steps, dt = round(steps * dt / dtmax), dtmax
        if phase.integrator not in ("quasistatic", "newmark"):
            raise SystemExit(f"{path.name}: {phase.integrator!r}: this script replays Newmark only")
        dynamic = phase.integrator == "newmark"
        if dynamic and t == 0.0:  # InitAccelerations: a_0 = M^-1 f(0) on the free DOFs
            body.set_condition_time(dt, 1e-9 * dt)
            free = np.ones(x.size, dtype=bool)
            free[model.prescribed_dofs] = False
            f0 = model.external_force(0.0)[free]
            if np.any(f0):
                a[free] = spla.spsolve(solver.M[free][:, free].tocsc(), f0)
        start = t
        for k in range(steps):
            t1 = start + (k + 1) * dt
            body.set_condition_time(t1, 1e-9 * dt)
            x, v, a = solver.step(x, v, a, t1, dt, dynamic)
            t = t1
    free = np.ones(x.size, dtype=bool)
    free[model.prescribed_dofs] = False
    return float(np.linalg.norm((x - rest)[free])), solver.iterations, t


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("deck", type=Path)
    parser.add_argument("--tight", action="store_true", help="dtol 1e-9, etol 1e-14")
    parser.add_argument("--gold", type=Path, help="FEBio's recorded norms (a gold .py file)")
    args = parser.parse_args(argv)
    settings = deck_settings(args.deck)
    if args.tight:
        settings.update(dtol=1e-9, etol=1e-14)
    norm, iterations, t = run(args.deck, settings)
    line = (f"{args.deck.stem}: dtol {settings['dtol']:g}, etol {settings['etol']:g}: norm "
            f"{norm:.12g} at t = {t:g}, {iterations} iterations")  # fmt: skip
    if args.gold:
        text = args.gold.read_text()
        record = ast.literal_eval(text[text.index("{") : text.rindex("}") + 1]).get(args.deck.stem)
        if record:
            febio = float(record[-1])
            line += f"; FEBio {febio:.12g} ({norm / febio - 1.0:+.1e}), {record[2]} iterations"
    print(line)
    return 0


if __name__ == "__main__":
    sys.exit(main())
