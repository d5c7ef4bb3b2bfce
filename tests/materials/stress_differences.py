"""Finite differences the material tests share: random deformation gradients and d fun / dF by
central differences, batched."""

from __future__ import annotations

import numpy as np


def random_deformations(rng, q: int, d: int, spread: float, jmin: float = 0.4) -> np.ndarray:
    """q random F = I + spread * N(0, 1) with det F > jmin (drawn 4q at a time)."""
    F = np.eye(d) + spread * rng.standard_normal((4 * q, d, d))
    return F[np.linalg.det(F) > jmin][:q]


def central_difference(fun, F: np.ndarray, h: float) -> np.ndarray:
    """d fun / dF by central differences in one batched call; fun (q, d, d) -> (q, ...); the
    derivative's indices last."""
    q, d = F.shape[:2]
    basis = np.eye(d * d).reshape(d * d, d, d) * h
    Fp = (F[:, None] + basis[None]).reshape(-1, d, d)
    Fm = (F[:, None] - basis[None]).reshape(-1, d, d)
    diff = (fun(Fp) - fun(Fm)) / (2 * h)
    diff = diff.reshape((q, d, d) + diff.shape[1:])
    return np.moveaxis(diff, (1, 2), (-2, -1))


def relative_difference(a: np.ndarray, b: np.ndarray) -> float:
    """The largest |a - b| over the largest |b|."""
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


def pointwise_difference(law, F: np.ndarray, h: float = 1e-6) -> tuple[np.ndarray, np.ndarray]:
    """(P, dP/dF) of ``law`` at F (q, d, d) by central differences of its energy and stress,
    one component of F at a time over all q points (a law bound to q points with a history
    evaluates its state only at that count, so the batched ``central_difference`` would not
    see it)."""
    d = F.shape[-1]
    P = np.zeros_like(F)
    A = np.zeros((*F.shape, d, d))
    for i in range(d):
        for j in range(d):
            Fp, Fm = F.copy(), F.copy()
            Fp[:, i, j] += h
            Fm[:, i, j] -= h
            P[:, i, j] = (law.evaluate(Fp, 0).energy - law.evaluate(Fm, 0).energy) / (2 * h)
            A[..., i, j] = (law.evaluate(Fp, 1).stress - law.evaluate(Fm, 1).stress) / (2 * h)
    return P, A
