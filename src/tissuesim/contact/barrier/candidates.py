"""The collision candidates of one step, built once with inflated bounds and reused.

ipctk builds a candidate set from the surface primitives' bounding boxes, each inflated by a
radius; ``NormalCollisions.build(candidates, ...)`` and ``Candidates.compute_collision_free_
stepsize / is_step_collision_free`` then work from it alone. Boxes inflated by dhat / 2 + m
around positions V_b hold every pair closer than dhat at any positions within m (per vertex and
coordinate) of V_b, and every pair a straight sweep between two such positions can bring into
contact, so one set serves a step's evaluations and CCD sweeps while the vertices stay within
the margin m; a vertex that leaves it rebuilds the set around where it is (a sweep: around the
middle of its two ends, the margin grown by half their spread), and so does a query that needs
far less margin than the set was grown to (the short moves after one long sweep).
"""

from __future__ import annotations

import time

import numpy as np

__all__ = ["StepCandidates"]

#: a cached set whose margin exceeds this many times what a query needs is rebuilt tighter
BLOATED = 4.0


class StepCandidates:
    """``margin`` None: off (every query builds its own broad phase)."""

    def __init__(self, ipctk, mesh, broad_phase, dhat: float, stats) -> None:
        self._ipctk, self.mesh, self.broad_phase = ipctk, mesh, broad_phase
        self.dhat, self.stats = float(dhat), stats
        self.margin: float | None = None
        self.margin_used = 0.0
        self._cached = None
        self._sweep = None  # (V0, V1, the set of that sweep): ``hold_sweep``

    def begin(self, margin: float) -> None:
        """A new step: the set is built at the first query, inflated by ``margin`` (m)."""
        self.margin, self._cached, self._sweep = float(margin), None, None

    def hold_sweep(self, V0: np.ndarray, V1: np.ndarray):
        """The set of the straight move V0 -> V1 (swept boxes inflated by dhat / 2), built
        once and answered to every query at exactly these positions: a predicted step's
        certification (CCD of that move, the sides test) and the barrier's collisions at V1
        (calibration) share one broad phase. Returns the set."""
        held = self._sweep
        if held is not None and np.array_equal(held[0], V0) and np.array_equal(held[1], V1):
            return held[2]
        start = time.perf_counter()
        candidates = self._ipctk.Candidates()
        V0, V1 = np.asfortranarray(V0), np.asfortranarray(V1)
        candidates.build(self.mesh, V0, V1, 0.5 * self.dhat, broad_phase=self.broad_phase)
        self._sweep = (V0.copy(), V1.copy(), candidates)
        self.stats.candidate_builds += 1
        self.stats.candidates_s += time.perf_counter() - start
        return candidates

    def held(self, *V: np.ndarray):
        """The set ``hold_sweep`` built, if every array of V is one of its two ends."""
        if self._sweep is None:
            return None
        V0, V1, candidates = self._sweep
        ends = (V0, V1)
        if all(any(v.shape == e.shape and np.array_equal(v, e) for e in ends) for v in V):
            return candidates
        return None

    def get(self, *V: np.ndarray):
        """The candidates valid for every vertex array in V (built or rebuilt if needed), or
        None when caching is off."""
        if self.margin is None:
            return None
        held = self.held(*V)
        if held is not None:
            return held
        low = np.minimum.reduce(V) if len(V) > 1 else V[0]
        high = np.maximum.reduce(V) if len(V) > 1 else V[0]
        spread = 0.5 * float(np.max(high - low, initial=0.0))
        if self._cached is not None:
            base, candidates = self._cached
            inside = all(np.max(np.abs(v - base), initial=0.0) <= self.margin_used for v in V)
            # a set grown for one long sweep (a Newton step's first, mm long) holds far more
            # pairs than the short moves after it need, and every evaluation and CCD sweep pays
            # for each pair (measured: 0.7 s per evaluation instead of 0.02 s on a cut organ)
            bloated = self.margin_used > BLOATED * (self.margin + spread)
            if inside and not bloated:
                return candidates
        start = time.perf_counter()
        base = np.asfortranarray(0.5 * (low + high))
        candidates = self._ipctk.Candidates()
        self.margin_used = self.margin + spread
        candidates.build(
            self.mesh, base, 0.5 * self.dhat + self.margin_used, broad_phase=self.broad_phase
        )
        self._cached = (base, candidates)
        self.stats.candidate_builds += 1
        self.stats.candidates_s += time.perf_counter() - start
        return candidates
