"""Exceptions raised by tissuesim. Each message says what is wrong and how to fix it."""

from __future__ import annotations

__all__ = [
    "TissueSimError",
    "MeshError",
    "MaterialError",
    "InvertedElementError",
    "SceneError",
    "ConvergenceError",
]


class TissueSimError(Exception):
    """Base class of every error tissuesim raises on purpose."""


class MeshError(TissueSimError, ValueError):
    """A mesh (file or arrays) is malformed, degenerate or of the wrong kind."""


class MaterialError(TissueSimError, ValueError):
    """Impossible material parameters, or a material evaluated where it is undefined."""


class InvertedElementError(MaterialError):
    """A material that is undefined for J <= 0 was asked for stress or tangent there."""

    def __init__(self, message: str, indices=None):
        super().__init__(message)
        self.indices = indices


class SceneError(TissueSimError, ValueError):
    """A scene file has an unknown key, a wrong type or an invalid value."""


class ConvergenceError(TissueSimError, RuntimeError):
    """Newton failed to converge even after the allowed step halvings."""
