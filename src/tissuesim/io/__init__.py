"""Output: crash-safe VTU/PVD time series for ParaView and atomic text/JSON writers.

Where things are: ``run_output.py`` (a run with output: series, summary.json, forces.csv,
pictures, checkpoints), ``forces.py`` (forces.csv and forces.png), ``manifest.py`` and
``lock.py`` (what a run wrote; one run per directory), ``atomic.py`` and ``interrupts.py``
(nothing half-written), ``progress.py``, ``device_path.py`` (a recorded instrument path),
``third_party_logs.py``; ``series/`` (the VTU/PVD series writer and each body's series);
``checkpoints/`` (resuming a run: the state, cut bodies, the tissue, the contact predictor,
the set-up's fingerprint).
"""

from tissuesim.io.atomic import write_json_atomic, write_text_atomic
from tissuesim.io.series.vtu import VTUSeriesWriter

__all__ = ["VTUSeriesWriter", "write_json_atomic", "write_text_atomic"]
