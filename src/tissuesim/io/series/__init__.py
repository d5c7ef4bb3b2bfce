"""Time series for ParaView: the crash-safe VTU/PVD writer (``vtu.py``) and what each body,
visual surface and tissue writes per frame on its rest positions (``bodies.py``)."""
