"""Continuous collision detection on the contact model (a mixin of
``contact.model.ContactModel``): the largest intersection-free fraction of a straight move (the
line search's first trial), whether a move or a step's start is free of intersection, and
whether a configuration intersects; from the step's candidate set when both ends lie within its
margin and the set is not dense, else from a broad phase over the sweep's own boxes; timed into
the step's stats."""

from __future__ import annotations

import time

import numpy as np

__all__ = ["CollisionQueries"]

#: tight-inclusion CCD for one yes-or-no query per step: its tolerance, and the iterations after
#: which it gives up (and says "not free"; unbounded it took 16-80 s between parallel faces)
TIGHT_TOLERANCE, TIGHT_ITERATIONS = 1e-6, 100_000
#: a sweep takes its pairs from the step's candidate set (``contact/barrier/candidates.py``) while
#: that holds at most this many per surface vertex, else from ipctk's broad phase over the sweep's
#: own boxes: the narrow phase pays for every pair, and the step's set holds every pair within
#: dhat of the step's path. Between a cut's two fresh faces (2 dhat apart over a whole section)
#: it held 11 per vertex (900 after a long sweep) and CCD took 5x longer from it; a probe on
#: an organ (1 per vertex) is as fast either way (``benchmarks/contact_candidates.py``)
SWEEP_PAIRS_PER_VERTEX = 8.0


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

    def start_free(self, c0: np.ndarray, c1: np.ndarray, y0: np.ndarray, y1: np.ndarray) -> bool:
        """Whether the straight move from (c0, obstacles y0) to (c1, obstacles y1) is free of
        intersection, by tight-inclusion CCD with its iterations bounded (undecided counts as
        not free): where a step's Newton solve may start. The additive CCD of the line search
        reports a hit as soon as a distance shrinks by a tenth, which an instrument sliding in
        a narrow kerf (a blade in its cut) always does."""
        V0, V1 = self.vertices(c0, obstacle=y0), self.vertices(c1, obstacle=y1)
        start = time.perf_counter()
        ccd = self._ipctk.TightInclusionCCD(TIGHT_TOLERANCE, TIGHT_ITERATIONS)
        held = self.candidates.held(V0, V1)
        if held is not None:
            free = held.is_step_collision_free(self.mesh, V0, V1, 0.0, ccd)
        else:
            free = self._ipctk.is_step_collision_free(
                self.mesh, V0, V1, broad_phase=self.broad_phase, narrow_phase_ccd=ccd
            )
        self.stats.ccd_s += time.perf_counter() - start
        self.stats.ccd_calls += 1
        return bool(free)

    def reachable(self, c0: np.ndarray, t0: float, c1: np.ndarray, t1: float) -> bool:
        """Whether the straight move from (c0, obstacles at t0) to (c1, obstacles at t1) is
        free of intersection: the start of a step's Newton solve must be reached so."""
        V0, V1 = self.vertices(c0, t0), self.vertices(c1, t1)
        return bool(self._sweep(self._ipctk.is_step_collision_free, V0, V1))

    def _sweep(self, query, V0: np.ndarray, V1: np.ndarray):
        """One CCD query over the straight move V0 -> V1, timed into the step's stats; from the
        step's candidate set when both ends lie within its margin and it holds at most
        SWEEP_PAIRS_PER_VERTEX pairs per vertex, else from a broad phase over the sweep."""
        start = time.perf_counter()
        candidates = self.candidates.get(V0, V1)
        if candidates is not None and len(candidates) > SWEEP_PAIRS_PER_VERTEX * len(V0):
            candidates = None
        if candidates is not None:
            out = getattr(candidates, query.__name__)(self.mesh, V0, V1, 0.0, self.ccd)
        else:
            out = query(self.mesh, V0, V1, broad_phase=self.broad_phase, narrow_phase_ccd=self.ccd)
        self.stats.ccd_s += time.perf_counter() - start
        self.stats.ccd_calls += 1
        return out

    def intersecting(self, c: np.ndarray, t: float | None = None) -> bool:
        return bool(self._ipctk.has_intersections(self.mesh, self.vertices(c, t)))
