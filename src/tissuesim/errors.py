"""Exceptions raised by tissuesim. Each message says what is wrong and how to fix it.

Two families, one per exit code of the command line (``tissuesim.cli``):

- ``InputError`` (exit 2): what the user gave is wrong: a scene key, a mesh, an API argument,
  the output directory, a size the machine cannot hold. Nothing has run.
- ``RunError`` (exit 1): the input was accepted but the run failed: Newton did not converge,
  explicit steps blew up. The output written so far stays valid (summary status "failed").
"""

from __future__ import annotations

__all__ = [
    "TissueSimError",
    "InputError",
    "MeshError",
    "MaterialError",
    "InvertedElementError",
    "SceneError",
    "OutputError",
    "ResourceError",
    "RunError",
    "ConvergenceError",
    "InstabilityError",
]


class TissueSimError(Exception):
    """Base class of every error tissuesim raises on purpose."""


class InputError(TissueSimError, ValueError):
    """A value given to tissuesim (API argument, scene value, file) is invalid."""


class MeshError(InputError):
    """A mesh (file or arrays) is malformed, degenerate or of the wrong kind."""


class MaterialError(InputError):
    """Impossible material parameters, or a material evaluated where it is undefined."""


class InvertedElementError(MaterialError):
    """A material that is undefined for J <= 0 was asked for stress or tangent there."""

    def __init__(self, message: str, indices=None):
        super().__init__(message)
        self.indices = indices


class SceneError(InputError):
    """A scene file has an unknown key, a wrong type or an invalid value."""


class OutputError(InputError):
    """The output directory cannot be used (a file, not writable, a clash with its contents)."""


class ResourceError(InputError):
    """A requested size (mesh, frames, samples) needs more memory than the machine has."""


class RunError(TissueSimError, RuntimeError):
    """An accepted simulation failed while running."""


class ConvergenceError(RunError):
    """Newton failed to converge even after the allowed step halvings."""


class InstabilityError(RunError):
    """Explicit steps blew up: the energy grew without bound (time step above the limit)."""
