"""Report stage: the day's CSV tables, provenance, workbook, PDF and figures.

Everything here formats what the earlier stages computed; nothing is computed a second time.
:func:`write_outputs` writes the whole set into a temporary folder beside the output folder and
swaps it into place only when complete, so a failure never leaves half a report and never
touches the previous outputs.
"""

from towtank.report.outputs import write_outputs

__all__ = ["write_outputs"]
