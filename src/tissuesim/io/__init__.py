"""Output: crash-safe VTU/PVD time series for ParaView and atomic text/JSON writers."""

from tissuesim.io.atomic import write_json_atomic, write_text_atomic
from tissuesim.io.vtu_series import VTUSeriesWriter

__all__ = ["VTUSeriesWriter", "write_json_atomic", "write_text_atomic"]
