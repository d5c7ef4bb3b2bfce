"""``python -m tissuesim``: the command line, for when the console script is not on PATH."""

import sys

from tissuesim.cli import main

sys.exit(main())
