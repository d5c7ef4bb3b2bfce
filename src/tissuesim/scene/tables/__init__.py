"""The scene file's tables, one reader per concept: bodies (``fem_body.py``, frame bodies
``frames.py`` and their regions ``frame_regions.py``, fibre fields ``fibre_fields.py``), contact
(``contact.py``), organs with connective tissue (``coupled.py``) and their cuts and tearing
(``cuts.py``), visual surfaces (``visual.py``) and FEBio-style log tables (``logfiles.py``).
``scene/loader.py`` reads the file and hands each table to its reader."""
