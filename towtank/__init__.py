"""towtank: towing-tank run files to hydrodynamic coefficients, fin data, scaling and reports.

The subpackages are the stages of the data's path, in order::

    ingest     protocol, run sheet, run files read as the lab recorded them
    signal     filter, zero and drift; the run's phases from the speed
    reduce     one run's steady and accelerated means; the sting tare
    analysis   hull coefficients with intervals, fins against Sandia, scaling to the prototype
    report     CSV tables, workbook, PDF and figures

with ``pipeline`` wiring them for a day into the typed results of ``results`` (``DayResult``,
one result per stage and ``IdentifyResult``, all with one vocabulary), ``reference`` (water,
Sandia, hull geometry, reference coefficient sets), ``stats`` (robust and interval
statistics) and ``runtime`` (cache, workers) beneath them, ``commands`` (the ``towtank``
command line) above, and ``testing`` (the synthetic-day generator) beside, never used by the
others.

The public API, for scripts and notebooks (see docs/api.md)::

    import towtank
    day = towtank.process_day("protocols/sut2_hull.toml")
    print(day.hull.summary())      # the coefficient table; day.hull.conf_int(0.10)
    day.coefficients               # coefficients.csv as a DataFrame

is loaded on first use, so that ``import towtank`` stays cheap.
"""

import importlib

__version__ = "0.1.0"

__all__ = [
    "__version__",
    "DayResult",
    "Estimate",
    "FinResult",
    "HullResult",
    "IdentifyResult",
    "ProtocolError",
    "RunError",
    "ScalingResult",
    "TareResult",
    "VehicleResult",
    "identify",
    "load_protocol",
    "process_day",
    "read_run",
    "reduce_run",
]

_API = {
    "process_day": "towtank.api",
    "load_protocol": "towtank.api",
    "read_run": "towtank.api",
    "reduce_run": "towtank.api",
    "identify": "towtank.api",
    "DayResult": "towtank.results",
    "Estimate": "towtank.results",
    "FinResult": "towtank.results",
    "HullResult": "towtank.results",
    "IdentifyResult": "towtank.results",
    "ScalingResult": "towtank.results",
    "TareResult": "towtank.results",
    "VehicleResult": "towtank.results",
    "ProtocolError": "towtank.errors",
    "RunError": "towtank.errors",
}


def __getattr__(name: str) -> object:
    """The API's names, imported on first use (PEP 562)."""
    if name in _API:
        value = getattr(importlib.import_module(_API[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'towtank' has no attribute {name!r}")


def __dir__() -> list[str]:
    """The public API only (``__all__``): not the subpackages loaded, nor helpers."""
    return sorted(__all__)
