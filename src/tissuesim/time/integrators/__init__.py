"""The time schemes beyond the plain step of ``time/steps.py`` (Backward Euler, quasistatic,
explicit): Newmark's method as an incremental potential (``newmark.py``), quasistatic steps of
bodies only contact holds, at rest in pseudo-time (``pseudo_time.py``), the supports a
quasistatic solve needs (``quasistatic.py``) and the explicit stability limit of a FEM body
(``stability.py``)."""
