"""FEBio's parameter optimisation (``<febio_optimize>`` files, FEBio's ``-s``) run on the
model it names (``-i``): ``read_optimize`` reads the file (``task.py``), ``ModelBuilder`` sets
the parameters in the model and maps the objective's quantities (``model.py``),
``run_optimize`` minimises FEBio's objective with the run's sensitivities (``run.py``)."""

from __future__ import annotations

from tissuesim.febio.optimize.run import OptimizeResult, run_optimize
from tissuesim.febio.optimize.task import OptimizeTask, read_optimize

__all__ = ["read_optimize", "run_optimize", "OptimizeTask", "OptimizeResult"]
