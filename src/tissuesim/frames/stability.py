"""The stability limit of explicit steps of a frame-based body (the step itself is
``time/steps.py``'s): 2 / omega_max of the generalised eigenproblem K_q v = omega^2 M_q v."""

from __future__ import annotations

import numpy as np
import scipy.sparse.linalg as spla

__all__ = ["frame_critical_time_step"]


def frame_critical_time_step(model, z: np.ndarray | None = None, t: float = 0.0) -> float:
    """2 / omega_max of K_q v = omega^2 M_q v at z (rest by default), springs included, free
    DOFs only."""
    z = model.rest_config() if z is None else z
    acc = model.evaluate(z, 2, False, model.spring_energies(t))
    free = np.ones(model.n_dofs, dtype=bool)
    free[model.prescribed_dofs] = False
    K = model.assembly.q_pattern.matrix(acc.hessian)[free][:, free]
    M = model.tangent_mass(z)[free][:, free]
    if K.shape[0] <= 400:
        from scipy.linalg import eigh

        lam = eigh(K.toarray(), M.toarray(), eigvals_only=True)[-1]
    else:
        lam = spla.eigsh(K.tocsc(), k=1, M=M.tocsc(), which="LM", return_eigenvectors=False)[0]
    return float(2.0 / np.sqrt(max(lam, 1e-300)))
