"""A small coupled scene shared by the coupling tests: two boxes and a tissue layer between."""

from __future__ import annotations

import numpy as np
import pytest

from tissuesim.coupling.attachment import Attachment
from tissuesim.frames.model import FrameModel
from tissuesim.frames.sampling import sample_box
from tissuesim.materials import make_material
from tissuesim.mesh import box
from tissuesim.model import Model
from tissuesim.system import System


def brute_barycentric(mesh, points):
    """Cell and barycentric coordinates of each point (the cell where it is most inside)."""
    X = mesh.points[mesh.cells]  # (m, 4, 3)
    D = np.swapaxes(X[:, 1:] - X[:, :1], 1, 2)  # (m, 3, 3)
    lam = np.einsum("mij,qmj->qmi", np.linalg.inv(D), points[:, None, :] - X[None, :, 0])
    bary = np.concatenate([1.0 - lam.sum(axis=2, keepdims=True), lam], axis=2)  # (q, m, 4)
    cell = np.argmax(bary.min(axis=2), axis=1)
    return cell, bary[np.arange(len(points)), cell]


def face_points(lower, upper, z, n):
    g = (np.arange(n) + 0.5) / n
    xs = lower[0] + (upper[0] - lower[0]) * g
    ys = lower[1] + (upper[1] - lower[1]) * g
    X, Y = np.meshgrid(xs, ys, indexing="ij")
    return np.column_stack([X.ravel(), Y.ravel(), np.full(X.size, z)])


def make_scene(frame_kind="rigid", tissue_E=300.0, k_attach=200.0, gap=0.2):
    """Organ 0: box [0,1]x[0,1]x[-0.5,0]; organ 1: box [0,1]x[0,1]x[gap, gap+0.5]; tissue
    fills the gap; attached on both facing faces."""
    organ_mat = make_material("neo_hookean", youngs_modulus=1000.0, poisson_ratio=0.3)
    lower = box((0, 0, -0.5), (1, 1, 0), (2, 2, 1))
    upper = box((0, 0, gap), (1, 1, gap + 0.5), (2, 2, 1))
    organs = [Model(lower, organ_mat, 1.0), Model(upper, organ_mat, 1.0)]
    samples = sample_box((0, 0, 0), (1, 1, gap), gap / 2)
    g = np.linspace(0.2, 0.8, 2)
    X, Y = np.meshgrid(g, g, indexing="ij")
    frames = np.column_stack([X.ravel(), Y.ravel(), np.full(X.size, gap / 2)])
    tissue = FrameModel(
        frames,
        samples,
        make_material("stvk", youngs_modulus=tissue_E, poisson_ratio=0.3),
        density=1.0,
        frame_kind=frame_kind,
    )
    attachments = []
    for j, (mesh, z) in enumerate([(lower, 0.0), (upper, gap)]):
        pts = face_points((0, 0), (1, 1), z, 3)
        cell, bary = brute_barycentric(mesh, pts)
        attachments.append(
            Attachment(
                organ=j,
                points=pts,
                cells=cell,
                barycentric=bary,
                stiffness=np.full(len(pts), k_attach),
                tissue=tissue.embed(pts, "attachment point"),
                ids=np.arange(len(pts)),
            )
        )
    return System([*organs, tissue], ["lower", "upper", "tissue"], attachments)


@pytest.fixture
def scene_factory():
    """make_scene, for tests that build several scenes (no import of conftest needed)."""
    return make_scene
