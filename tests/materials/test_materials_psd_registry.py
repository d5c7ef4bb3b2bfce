"""PSD projection of tangents and the name -> law registry."""

from __future__ import annotations

import numpy as np
import pytest

from tissuesim.errors import MaterialError
from tissuesim.materials import (
    FIBRE_LAWS,
    MATERIALS,
    SOFT_TISSUE_LAWS,
    CourseNeoHookean,
    Material,
    make_material,
    project_psd,
    project_tangent_psd,
)
from tissuesim.materials.registry import FEBIO_FIBRE_LAWS, FEBIO_LAWS


def test_project_psd_clamps_negative_eigenvalues():
    rng = np.random.default_rng(0)
    A = rng.standard_normal((20, 6, 6))
    out = project_psd(A)
    assert out.shape == A.shape
    np.testing.assert_allclose(out, np.swapaxes(out, 1, 2))
    assert np.linalg.eigvalsh(out).min() > -1e-12
    # the projection is the nearest PSD matrix: sym(A) - out is negative semidefinite
    sym = 0.5 * (A + np.swapaxes(A, 1, 2))
    assert np.linalg.eigvalsh(sym - out).max() < 1e-12


def test_project_psd_leaves_psd_input_unchanged():
    B = np.random.default_rng(1).standard_normal((10, 5, 5))
    A = B @ np.swapaxes(B, 1, 2) + 1e-3 * np.eye(5)
    np.testing.assert_array_equal(project_psd(A), A)


def test_project_tangent_psd_on_inverted_course_neo_hookean():
    law = CourseNeoHookean(youngs_modulus=1000.0, poisson_ratio=0.3)
    F = np.array([np.diag([-0.5, 1.0, 0.8]), np.eye(3), np.diag([0.2, 0.3, 0.4])])
    A = law.stress_derivative(F)
    out = project_tangent_psd(A)
    assert out.shape == A.shape
    assert np.linalg.eigvalsh(out.reshape(3, 9, 9)).min() > -1e-9
    np.testing.assert_allclose(out[1], A[1], atol=1e-9)  # PSD at rest: unchanged


def test_registry_builds_every_law():
    assert set(MATERIALS) == {
        "course_neo_hookean",
        "neo_hookean",
        "stvk",
        "linear",
        "fixed_corotated",
        *(cls.name for cls in SOFT_TISSUE_LAWS + FIBRE_LAWS if cls not in FEBIO_FIBRE_LAWS),
    }
    assert {cls.name for cls in FEBIO_FIBRE_LAWS} <= set(FEBIO_LAWS)  # FEBio's parameters
    for name, cls in MATERIALS.items():
        if cls in SOFT_TISSUE_LAWS + FIBRE_LAWS:
            continue  # their own parameters: test_materials_soft_tissue_registry.py
        mat = make_material(name, youngs_modulus=1000.0, poisson_ratio=0.3)
        assert isinstance(mat, cls) and isinstance(mat, Material) and mat.name == name
    assert isinstance(make_material("Neo-Hookean", shear_modulus=1.0, lame_lambda=1.0), Material)


def test_unknown_model_suggests_close_name():
    with pytest.raises(MaterialError, match="did you mean 'neo_hookean'"):
        make_material("neo_hokean", youngs_modulus=1.0, poisson_ratio=0.3)


def test_unknown_parameter_suggests_close_key():
    with pytest.raises(MaterialError, match="did you mean 'youngs_modulus'"):
        make_material("stvk", young_modulus=1.0, poisson_ratio=0.3)
