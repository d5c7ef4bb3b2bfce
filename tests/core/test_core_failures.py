"""How a simulation fails: a clear ConvergenceError, a summary that says "failed", a frame
series that stays readable; and set-up mistakes refused with errors that name them."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET

import meshio
import numpy as np
import pytest

import tissuesim as ts
from tissuesim.errors import ConvergenceError, InputError, TissueSimError
from tissuesim.mesh import select


def squash(X, t):
    """Edges x = -1 and x = 1 driven towards each other: they meet at t = 2/3 and pass."""
    return np.column_stack([-1.5 * X[:, 0] * t, np.zeros(len(X))])


def squashed_square(**options):
    mesh = ts.rectangle(lower=(-1, -1), upper=(1, 1), divisions=(4, 4))
    sim = ts.Simulation(
        mesh,
        ts.NeoHookean(youngs_modulus=1e3, poisson_ratio=0.3),  # refuses J <= 0
        time_step=0.4,
        max_step_halvings=2,
        newton=ts.NewtonOptions(max_iterations=5),
        **options,
    )
    for side in (-1.0, 1.0):
        sim.add_dirichlet(select.vertices_on_plane(mesh, 0, side), squash)
    return sim


def test_non_converging_step_raises_a_helpful_convergence_error():
    sim = squashed_square()
    with pytest.raises(ConvergenceError) as info:
        for _ in range(5):
            sim.step()
    message = str(info.value)
    assert "did not converge" in message
    assert "from t = " in message  # names the time
    assert "after 2 halvings" in message
    for advice in ("smaller time_step", "newton.max_iterations", "course_neo_hookean"):
        assert advice in message
    # The failed step left the simulation at the last converged state.
    assert len(sim.history) >= 1
    assert sim.time == pytest.approx(sim.history[-1].time)
    assert np.all(sim.cell_fields()["J"] > 0)


def test_a_failing_quasistatic_step_says_to_apply_the_load_gradually():
    """Full gravity on a soft beam from the first quasistatic step: a shorter step is the same
    problem (the load does not depend on t), so the error says to ramp the load instead."""
    mesh = ts.box((0.0, 0.0, 0.0), (1.0, 0.4, 0.4), (3, 1, 1))
    sim = ts.Simulation(
        mesh,
        ts.make_material("neo_hookean", youngs_modulus=3e3, poisson_ratio=0.45),
        density=1000.0,
        integrator="quasistatic",
        time_step=1.0,
        gravity=(0.0, 0.0, -9.81),
        max_step_halvings=1,
        newton=ts.NewtonOptions(max_iterations=3),
    )
    sim.fix(select.vertices_on_plane(mesh, 0, 0.0))
    with pytest.raises(ConvergenceError) as info:
        sim.step()
    message = str(info.value)
    assert "apply the load gradually" in message and "backward_euler" in message
    assert "smaller time_step" not in message


def test_failed_run_leaves_valid_output(tmp_path):
    sim = squashed_square()
    out = tmp_path / "run"
    with pytest.raises(ConvergenceError):
        sim.run(5, output=out, progress=False, render=False)

    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "failed"
    assert "did not converge" in summary["error"]
    assert summary["totals"]["steps"] == len(sim.history) == len(summary["steps"])
    assert all(step["converged"] for step in summary["steps"])

    root = ET.parse(out / "body.pvd").getroot()
    rows = root.find("Collection").findall("DataSet")
    assert len(rows) == 1 + len(sim.history)
    listed = {r.get("file") for r in rows}
    on_disk = {p.name for p in out.glob("*.vtu")}
    assert listed == on_disk  # no stray or missing frames, no temporary files left
    assert not [p for p in out.iterdir() if p.name.startswith(".")]
    for row in rows:
        frame = meshio.read(out / row.get("file"))
        assert frame.points.shape == (sim.mesh.n_points, 3)
        assert np.all(np.isfinite(frame.point_data["displacement"]))
        assert np.all(frame.cell_data["J"][0] > 0)
    last = meshio.read(out / rows[-1].get("file"))
    # rest points + displacement (ParaView's Warp By Vector) = the positions it failed at
    np.testing.assert_allclose(last.points[:, :2], sim.mesh.points)
    np.testing.assert_allclose(
        last.points[:, :2] + last.point_data["displacement"][:, :2], sim.positions
    )


def test_any_crash_during_a_run_marks_the_summary_failed(tmp_path):
    mesh = ts.rectangle(divisions=(2, 2))
    sim = ts.Simulation(mesh, ts.LinearElastic(youngs_modulus=1e3, poisson_ratio=0.3))

    def broken(X, t):
        if t > 0.015:
            raise RuntimeError("boundary data unavailable")
        return np.zeros_like(X)

    sim.add_dirichlet(select.vertices_on_plane(mesh, 0, 0.0), broken)
    with pytest.raises(RuntimeError):
        sim.run(3, output=tmp_path, progress=False, render=False)
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["status"] == "failed"
    assert "RuntimeError: boundary data unavailable" in summary["error"]
    assert summary["totals"]["steps"] == 1


def test_quasistatic_without_dirichlet_conditions_is_refused():
    sim = ts.Simulation(
        ts.rectangle(divisions=(2, 2)),
        ts.LinearElastic(youngs_modulus=1e3, poisson_ratio=0.3),
        integrator="quasistatic",
    )
    sim.add_gravity([0.0, -9.81])
    with pytest.raises((ValueError, TissueSimError), match="rigid motions"):
        sim.step()
    assert sim.history == [] and sim.time == 0.0


def test_quasistatic_with_too_few_prescribed_dofs_is_refused():
    mesh = ts.rectangle(divisions=(2, 2))
    sim = ts.Simulation(
        mesh, ts.LinearElastic(youngs_modulus=1e3, poisson_ratio=0.3), integrator="quasistatic"
    )
    sim.add_dirichlet([0], components=[0])
    with pytest.raises(ValueError, match="rigid motions"):
        sim.step()


def test_a_lone_body_free_along_an_axis_is_named_once():
    """A biaxial test holding x on two faces and y on the other two (FEBio's ma57) leaves z
    free: the equilibria are a family shifted along z, and one warning says so (once, not per
    step); the solve still ends at one of them (the stretch right). Held in z at one vertex:
    no warning."""
    import warnings

    mesh = ts.box(upper=(1.0, 1.0, 0.1), divisions=(2, 2, 1))
    p = mesh.points
    for hold_z in (False, True):
        sim = ts.Simulation(mesh, MATERIAL, integrator="quasistatic", time_step=0.5)
        for k in (0, 1):
            sim.add_dirichlet(np.flatnonzero(np.isclose(p[:, k], 0.0)), components=[k])
            sim.add_dirichlet(
                np.flatnonzero(np.isclose(p[:, k], 1.0)),
                displacement=lambda x, t, k=k: np.eye(3)[k] * 0.01 * t,
                components=[k],
            )
        if hold_z:
            sim.add_dirichlet([0], components=[2])
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            sim.step()
            sim.step()
        free = [w for w in caught if "no condition holds it along z" in str(w.message)]
        assert len(free) == (0 if hold_z else 1), [str(w.message) for w in caught]
        u = sim.body_positions("body") - p
        np.testing.assert_allclose(u[:, 0], 0.01 * p[:, 0], atol=1e-9)


MESH = ts.rectangle(divisions=(2, 2))
MATERIAL = ts.LinearElastic(youngs_modulus=1e3, poisson_ratio=0.3)


@pytest.mark.parametrize("time_step", [0.0, -0.1, float("nan"), float("inf"), True, "0.1"])
def test_bad_time_step_is_refused(time_step):
    with pytest.raises(ValueError, match="time_step"):
        ts.Simulation(MESH, MATERIAL, time_step=time_step)


def test_unknown_integrator_is_refused():
    with pytest.raises(ValueError, match="integrator") as info:
        ts.Simulation(MESH, MATERIAL, integrator="runge_kutta")
    assert "runge_kutta" in str(info.value) and "backward_euler" in str(info.value)


def test_bad_max_step_halvings_and_linear_solver_are_refused():
    with pytest.raises(ValueError, match="max_step_halvings"):
        ts.Simulation(MESH, MATERIAL, max_step_halvings=-1)
    with pytest.raises(ValueError, match="linear_solver"):
        ts.Simulation(MESH, MATERIAL, newton=ts.NewtonOptions(linear_solver="magic"))


@pytest.mark.parametrize("vertices", [[MESH.n_points], [-1], [0, 10_000]])
def test_dirichlet_vertices_out_of_range(vertices):
    sim = ts.Simulation(MESH, MATERIAL)
    with pytest.raises(ValueError, match="vertex indices must be in"):
        sim.add_dirichlet(vertices)


def test_dirichlet_bad_components_and_empty_selection():
    sim = ts.Simulation(MESH, MATERIAL)
    with pytest.raises(ValueError, match="empty"):
        sim.add_dirichlet([])
    for components in ([], [2], [-1], 0, ["a"]):
        with pytest.raises(ValueError, match="components"):
            sim.add_dirichlet([0], components=components)
    assert sim.model.prescribed.dofs.size == 0  # nothing half-added


@pytest.mark.parametrize("bad", [0.0, -1.0, float("nan"), float("inf")])
def test_bad_density_names_the_element(bad):
    density = np.ones(MESH.n_cells)
    density[5] = bad
    with pytest.raises(ValueError, match="element 5"):
        ts.Simulation(MESH, MATERIAL, density=density)
    with pytest.raises(InputError, match="density must be"):
        ts.Simulation(MESH, MATERIAL, density=bad)


def test_bad_run_arguments():
    sim = ts.Simulation(MESH, MATERIAL)
    with pytest.raises(ValueError, match="steps"):
        sim.run(-1, progress=False, render=False)
    with pytest.raises(ValueError, match="every"):
        sim.run(1, every=0, progress=False, render=False)
