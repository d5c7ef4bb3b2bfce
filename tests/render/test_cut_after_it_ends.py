"""Issue 41: in the pictures, the blade's swept surface hid the organs after the cut had ended
(``organs_rest_after_cut``: a red sheet over the liver for the rest of the run). It is drawn
as a translucent sheet only while a blade sweeps, and as its outline once every cut has ended
(render/overlays.py)."""

from __future__ import annotations

import types

import numpy as np
import pytest

import tissuesim as ts
from tissuesim.io.series.bodies import FemSeries
from tissuesim.render.overlays import cut_outline


def sheet(lower, upper, z: float, n: int = 6) -> np.ndarray:
    """A flat swept surface (2 n^2, 3, 3) over [lower, upper] at height z, as a blade sweeps
    it: a grid of triangles, each its own corners."""
    x = np.linspace(lower[0], upper[0], n + 1)
    y = np.linspace(lower[1], upper[1], n + 1)
    X, Y = np.meshgrid(x, y, indexing="ij")
    P = np.stack([X, Y, np.full_like(X, z)], axis=-1)
    a, b, c, d = P[:-1, :-1], P[1:, :-1], P[1:, 1:], P[:-1, 1:]
    return np.concatenate([np.stack([a, b, c], 2), np.stack([a, c, d], 2)]).reshape(-1, 3, 3)


def test_the_outline_of_a_swept_sheet_is_its_border():
    cut = sheet((0, 0), (1, 2), 0.5, n=4)
    border = cut_outline(cut)
    assert border.shape == (16, 2, 3)  # 4 segments per side
    length = np.linalg.norm(border[:, 1] - border[:, 0], axis=1).sum()
    assert length == pytest.approx(6.0)  # the perimeter
    mid = border.mean(axis=1)
    on_side = np.isclose(mid[:, 0], 0) | np.isclose(mid[:, 0], 1)
    on_side |= np.isclose(mid[:, 1], 0) | np.isclose(mid[:, 1], 2)
    assert on_side.all()


def seen(path) -> tuple[float, float]:
    """(red, organ): the fractions of the picture (left of its colour bars) that are reddish
    (the cut: red over white or over the organ) and the organ's own teal (J = 1)."""
    from PIL import Image

    img = np.asarray(Image.open(path).convert("RGB")).astype(int)
    r, g, b = (img[:, : int(0.78 * img.shape[1]), k] for k in range(3))
    return float(((r > g + 40) & (r > b + 40)).mean()), float(((g > r + 50) & (b > r + 50)).mean())


def organ_under_a_cut(cut_end: float):
    """An organ under a blade's swept sheet, and the one frame of a run at t = 1 s; the blade
    swept from t = 0 to ``cut_end``."""
    sim = ts.Simulation(integrator="quasistatic")
    material = ts.make_material("neo_hookean", youngs_modulus=1e4, poisson_ratio=0.3)
    sim.add_body("organ", ts.ellipsoid((0, 0, 0), (0.06, 0.04, 0.02), 4), material)
    sim.build()
    data = FemSeries(sim.body("organ")).write(sim, 1.0)
    sim.tissue = types.SimpleNamespace(cuts=[types.SimpleNamespace(start=0.0, end=cut_end)])
    cut = sheet((-0.08, -0.06), (0.08, 0.06), 0.03)  # over the organ, larger than it
    return sim, [(1.0, {"organ": data}, cut, "")]


@pytest.mark.parametrize("cut_end, cutting", [(0.5, False), (2.0, True)])
def test_a_cut_that_has_ended_does_not_hide_the_organ(tmp_path, cut_end, cutting):
    pytest.importorskip("pyvista")
    from tissuesim.render.scene import render_run

    sim, frames = organ_under_a_cut(cut_end)
    render_run(sim, frames, tmp_path)
    red, organ = seen(tmp_path / "final.png")
    if cutting:  # while the blade sweeps: the translucent sheet tints the organ under it
        assert red > 0.1 and organ < 0.05  # measured: 0.15, 0.03
    else:  # ended: its outline only, the whole organ seen (today's code: as while cutting)
        assert red < 0.01 and organ > 0.06  # measured: 0.004, 0.08
