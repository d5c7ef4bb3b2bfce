"""Checkpoints, so that a run continues where it stopped, bit-identically: the state and the
solvers (``checkpoint.py``), cut and torn bodies (``cuts.py``), the connective tissue
(``tissue.py``), the contact predictor (``predictor.py``) and the set-up a checkpoint must
match (``fingerprint.py``)."""
