"""Frame shape functions: partition of unity, analytic gradients, compact support, errors."""

from __future__ import annotations

import numpy as np
import pytest

from tissuesim.frames.shape_functions import ShapeFunctions, auto_radii, shape_functions

KINDS = ["wendland", "shepard"]


def grid_frames() -> np.ndarray:
    """3 x 3 x 5 frames filling the box [0, 1] x [0, 1] x [0, 2]."""
    axes = (np.linspace(0, 1, 3), np.linspace(0, 1, 3), np.linspace(0, 2, 5))
    return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)


def random_points(q: int = 300, seed: int = 0) -> np.ndarray:
    return np.random.default_rng(seed).uniform([0, 0, 0], [1, 1, 2], size=(q, 3))


def dense(sf: ShapeFunctions, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Weights (q, n) and gradients (q, n, d), independent of the padded row layout."""
    q, k = sf.frames.shape
    real = np.arange(k)[None, :] < sf.count[:, None]
    rows = np.broadcast_to(np.arange(q)[:, None], (q, k))[real]
    cols = sf.frames[real]
    w = np.zeros((q, n))
    g = np.zeros((q, n, sf.gradients.shape[2]))
    w[rows, cols] = sf.weights[real]
    g[rows, cols] = sf.gradients[real]
    return w, g


def box_grid(nx: int = 41, ny: int = 9, nz: int = 9) -> np.ndarray:
    """Grid samples of the 2 x 0.4 x 0.4 box (long axis x)."""
    axes = (np.linspace(0, 2, nx), np.linspace(0, 0.4, ny), np.linspace(0, 0.4, nz))
    return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)


# --- partition of unity and gradients ------------------------------------------------------------


@pytest.mark.parametrize("kind", KINDS)
def test_partition_of_unity_and_zero_gradient_sum(kind):
    frames, pts = grid_frames(), random_points()
    sf = shape_functions(frames, pts, kind=kind)
    assert sf.kind == kind
    q = pts.shape[0]
    assert sf.frames.shape == (q, sf.width) and sf.frames.dtype == np.int64
    assert sf.weights.shape == (q, sf.width) and sf.weights.dtype == np.float64
    assert sf.gradients.shape == (q, sf.width, 3)
    assert sf.count.shape == (q,) and sf.count.dtype == np.int64
    assert sf.radii.shape == (frames.shape[0],)
    np.testing.assert_allclose(sf.weights.sum(axis=1), 1.0, rtol=0, atol=1e-14)
    np.testing.assert_allclose(sf.gradients.sum(axis=1), 0.0, rtol=0, atol=1e-12)
    assert np.all(sf.weights[np.arange(sf.width)[None, :] < sf.count[:, None]] > 0)
    # non-trivial: some points blend several frames with non-zero gradients
    assert sf.count.max() > 1 and np.abs(sf.gradients).max() > 0.1


@pytest.mark.parametrize("kind", KINDS)
def test_padding_layout(kind):
    frames = grid_frames()
    sf = shape_functions(
        frames, random_points(), kind=kind, radius=0.6 if kind == "wendland" else None
    )
    k = sf.width
    pad = np.arange(k)[None, :] >= sf.count[:, None]
    assert sf.count.max() == k
    assert np.all(sf.weights[pad] == 0) and np.all(sf.gradients[pad] == 0)
    # padding repeats a real frame of the row, so gathers stay in range
    first = np.broadcast_to(sf.frames[:, :1], sf.frames.shape)
    assert np.array_equal(sf.frames[pad], first[pad])
    # real entries are distinct and sorted by frame index (deterministic order)
    both_real = ~pad[:, 1:]
    assert np.all(np.diff(sf.frames, axis=1)[both_real] > 0)
    assert sf.frames.min() >= 0 and sf.frames.max() < frames.shape[0]


@pytest.mark.parametrize("kind", KINDS)
def test_gradients_match_finite_differences(kind):
    frames, pts = grid_frames(), random_points(q=60, seed=1)
    sf = shape_functions(frames, pts, kind=kind)
    n = frames.shape[0]
    _, g = dense(sf, n)
    radius = None if kind == "shepard" else sf.radii  # the SAME radii for the perturbed points
    h = 1e-5
    fd = np.zeros_like(g)
    for c in range(3):
        e = np.zeros(3)
        e[c] = h
        wp, _ = dense(shape_functions(frames, pts + e, kind=kind, radius=radius), n)
        wm, _ = dense(shape_functions(frames, pts - e, kind=kind, radius=radius), n)
        fd[:, :, c] = (wp - wm) / (2 * h)
    rel = np.abs(fd - g).max() / np.abs(g).max()
    assert rel < 1e-6, rel


def test_two_dimensional_frames():
    frames = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]])
    pts = np.random.default_rng(2).uniform(0, 1, size=(50, 2))
    for kind in KINDS:
        sf = shape_functions(frames, pts, kind=kind)
        assert sf.gradients.shape[2] == 2
        np.testing.assert_allclose(sf.weights.sum(axis=1), 1.0, rtol=0, atol=1e-14)
        np.testing.assert_allclose(sf.gradients.sum(axis=1), 0.0, rtol=0, atol=1e-12)


# --- Wendland compact support --------------------------------------------------------------------


def test_wendland_weights_vanish_exactly_outside_support():
    frames, pts = grid_frames(), random_points(q=400, seed=3)
    radii = np.random.default_rng(4).uniform(0.5, 0.9, size=frames.shape[0])
    sf = shape_functions(frames, pts, radius=radii)
    np.testing.assert_array_equal(sf.radii, radii)
    w, _ = dense(sf, frames.shape[0])
    dist = np.linalg.norm(pts[:, None, :] - frames[None, :, :], axis=2)
    inside = dist < radii[None, :]
    assert np.all(w[inside] > 0)
    assert np.all(w[~inside] == 0)  # frames beyond r are absent from the row
    np.testing.assert_array_equal(sf.count, inside.sum(axis=1))
    assert sf.count.max() < frames.shape[0]  # really compact: no row holds every frame


def test_wendland_known_values():
    frames = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    pts = np.array([[0.3, 0.0, 0.0], [0.8, 0.0, 0.0], [0.5, 0.0, 0.0]])
    r = 0.8
    sf = shape_functions(frames, pts, radius=r)
    # point 1 lies exactly on the support boundary of frame 0 (s = 1): not reached by it
    np.testing.assert_array_equal(sf.count, [2, 1, 2])

    def psi(s):
        return (1 - s) ** 4 * (4 * s + 1)

    def dpsi_dx(s, sign):  # d phi / dx along the axis, sign of (p - xbar)_x
        return -20 * (1 - s) ** 3 * sign * s * r / r**2

    a, b = psi(0.3 / r), psi(0.7 / r)
    np.testing.assert_allclose(sf.weights[0], [a / (a + b), b / (a + b)], rtol=1e-14)
    ga, gb = dpsi_dx(0.3 / r, 1.0), dpsi_dx(0.7 / r, -1.0)
    expected = [
        ga / (a + b) - a * (ga + gb) / (a + b) ** 2,
        gb / (a + b) - b * (ga + gb) / (a + b) ** 2,
    ]
    np.testing.assert_allclose(sf.gradients[0, :, 0], expected, rtol=1e-12)
    np.testing.assert_array_equal(sf.gradients[0, :, 1:], 0.0)
    # point 1 is reached only by frame 1: weight 1, zero gradient, frame 0 absent
    assert sf.frames[1, 0] == 1 and sf.weights[1, 0] == 1.0
    np.testing.assert_allclose(sf.gradients[1, 0], 0.0, atol=1e-15)
    # midway between the frames: equal weights, opposite gradients along x
    np.testing.assert_allclose(sf.weights[2], [0.5, 0.5], rtol=0, atol=1e-15)
    gx = sf.gradients[2, :, 0]
    assert gx[0] < 0 < gx[1]


def test_wendland_weight_is_c2_continuous_across_the_support_boundary():
    frames = np.array([[0.0, 0.0, 0.0], [0.5, 0.0, 0.0]])
    r = 1.0
    deltas = np.array([1e-2, 5e-3, 1e-6])
    inside = np.column_stack([r * (1 - deltas), np.zeros(3), np.zeros(3)])
    outside = np.array([[r * (1 + 1e-6), 0.0, 0.0]])
    sf = shape_functions(frames, np.vstack([inside, outside]), radius=r)
    w, g = dense(sf, 2)
    # just inside the support of frame 0: tiny weight and gradient, so no jump at s = 1
    assert 0 < w[2, 0] < 1e-20
    assert np.abs(g[2, 0]).max() < 1e-15
    # just outside: exactly zero, and frame 0 is not in the row
    assert w[3, 0] == 0 and sf.count[3] == 1 and sf.frames[3, 0] == 1
    # the weight fades like (1 - s)^4 (C2 kernel): halving 1 - s divides it by about 16
    ratio = w[0, 0] / w[1, 0]
    assert 14 < ratio < 18, ratio


# --- automatic radii ---------------------------------------------------------------------------


@pytest.mark.parametrize("n_frames", [2, 4, 8, 16])
def test_auto_radii_cover_a_long_box_with_a_line_of_frames(n_frames):
    pts = box_grid()
    x = np.linspace(0, 2, n_frames)
    frames = np.column_stack([x, np.full(n_frames, 0.2), np.full(n_frames, 0.2)])
    sf = shape_functions(frames, pts)
    assert np.all(sf.count >= 1)
    np.testing.assert_allclose(sf.weights.sum(axis=1), 1.0, rtol=0, atol=1e-14)
    np.testing.assert_array_equal(sf.radii, auto_radii(frames, pts))
    # every point lies strictly inside the support of at least one frame
    dist = np.linalg.norm(pts[:, None, :] - frames[None, :, :], axis=2)
    assert np.all((dist < sf.radii[None, :]).any(axis=1))


def test_auto_radii_formula():
    frames = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [3.0, 0.0, 0.0]])
    samples = np.array([[-0.5, 0.0, 0.0], [0.9, 0.0, 0.0], [3.0, 2.5, 0.0]])
    # frame 0: max(1, 0.5); frame 1: max(1, 0.1); frame 2: max(2, 2.5)
    np.testing.assert_allclose(auto_radii(frames, samples, factor=2.0), [2.0, 2.0, 5.0])
    # one frame alone: factor * farthest sample, or 1.0 without extent
    np.testing.assert_allclose(
        auto_radii(frames[:1], samples, factor=1.5), [1.5 * np.hypot(3, 2.5)]
    )
    np.testing.assert_allclose(auto_radii(frames[:1], frames[:1]), [1.0])


def test_radii_from_other_samples_and_factor():
    frames = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    pts = np.array([[0.5, 0.0, 0.0]])
    wide = np.array([[0.0, 3.0, 0.0]])
    sf = shape_functions(frames, pts, radii_from=wide, radius_factor=2.0)
    np.testing.assert_allclose(sf.radii, auto_radii(frames, wide, 2.0))
    np.testing.assert_allclose(sf.radii, [6.0, 2.0])
    sf2 = shape_functions(frames, pts, radius_factor=3.0)
    np.testing.assert_allclose(sf2.radii, [3.0, 3.0])
    with pytest.raises(ValueError, match="radius_factor"):
        shape_functions(frames, pts, radius_factor=1.0)


def test_far_point_raises_naming_point_and_radius():
    frames = grid_frames()
    pts = np.vstack([random_points(q=20), [[5.0, 5.0, 9.0]], [[-4.0, 0.0, 0.0]]])
    with pytest.raises(ValueError, match="radius") as info:
        shape_functions(frames, pts, radius=0.6)
    msg = str(info.value)
    assert "integration point 20 at (5, 5, 9)" in msg
    assert "reached by 0 frame(s), at least 1 needed" in msg
    assert "2 of 22 integration points" in msg
    # the nearest frame (index 44, the corner (1, 1, 2)) is named with its distance and radius
    assert "nearest frame is 44 at distance" in msg and "support radius 0.6" in msg
    # automatic radii computed from other samples do not reach it either; `what` is the noun
    with pytest.raises(ValueError, match="display point 20 at") as info:
        shape_functions(frames, pts, radii_from=random_points(), what="display point")
    assert "radius" in str(info.value)


def test_min_frames():
    frames = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    pts = np.array([[0.5, 0.0, 0.0], [0.05, 0.0, 0.0]])
    sf = shape_functions(frames, pts, radius=0.6)
    np.testing.assert_array_equal(sf.count, [2, 1])
    with pytest.raises(ValueError, match=r"point 1 .* reached by 1 frame\(s\), at least 2") as info:
        shape_functions(frames, pts, radius=0.6, min_frames=2)
    assert "does not reach it is 1" in str(info.value)
    assert shape_functions(frames, pts, radius=1.0, min_frames=2).count.min() == 2
    with pytest.raises(ValueError, match="only 2 frame"):
        shape_functions(frames, pts, radius=5.0, min_frames=3)


# --- radius overrides ----------------------------------------------------------------------------


def test_scalar_and_per_frame_radius_override():
    frames, pts = grid_frames(), random_points()
    n = frames.shape[0]
    sf = shape_functions(frames, pts, radius=0.7)
    np.testing.assert_array_equal(sf.radii, np.full(n, 0.7))
    per = np.linspace(0.6, 1.2, n)
    sf2 = shape_functions(frames, pts, radius=per)
    np.testing.assert_array_equal(sf2.radii, per)
    w, _ = dense(sf, n)
    w2, _ = dense(sf2, n)
    assert not np.allclose(w, w2)
    np.testing.assert_allclose(w2.sum(axis=1), 1.0, rtol=0, atol=1e-14)
    # the same per-frame radii as a scalar give the same result as the scalar
    w3, _ = dense(shape_functions(frames, pts, radius=np.full(n, 0.7)), n)
    np.testing.assert_array_equal(w, w3)


# --- shepard -------------------------------------------------------------------------------------


def test_shepard_rows_contain_all_frames():
    frames, pts = grid_frames(), random_points()
    n = frames.shape[0]
    sf = shape_functions(frames, pts, kind="shepard")
    assert sf.width == n
    np.testing.assert_array_equal(sf.count, n)
    np.testing.assert_array_equal(sf.frames, np.broadcast_to(np.arange(n), sf.frames.shape))
    assert np.all(sf.weights > 0)
    assert np.all(np.isinf(sf.radii))


def test_shepard_is_finite_and_interpolating_at_a_frame():
    frames = grid_frames()
    sf = shape_functions(frames, frames[[0, 7]], kind="shepard")
    assert np.all(np.isfinite(sf.weights)) and np.all(np.isfinite(sf.gradients))
    assert sf.weights[0, 0] > 0.999 and sf.weights[1, 7] > 0.999
    with pytest.raises(ValueError, match="wendland"):
        shape_functions(frames, frames, kind="shepard", radius=1.0)


# --- errors --------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("frames", "points", "match"),
    [
        (np.zeros(3), np.zeros((2, 3)), "frame_positions has shape"),
        (np.eye(3), np.zeros(3), "points has shape"),
        (np.zeros((2, 4)), np.zeros((2, 4)), r"\(m, 2\) or \(m, 3\)"),
        (np.eye(3), np.zeros((2, 2)), "points are 2-D but frame_positions are 3-D"),
        (np.zeros((0, 3)), np.zeros((2, 3)), "no frames"),
        ([[0, 0, 0], [1, np.nan, 0]], np.zeros((2, 3)), r"frame 1 has non-finite"),
        (np.eye(3), [[0, 0, 0], [0, 0, 0], [np.inf, 0, 0]], r"integration point 2 has non-finite"),
        ([["a", "b", "c"]], np.zeros((2, 3)), "array of numbers"),
    ],
)
def test_bad_arrays(frames, points, match):
    with pytest.raises(ValueError, match=match):
        shape_functions(frames, points)


@pytest.mark.parametrize(
    ("radius", "match"),
    [
        (0.0, "frame 0 is 0.0"),
        (-1.0, r"must be finite and > 0"),
        (np.array([0.5, 0.5, -0.1]), "frame 2 is -0.1"),
        (np.inf, "finite"),
        (np.nan, "finite"),
        (np.ones(4), r"shape \(4,\).*\(3,\)"),
        (np.ones((3, 1)), r"shape \(3, 1\)"),
        ("big", "radius must be"),
    ],
)
def test_bad_radius(radius, match):
    with pytest.raises(ValueError, match=match):
        shape_functions(np.eye(3), np.eye(3), radius=radius)


def test_unknown_kind_lists_known_kinds():
    with pytest.raises(ValueError, match="gaussian") as info:
        shape_functions(np.eye(3), np.eye(3), kind="gaussian")
    assert "'wendland'" in str(info.value) and "'shepard'" in str(info.value)


@pytest.mark.parametrize("min_frames", [0, -1, 1.5, True])
def test_bad_min_frames(min_frames):
    with pytest.raises(ValueError, match="min_frames"):
        shape_functions(np.eye(3), np.eye(3), min_frames=min_frames)


@pytest.mark.parametrize("kind", KINDS)
def test_duplicate_frames_name_both_indices(kind):
    frames = np.array([[0.0, 0, 0], [1, 0, 0], [2, 0, 0], [1, 0, 0]])
    with pytest.raises(ValueError, match=r"frames 1 and 3 are at the same place \(1, 0, 0\)"):
        shape_functions(frames, np.zeros((2, 3)), kind=kind)
    with pytest.raises(ValueError, match="frames 1 and 3"):
        auto_radii(frames, np.zeros((2, 3)))


def test_bad_radii_from():
    with pytest.raises(ValueError, match="radii_from samples are 2-D"):
        shape_functions(np.eye(3), np.eye(3), radii_from=np.zeros((3, 2)))
    with pytest.raises(ValueError, match="radii_from sample 0 has non-finite"):
        shape_functions(np.eye(3), np.eye(3), radii_from=[[np.nan, 0, 0]])
