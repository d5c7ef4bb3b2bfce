"""Contact geometry: the bodies' contact surfaces as maps from the configuration to collision
vertices, and a surface's edges (the table of pairs that may touch: ``contact/pairs.py``)."""
