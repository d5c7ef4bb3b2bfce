"""Barrier contact (IPC): obstacles, contact pairs, the contact model and its costs.

Where things are: ``model.py`` (the contact model: IPC's barrier energy over the bodies'
surfaces and the obstacles), ``obstacles.py`` (kinematic obstacles: instruments, a table),
``pairs.py`` (who touches whom, and with what friction); ``barrier/`` (the model's parts:
CCD queries, lagged friction, the step's candidates, the adaptive stiffness, obstacles moving
inside Newton, the forces it reports); ``geometry/`` (the bodies' contact surfaces, a
surface's edges); ``cut/`` (the contact surfaces of cut bodies, slivers and thin pieces, the
kerf ahead of a blade); ``readout/``
(what contact reports: body-to-body forces, an instrument's linearised force, a probe's depth);
``predict/`` (the step's contacts predicted on the compliance: interactive contact).

Import the modules themselves (``tissuesim.contact.obstacles``,
``tissuesim.contact.pairs``); this package imports nothing, so importing an obstacle
generator does not load ipctk.
"""
