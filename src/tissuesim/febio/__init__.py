"""FEBio models: read a FEBio 3.0 / 4.0 ``.feb`` file (``read_feb``), turn it into the
equivalent tissuesim scene (``febio_scene``, ``convert_febio``) or load it as a Scene ready
to run (``load_febio``; ``tissuesim run model.feb``). What is supported: docs/guide/febio.md."""

from __future__ import annotations

from tissuesim.febio.convert import convert_febio
from tissuesim.febio.reader import read_feb
from tissuesim.febio.scene import febio_scene
from tissuesim.febio.xml import FebError
from tissuesim.scene.loader import load_febio

__all__ = ["read_feb", "febio_scene", "convert_febio", "load_febio", "FebError"]
