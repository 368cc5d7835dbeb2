"""Report stage: the day's CSV tables, provenance, workbook, PDF and figures.

Everything here formats what the earlier stages computed; nothing is computed a second time.
:func:`write_outputs` writes the whole set into a temporary folder beside the output folder and
swaps it into place only when complete, so a failure never leaves half a report and never
touches the previous outputs.

``write_outputs`` is loaded on first use (PEP 562), so that ``towtank inspect``, which only
draws one run with :mod:`towtank.report.figures`, does not load pandas for the tables.
"""

from __future__ import annotations

from typing import Any

__all__ = ["write_outputs"]


def __getattr__(name: str) -> Any:
    if name == "write_outputs":
        # loaded on use: `towtank inspect` loads this package (report.style) and never the
        # writers; report.outputs loads pandas
        from towtank.report.outputs import write_outputs

        return write_outputs
    raise AttributeError(f"module 'towtank.report' has no attribute {name!r}")
