"""Barrier contact (IPC): obstacles, contact pairs, the contact model and its costs.

Import the modules themselves (``tissuesim.contact.obstacles``, ``tissuesim.contact.pairs``);
this package imports nothing, so importing an obstacle generator does not load ipctk.
"""
