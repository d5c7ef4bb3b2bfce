"""The contact predictor: a step's contacts solved on the compliance of the kept factorisation
before (or instead of) the barrier's Newton solve, as SOFA's constraint-based contact does.

One file per stage, read in this order:

- ``broad_phase.py``: the candidate pairs of the step's sweep as arrays (``box_grid.py``: its
  compiled grid; ipctk's broad phase without numba);
- ``rows.py``: which pairs the step makes (proximity at the step's start within the distance
  the step can close) and their constraint rows J (a normal and, in 3D, two tangents each);
- ``compliance.py``: W = J H^-1 J^T from the kept factor, its columns kept while the factor is;
- ``signorini.py``: the Signorini-Coulomb problem on W (projected block Gauss-Seidel);
- ``predictor.py``: the stages together: free motion in, corrected positions, multipliers and
  the instrument forces out (``time/contact_step.py`` certifies and accepts them), and the
  accepted step's forces kept for the next free motion;
- ``haptic.py``: the last step's contact problem re-solved for an instrument's displacement.

Import the modules themselves; this package imports nothing.
"""
