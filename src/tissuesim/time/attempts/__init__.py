"""One step's attempts: where Newton starts, the candidate of lowest energy (``start.py``); a
failing step split into halves (``retry.py``); the bodies' internal variables frozen before
each attempt and updated after it converged (``history.py``)."""
