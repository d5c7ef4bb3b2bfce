"""Continuous collision detection on the contact model (a mixin of
``contact.model.ContactModel``): the largest intersection-free fraction of a straight move (the
line search's first trial), whether a move or a step's start is free of intersection, and
whether a configuration intersects; from the step's candidate set when both ends lie within its
margin, timed into the step's stats."""

from __future__ import annotations

import time

import numpy as np

__all__ = ["CollisionQueries"]


class CollisionQueries:
    """Mixed into ``ContactModel`` (uses its vertices, mesh, candidates, CCD and stats)."""

    def max_step(
        self,
        c0: np.ndarray,
        c1: np.ndarray,
        y0: np.ndarray | None = None,
        y1: np.ndarray | None = None,
    ) -> float:
        """The largest fraction of the straight move c0 -> c1 (obstacles y0 -> y1, or where
        they are) free of intersection (CCD)."""
        V0, V1 = self.vertices(c0, obstacle=y0), self.vertices(c1, obstacle=y1)
        return float(self._sweep(self._ipctk.compute_collision_free_stepsize, V0, V1))

    def path_free(
        self,
        c0: np.ndarray,
        c1: np.ndarray,
        y0: np.ndarray | None = None,
        y1: np.ndarray | None = None,
    ) -> bool:
        """Whether the straight move of the vertices from c0 to c1 (obstacles y0 -> y1, or
        where they are) is free of intersection: Newton's check of each line-search trial when
        rigid frames move points on arcs (``linear`` False)."""
        V0, V1 = self.vertices(c0, obstacle=y0), self.vertices(c1, obstacle=y1)
        return bool(self._sweep(self._ipctk.is_step_collision_free, V0, V1))

    def reachable(self, c0: np.ndarray, t0: float, c1: np.ndarray, t1: float) -> bool:
        """Whether the straight move from (c0, obstacles at t0) to (c1, obstacles at t1) is
        free of intersection: the start of a step's Newton solve must be reached so."""
        V0, V1 = self.vertices(c0, t0), self.vertices(c1, t1)
        return bool(self._sweep(self._ipctk.is_step_collision_free, V0, V1))

    def _sweep(self, query, V0: np.ndarray, V1: np.ndarray):
        """One CCD query over the straight move V0 -> V1, timed into the step's stats; from the
        step's candidate set when both ends lie within its margin."""
        start = time.perf_counter()
        candidates = self.candidates.get(V0, V1)
        if candidates is not None:
            out = getattr(candidates, query.__name__)(self.mesh, V0, V1, 0.0, self.ccd)
        else:
            out = query(self.mesh, V0, V1, broad_phase=self.broad_phase, narrow_phase_ccd=self.ccd)
        self.stats.ccd_s += time.perf_counter() - start
        self.stats.ccd_calls += 1
        return out

    def intersecting(self, c: np.ndarray, t: float | None = None) -> bool:
        return bool(self._ipctk.has_intersections(self.mesh, self.vertices(c, t)))
