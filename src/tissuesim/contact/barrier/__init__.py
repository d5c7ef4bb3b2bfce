"""The contact model's parts (``contact/model.py``'s mixins and helpers): CCD queries, IPC's
lagged friction, the step's collision candidates, the adaptive barrier stiffness, obstacles
moved inside Newton, and the forces the model reports."""
