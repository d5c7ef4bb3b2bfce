"""Issue 41: the pictures' colour range was the whole run's, so a frame after the peak (a torn
strip relaxed at its end) was drawn uniformly dark. final.png now takes its own frame's range;
run.gif keeps one range for the run, so its frames compare (render/scene.py)."""

from __future__ import annotations

import numpy as np
import pytest

import tissuesim as ts

PEAK, END = 0.02, 0.001  # m: the pull's largest displacement, and where it ends


def _pull_and_release(dim: int) -> ts.Simulation:
    """A strip pulled out to PEAK at t = 0.5 and let back to END at t = 1."""
    sim = ts.Simulation(integrator="quasistatic", time_step=0.25)
    material = ts.make_material("neo_hookean", youngs_modulus=1e4, poisson_ratio=0.3)
    if dim == 2:
        mesh = ts.rectangle((0, 0), (0.1, 0.02), (4, 1))
    else:
        mesh = ts.box((0, 0, 0), (0.1, 0.02, 0.02), (4, 1, 1))
    sim.add_body("strip", mesh, material)
    x = sim.body("strip").mesh.points[:, 0]
    sim.fix(np.flatnonzero(x < 1e-9))
    pull = lambda X, t: np.tile(  # noqa: E731
        [PEAK * np.sin(np.pi * t) + END * t] + [0.0] * (dim - 1), (len(X), 1)
    )
    sim.add_dirichlet(np.flatnonzero(x > 0.1 - 1e-9), pull)
    return sim


def test_final_png_of_a_2d_run_has_its_own_frames_range(tmp_path, monkeypatch):
    from tissuesim.render import plot2d

    seen = {}
    real_png, real_gif = plot2d.render_frame_png, plot2d.render_gif

    def png(*args, vmin=None, vmax=None, **kwargs):
        seen["final"] = (vmin, vmax)
        return real_png(*args, vmin=vmin, vmax=vmax, **kwargs)

    def gif(*args, vmin=None, vmax=None, **kwargs):
        seen["gif"] = (vmin, vmax)
        return real_gif(*args, vmin=vmin, vmax=vmax, **kwargs)

    monkeypatch.setattr(plot2d, "render_frame_png", png)
    monkeypatch.setattr(plot2d, "render_gif", gif)
    sim = _pull_and_release(2)
    sim.run(4, tmp_path / "out", progress=False, field="displacement")
    assert (tmp_path / "out" / "final.png").is_file()
    lo, hi = seen["final"]
    assert lo == 0.0 and END / 2 < hi <= END * 1.001  # the last frame's own range (by cell)
    assert seen["gif"][1] > 0.9 * PEAK  # the GIF: the run's range, its frames compare


def test_final_png_of_a_3d_run_has_its_own_frames_range(tmp_path, monkeypatch):
    pytest.importorskip("pyvista")
    from tissuesim.render import gif3d, pyvista3d

    seen = {}

    def png(path, frame, **kwargs):
        seen["final"] = frame.surfaces[0].clim
        return None

    class Gif:
        def __init__(self, *args, **kwargs):
            pass

        def add(self, frame):
            seen["gif"] = frame.surfaces[0].clim

        def close(self):
            pass

    monkeypatch.setattr(pyvista3d, "render_frame_png", png)
    monkeypatch.setattr(gif3d, "GifWriter", Gif)
    sim = _pull_and_release(3)
    sim.run(4, tmp_path / "out", progress=False, field="displacement")
    lo, hi = seen["final"]
    assert lo == 0.0 and END / 2 < hi <= END * 1.001
    assert seen["gif"][1] > 0.9 * PEAK
