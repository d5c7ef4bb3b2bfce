"""Shared helpers for the core tests: small meshes and finite-difference checks."""

from __future__ import annotations

import pytest

from tissuesim.mesh import box, rectangle


@pytest.fixture(params=[2, 3], ids=["2d", "3d"])
def small_mesh(request):
    if request.param == 2:
        return rectangle(lower=(0, 0), upper=(1, 0.7), divisions=(3, 2))
    return box(lower=(0, 0, 0), upper=(1, 0.6, 0.5), divisions=(2, 2, 1))
