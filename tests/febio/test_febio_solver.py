"""FEBio's quasi-Newton as a solver option (``NewtonOptions(method="febio")``,
solve/quasin.py; ``--febio-solver``): on a Newmark cantilever of our own it is FEBio's loop
replayed by benchmarks/febio_quasin.py (the replay gives FEBio's recorded norms and iteration
counts of ms01, ms02, dy02), with tight tolerances it is tissuesim's Newton, it counts
iterations as FEBio does, and bad settings are refused in one line."""

from __future__ import annotations

import dataclasses
import importlib.util
import warnings
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

from tissuesim.assembly.pattern import SparsityPattern
from tissuesim.constraints.dirichlet import Elimination
from tissuesim.energies.accumulator import Accumulator
from tissuesim.errors import InputError
from tissuesim.solve.febio_settings import FebioSettings
from tissuesim.solve.linear import SuperLUSolver
from tissuesim.solve.newton import NewtonOptions
from tissuesim.solve.quasin import minimize_febio

HERE = Path(__file__).resolve().parent


def _load(name: str, path: Path):
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


REPLAY = _load("febio_quasin", HERE.parents[1] / "benchmarks" / "febio_quasin.py")
DECK = _load("newmark_deck", HERE / "test_newmark_is_febios_step.py")._deck


def _run(deck: Path, settings: FebioSettings | None, febio_solver: bool = False):
    """(norm of the free displacement at the end, Newton iterations summed, end time)."""
    from tissuesim.febio import load_febio

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = load_febio(deck, febio_solver=febio_solver)
    sim = scene.simulation
    if settings is not None:
        sim.newton = dataclasses.replace(sim.newton, method="febio", febio=settings)
    rest = sim.state.x.copy()
    iterations = sum(sim.step().newton_iterations for _ in range(scene.run["steps"]))
    free = np.ones(rest.size, dtype=bool)
    free[sim.body().model.prescribed_dofs] = False
    return float(np.linalg.norm((sim.state.x - rest)[free])), iterations, sim.time


@pytest.fixture(scope="module")
def deck(tmp_path_factory) -> Path:
    return DECK(tmp_path_factory.mktemp("febio_solver") / "cantilever.feb")


def test_the_option_is_febios_loop_as_the_replay_runs_it(deck):
    settings = REPLAY.deck_settings(deck)
    febio, febio_iterations, t = REPLAY.run(deck, settings)
    ours, iterations, t_ours = _run(deck, None, febio_solver=True)  # the deck's <solver>
    assert t_ours == pytest.approx(t)
    assert ours == pytest.approx(febio, rel=1e-10)
    assert iterations == febio_iterations  # FEBio's equilibrium iterations, counted alike
    newton, _, _ = _run(deck, None)
    assert abs(ours / newton - 1.0) > 1e-4  # FEBio's stopping point, not tissuesim's


def test_tight_tolerances_give_tissuesims_newton(deck):
    newton, newton_iterations, _ = _run(deck, None)
    for method, each_step in (("BFGS", True), ("Broyden", True), ("full Newton", True),
                              ("BFGS", False)):  # fmt: skip
        tight = FebioSettings(dtol=1e-9, etol=1e-14, qn_method=method,
                              reform_each_time_step=each_step)  # fmt: skip
        ours, iterations, _ = _run(deck, tight)
        assert ours == pytest.approx(newton, rel=1e-8), method
        assert iterations >= newton_iterations


def _quadratic(n: int = 6, shift: float = 0.0):
    """Phi = x'Ax/2 + c sum x^4/4 - b'x on a chain; ``shift`` moves b (the lag)."""
    rows = np.r_[np.arange(n - 1), np.arange(1, n)]
    cols = np.r_[np.arange(1, n), np.arange(n - 1)]
    pattern = SparsityPattern.from_entries(n, rows, cols)
    A = sp.diags([-np.ones(n - 1), 2.5 * np.ones(n), -np.ones(n - 1)], [-1, 0, 1]).tocsr()
    lag = {"b": np.linspace(1.0, 2.0, n), "relags": 0}

    def evaluate(x, order, project):
        acc = Accumulator(pattern, order)
        acc.value = 0.5 * x @ A @ x + 0.25 * np.sum(x**4) - lag["b"] @ x
        if order >= 1:
            acc.gradient[:] = A @ x + x**3 - lag["b"]
        if order >= 2:
            H = (A + sp.diags(3.0 * x**2)).tocsr()
            acc.hessian[:] = np.asarray(H[pattern.keys() // n, pattern.keys() % n]).ravel()
        return acc

    def relag(x):  # FEBio's augmentation: b moves once, then stays
        lag["relags"] += 1
        if lag["relags"] > 1 or shift == 0.0:
            return False
        lag["b"] = lag["b"] + shift
        return True

    elimination = Elimination.build(pattern, np.array([0]))
    return evaluate, relag, elimination, lag


def test_an_augmentation_that_changes_something_iterates_on():
    evaluate, relag, elimination, lag = _quadratic(shift=0.5)
    options = NewtonOptions(method="febio", febio={"dtol": 1e-10, "etol": 1e-16})
    x, record = minimize_febio(evaluate, np.zeros(6), elimination, SuperLUSolver(), options,
                               relag=relag, max_relags=5)  # fmt: skip
    assert record.converged and record.relags == 2  # changed once, then settled
    assert np.linalg.norm(evaluate(x, 1, False).gradient[1:]) < 1e-8
    assert lag["b"][0] == pytest.approx(1.5)
    assert record.iterations == len(record.step_lengths)


def test_a_step_past_max_refs_fails_as_febios_does():
    evaluate, _, elimination, _ = _quadratic()
    options = NewtonOptions(method="febio", febio={"max_ups": 0, "max_refs": 1, "etol": 1e-16})
    x0 = np.zeros(6)
    x, record = minimize_febio(evaluate, x0, elimination, SuperLUSolver(), options)
    assert not record.converged and "max_refs" in record.reason
    assert np.array_equal(x, x0)


@pytest.mark.parametrize(
    ("table", "message"),
    [
        ({"dtol": -1.0}, "febio.dtol must be >= 0"),
        ({"lsiter": 2.5}, "febio.lsiter must be an integer"),
        ({"qn_method": "JFNK"}, "febio.qn_method must be one of"),
        ({"diverge_reform": 1}, "febio.diverge_reform must be true or false"),
        ({"max_refs": 0}, "febio.max_refs must be an integer in 1..10000"),
        ({"dtl": 1e-3}, "febio: unknown setting 'dtl'"),
        ({"dtol": 0.0, "etol": 0.0}, "nothing would stop a step"),
    ],
)
def test_bad_settings_are_refused_in_one_line(table, message):
    with pytest.raises(InputError, match=message) as info:
        NewtonOptions(method="febio", febio=table)
    assert "\n" not in str(info.value)


def test_settings_without_the_method_and_a_bad_method_are_refused():
    with pytest.raises(InputError, match="used by method = 'febio' only"):
        NewtonOptions(febio={"dtol": 1e-3})
    with pytest.raises(InputError, match="method must be one of"):
        NewtonOptions(method="bfgs")
    assert NewtonOptions(method="febio").febio == FebioSettings()


def test_convert_writes_the_decks_solver_only_with_the_flag(deck, tmp_path):
    from tissuesim.febio import convert_febio

    text = deck.read_text().replace(
        "<etol>0.01</etol></solver>",
        '<etol>0.01</etol><qn_method type="Broyden"><max_ups>25</max_ups></qn_method>'
        "<diverge_reform>0</diverge_reform></solver>",
        1,
    )
    model = tmp_path / "m.feb"
    model.write_text(text)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        convert_febio(model, tmp_path / "plain.toml")
        convert_febio(model, tmp_path / "febio.toml", febio_solver=True)
    plain = (tmp_path / "plain.toml").read_text()
    assert "febio" not in plain.replace("FEBio", "")
    written = (tmp_path / "febio.toml").read_text()
    assert 'method = "febio"' in written
    for part in ('qn_method = "Broyden"', "max_ups = 25", "diverge_reform = false", "dtol = "):
        assert part in written
    # the first step's settings are used now; the second step's are not (a note still)
    assert plain.count("FEBio's solver settings") == 2
    assert written.count("FEBio's solver settings") == 1


def test_the_cli_refuses_the_flag_on_a_scene(tmp_path):
    from tissuesim.cli import main

    scene = tmp_path / "s.toml"
    scene.write_text("")
    assert main(["run", str(scene), "--febio-solver", "--out", str(tmp_path / "o")]) == 2


def test_a_follower_pressure_is_febios_in_every_residual(deck, tmp_path):
    """The cantilever pushed down by a follower pressure on its top face: FEBio's loop takes
    the load at x in every residual (no re-lags) and, tight, lands on tissuesim's Newton,
    whose lagged load is re-lagged to the same fixed point."""
    top = "".join(
        f'<quad4 id="{i + 1}">{1 + i + 8},{2 + i + 8},{6 + i + 8},{5 + i + 8}</quad4>'
        for i in range(3)
    )
    text = deck.read_text().replace("</NodeSet></Mesh>", f'</NodeSet><Surface name="top">{top}'
                                    "</Surface></Mesh>", 1)  # fmt: skip
    text = text.replace(
        '<nodal_load node_set="tip" type="nodal_force">\n        <value lc="1">0,0,2</value>'
        "</nodal_load>",
        '<surface_load surface="top" type="pressure"><pressure lc="1">5</pressure></surface_load>',
    )
    assert "surface_load" in text
    model = tmp_path / "pressed.feb"
    model.write_text(text)
    newton, _, _ = _run(model, None)
    tight, _, _ = _run(model, FebioSettings(dtol=1e-9, etol=1e-14))
    febio, _, _ = _run(model, None, febio_solver=True)
    assert tight == pytest.approx(newton, rel=1e-7)
    assert abs(febio / newton - 1.0) > 1e-5


def test_an_inverted_iterate_fails_the_step_instead_of_crashing():
    """An iterate where the potential is undefined (an inverted element: infinite energy,
    with a finite gradient) fails the solve, as FEBio's negative jacobian fails its step, so
    the stepper retries it smaller (it crashed the linear solver later: co34, co36, co37)."""
    evaluate, _, elimination, _ = _quadratic()

    def inverted(x, order, project):
        acc = evaluate(x, order, project)
        if np.max(np.abs(x)) > 0.1:  # past here the "elements" are inverted
            acc.value = np.inf
        return acc

    x0 = np.zeros(6)
    options = NewtonOptions(method="febio", febio={"lsiter": 0})  # no line search rescue
    x, record = minimize_febio(inverted, x0, elimination, SuperLUSolver(), options)
    assert not record.converged and "inverted" in record.reason
    assert np.array_equal(x, x0)


def test_a_stiffness_that_is_not_finite_fails_the_step_instead_of_crashing():
    """A stiffness with NaN (an inverted element's) fails the solve in one reason, where
    PARDISO's analysis raised out of the step (co10 with --febio-solver)."""
    evaluate, _, elimination, _ = _quadratic()

    def broken(x, order, project):
        acc = evaluate(x, order, project)
        if order >= 2:
            acc.hessian[:] = np.nan
        return acc

    options = NewtonOptions(method="febio")
    x, record = minimize_febio(broken, np.zeros(6), elimination, SuperLUSolver(), options)
    assert not record.converged and "not finite" in record.reason


def test_a_step_febios_solver_gives_up_on_is_solved_by_tissuesims_newton(deck):
    """max_refs 1 with no BFGS updates: FEBio's loop gives up on the cantilever's first step.
    With the fallback (the default) tissuesim's Newton solves that step and the run is
    tissuesim's Newton's; without it the step is halved until the run fails."""
    from tissuesim.errors import ConvergenceError

    hopeless = {"max_ups": 0, "max_refs": 1, "etol": 1e-16, "dtol": 1e-16}
    newton, _, t_newton = _run(deck, None)
    ours, _, t = _run(deck, hopeless)
    assert t == pytest.approx(t_newton)
    assert ours == pytest.approx(newton, rel=1e-9)
    from tissuesim.febio import load_febio

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sim = load_febio(deck).simulation
    sim.newton = dataclasses.replace(sim.newton, method="febio", febio=hopeless)
    record = sim.step()
    assert record.extra["newton_fallback"] >= 1
    sim.newton = dataclasses.replace(sim.newton, febio_fallback=False)
    with pytest.raises(ConvergenceError, match="max_refs"):
        sim.step()


def test_febios_stepper_cuts_a_step_back_before_falling_back_to_newton(deck):
    """With FEBio's adaptive stepper, a step FEBio's solver gives up on is cut back as FEBio
    cuts it (max_retries times) and only the last attempt falls back to tissuesim's Newton,
    so the steps stay FEBio's where a shorter step is enough (dy03, dy04, sh59 of FEBio's
    suite); without the stepper the fallback comes at once (the test above)."""
    from tissuesim.febio import load_febio
    from tissuesim.time.adaptive import attempt_options

    hopeless = {"max_ups": 0, "max_refs": 1, "etol": 1e-16, "dtol": 1e-16}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sim = load_febio(deck).simulation
    sim.newton = dataclasses.replace(sim.newton, method="febio", febio=hopeless)
    sim.set_adaptive({"dtmax": 0.5, "dtmin": 0.01, "max_retries": 2, "opt_iter": 10})
    record = sim.step()
    assert record.extra["adaptive"]["retries"] == 2  # two cut-backs, each failed by Quasin
    assert record.extra["newton_fallback"] == 1  # then the last attempt's fallback
    assert record.extra["adaptive"]["dt"] == pytest.approx(0.5 * (1 - 2 / 3))
    # the options of an attempt: the fallback only where it is the last one
    assert attempt_options(sim.newton, last=False).febio_fallback is False
    assert attempt_options(sim.newton, last=True) is sim.newton
    plain = dataclasses.replace(sim.newton, method="newton", febio=None)
    assert attempt_options(plain, last=False) is plain


def test_febios_solver_factors_directly_where_the_run_chose_an_iterative_solver():
    """FEBio factors its stiffness: where "auto" chose CG for a large model (mi39, 73k DOFs)
    the Quasin factors with PARDISO or CHOLMOD (it fell to SuperLU: 67 s a factorisation),
    and an indefinite stiffness that the Cholesky refuses is factored too (PARDISO's LU where
    installed, else SuperLU)."""
    from tissuesim.solve.linear import CGSolver, has_cholmod, has_pardiso
    from tissuesim.solve.quasin import _direct_factor

    rng = np.random.default_rng(3)
    B = sp.random(40, 40, density=0.2, random_state=3)
    spd = (B @ B.T + 40 * sp.eye(40)).tocsr()
    indefinite = (spd - 45 * sp.eye(40)).tocsr()  # eigenvalues on both sides of 0
    assert (
        np.linalg.eigvalsh(indefinite.toarray()).min()
        < 0
        < np.linalg.eigvalsh(indefinite.toarray()).max()
    )
    b = rng.standard_normal(40)
    for A in (spd, indefinite):
        solve = _direct_factor(CGSolver("jacobi"), A)
        assert np.linalg.norm(A @ solve(b) - b) < 1e-10 * np.linalg.norm(b)
    if has_pardiso() or has_cholmod():
        import tissuesim.solve.quasin as quasin

        called = []
        real = quasin.spla.splu
        quasin.spla.splu = lambda *a, **k: called.append(1) or real(*a, **k)
        try:
            _direct_factor(CGSolver("jacobi"), spd)
        finally:
            quasin.spla.splu = real
        assert not called  # a fast direct solver, not SuperLU


@pytest.mark.skipif(importlib.util.find_spec("pypardiso") is None, reason="needs pypardiso")
def test_pardisos_lu_releases_its_memory_with_its_factor():
    """PARDISO keeps a factor until told; one per reformation filled 17 GB (sh29, oi01 of
    FEBio's suite killed): a factor let go of releases PARDISO's memory."""
    import gc

    from tissuesim.solve.quasin import _PardisoLU

    A = sp.diags([-1.0, 2.5, -1.0], [-1, 0, 1], shape=(50, 50)).tocsr()
    lu = _PardisoLU(A)
    assert np.allclose(A @ lu(np.ones(50)), 1.0)
    release = lu._release
    assert release.alive
    del lu
    gc.collect()
    assert not release.alive
