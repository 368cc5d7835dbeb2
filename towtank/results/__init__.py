"""The results of a day and of ``towtank identify``: typed, frozen, printable; one vocabulary.

``towtank.process_day`` returns a :class:`DayResult`; its fields are the results of the stages,
each a frozen dataclass with ``to_frame()`` (the DataFrame its CSV is written from), a short
``repr`` and an HTML form for notebooks::

    day.tare       TareResult      the sting tare of every group (tare.csv)
    day.hull       HullResult      hull coefficients (coefficients.csv)
    day.fins       FinResult       fins against Sandia (day.fins.table: fins.csv; fin_curves.csv)
    day.scaling    ScalingResult   the prototype (day.scaling.table: scaling.csv)
    day.vehicle    VehicleResult   the [vehicle] prediction (predicted.csv, model.json)

``towtank.identify`` returns an :class:`IdentifyResult`. Every result with estimates
(:class:`HullResult`, :class:`FinResult`, :class:`ScalingResult`, :class:`IdentifyResult`)
speaks one vocabulary (:mod:`towtank.results.summary`), like a statsmodels fit: ``params`` and
``bse`` (Series by symbol), ``conf_int(alpha=0.05)`` (a DataFrame by symbol with columns
``lower`` and ``upper``), ``summary(alpha=0.05)`` (a :class:`Summary`) and ``to_frame()``.

The package sits above the stages (``vehicle``) and below ``pipeline``: the stages return
their fits (:class:`~towtank.analysis.hull.HullFit`, :class:`~towtank.analysis.fin_analysis.FinFit`,
:class:`~towtank.analysis.scaling.ScalingFit`, :class:`~towtank.vehicle.identify.IdentifyFit`,
:class:`~towtank.vehicle.stage.VehiclePrediction`) and the wiring builds the results from them
(:func:`towtank.results.summary.from_fit`).
"""

from __future__ import annotations

import warnings as _warnings
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Literal, TypeVar

import numpy as np
import pandas as pd

from towtank.analysis.captive import PMM_COLUMNS
from towtank.analysis.fins import FIN_TABLE_COLUMNS
from towtank.analysis.hull import COEFFICIENT_COLUMNS, COEFFICIENT_EXTRA_COLUMNS, Estimate
from towtank.analysis.scaling import with_prototype_values
from towtank.analysis.similarity import SCALING_COLUMNS, SCALING_RECOMMENDED_COLUMNS
from towtank.ingest.protocol import Protocol
from towtank.messages import STAGES, Notice, Rejection, Stage, notices
from towtank.reduce.run import RunReduction
from towtank.reduce.tare import TareModel
from towtank.results.stages import (
    CaptiveResult,
    FinResult,
    HullResult,
    ScalingResult,
    TareResult,
    VehicleResult,
)
from towtank.results.summary import Estimates, Summary, from_fit

if TYPE_CHECKING:
    from towtank.results.identify import IdentifyResult

R = TypeVar("R")

__all__ = [
    "CaptiveResult", "DayResult", "Estimate", "Estimates", "FinResult", "HullResult",
    "IdentifyResult", "Notice", "Rejection", "STAGES", "ScalingResult", "Stage", "Summary",
    "TareResult", "VehicleResult",
    "from_fit", "notices",
]

def require(result: R | None, stage: str) -> R:
    """``result``, which the caller only reaches when its stage ran (a report page or sheet
    listed for it); ValueError naming the stage otherwise."""
    if result is None:
        raise ValueError(f"the day has no {stage} result")
    return result


@dataclass(frozen=True, repr=False)
class DayResult:
    """Everything computed for a day; the report stage only formats it.

    Tables are pandas DataFrames, numbers SI. ``hull``, ``fins``, ``scaling`` and ``vehicle``
    are the stages' results (None where the stage did not run): ``day.fins.table`` is
    fins.csv, ``day.scaling.table`` scaling.csv. ``coefficients`` and :meth:`table` give the
    day's CSV tables with their headers also when the stage did not run.
    """

    protocol: Protocol
    sheet: pd.DataFrame
    reductions: dict[int, RunReduction]
    #: run number -> why it is not used (``str()`` of each is runs.csv's ``reason``)
    rejected: Mapping[int, Rejection]
    tares: dict[str, TareModel]
    runs: pd.DataFrame
    #: the day's warnings, in the order of the stages (``str()`` of each is its sentence)
    warnings: tuple[Notice, ...] = ()
    hull: HullResult | None = None
    fins: FinResult | None = None
    scaling: ScalingResult | None = None
    #: path -> sha256 of every input of the day (a mapping no code changes once made)
    inputs: Mapping[str, str] = field(default_factory=dict)
    report_date: str | None = None
    # rejected runs that were read: calibrated speed and forces at 10 Hz, for the report
    previews: dict[int, dict[str, np.ndarray]] = field(default_factory=dict)
    vehicle: VehicleResult | None = None
    #: symbol, prototype_value: the hull coefficients at prototype scale (scaling stage)
    prototype_values: pd.DataFrame | None = None
    #: the captive derivatives of the horizontal plane (static drift, rudder, rotating arm,
    #: PMM, a lab's means) and of the vertical plane (the model rolled 90°)
    captive: CaptiveResult | None = None
    captive_vertical: CaptiveResult | None = None

    @property
    def n_rejected(self) -> int:
        """Number of rejected runs."""
        return len(self.rejected)

    @property
    def tare(self) -> TareResult:
        """The sting tare of every group (tare.csv: ``day.tare.to_frame()``)."""
        return TareResult(dict(self.tares))

    def table(self, name: Literal["fins", "scaling"]) -> pd.DataFrame:
        """The CSV table ``name`` of the day (a copy), with its header when the stage did not run:
        ``"fins"`` fins.csv (one row per fin run, ``day.fins.table``), ``"scaling"``
        scaling.csv (one row per prototype speed, ``day.scaling.table``)."""
        if name == "fins":
            if self.fins is not None:
                return self.fins.table.copy()
            return pd.DataFrame(columns=list(FIN_TABLE_COLUMNS))
        if name == "scaling":
            if self.scaling is not None:
                return self.scaling.table.copy()
            return pd.DataFrame(columns=list(SCALING_COLUMNS + SCALING_RECOMMENDED_COLUMNS))
        raise ValueError(f"a day's table is 'fins' or 'scaling', not {name!r}")

    @property
    def fin_result(self) -> FinResult | None:
        """Deprecated: ``day.fins``."""
        _warnings.warn("DayResult.fin_result is deprecated: use DayResult.fins (its table: "
                       "day.fins.table)", DeprecationWarning, stacklevel=2)
        return self.fins

    @property
    def scaling_result(self) -> ScalingResult | None:
        """Deprecated: ``day.scaling``."""
        _warnings.warn("DayResult.scaling_result is deprecated: use DayResult.scaling (its "
                       "table: day.scaling.table)", DeprecationWarning, stacklevel=2)
        return self.scaling

    @property
    def coefficients(self) -> pd.DataFrame:
        """coefficients.csv of the day (a copy): the hull's coefficients with their prototype
        values and, with a [vehicle], the predicted beside them (empty without hull runs)."""
        if self.vehicle is not None and self.vehicle.coefficients is not None:
            return self.vehicle.coefficients.copy()  # the measured with prototype values
        hull = (with_prototype_values(self.hull.coefficients, self.prototype_values)
                if self.hull is not None else None)
        tables = [t for t in (hull, *(c.table() for c in self.captive_results)) if t is not None]
        if not tables:
            return pd.DataFrame(columns=COEFFICIENT_COLUMNS + COEFFICIENT_EXTRA_COLUMNS)
        return tables[0].copy() if len(tables) == 1 else pd.concat(tables, ignore_index=True)

    @property
    def captive_results(self) -> tuple[CaptiveResult, ...]:
        """The captive results of the day, horizontal plane first (empty without)."""
        return tuple(c for c in (self.captive, self.captive_vertical) if c is not None)

    @property
    def means_text(self) -> str:
        """The runs of a lab's table of means (``[captive] means``), which are in no run
        sheet, for the sentences that count the day's runs: ", and 63 runs from the table of
        means captive.csv"; "" without."""
        means = sum(1 for fit in self.captive_results for r in fit.runs if not r.file)
        options = self.protocol.captive
        if not means or options is None or options.means is None:
            return ""
        return f", and {means} runs from the table of means {Path(options.means).name}"

    @property
    def pmm(self) -> pd.DataFrame:
        """pmm.csv of the day: one row per PMM run of either plane (empty without)."""
        tables = [c.pmm_table() for c in self.captive_results]
        return (pd.concat(tables, ignore_index=True) if tables
                else pd.DataFrame(columns=list(PMM_COLUMNS)))

    def summary(self, alpha: float = 0.05) -> Summary:
        """The day at a glance: the hull's coefficient table (:meth:`HullResult.summary`) or,
        without hull coefficients, the runs by configuration and status."""
        if self.hull is not None and len(self.hull.estimate_frame()):
            s = self.hull.summary(alpha)
            return Summary(title=f"{self.protocol.name}: {s.title}", table=s.table,
                           notes=(*s.notes, self._counts()))
        table = (self.runs.groupby(["config", "status"]).size().rename("runs").reset_index()
                 if len(self.runs) else pd.DataFrame(columns=["config", "status", "runs"]))
        return Summary(title=f"{self.protocol.name}: runs", table=table,
                       notes=(self._counts(),))

    def _counts(self) -> str:
        stages = [name for name, r in (("hull", self.hull), ("fins", self.fins),
                                       ("scaling", self.scaling), ("captive", self.captive),
                                       ("captive_vertical", self.captive_vertical),
                                       ("vehicle", self.vehicle)) if r is not None]
        n = len(self.warnings)
        return (f"{len(self.runs)} runs, {len(self.reductions)} reduced, {self.n_rejected} "
                f"rejected; {n} warning{'' if n == 1 else 's'}; stages: "
                f"{', '.join(stages) or 'none'}.")

    def __repr__(self) -> str:
        return f"DayResult({self.protocol.name!r}: {self._counts()})"

    def _repr_html_(self) -> str:
        return self.summary()._repr_html_()


def __getattr__(name: str) -> object:
    """:class:`~towtank.results.identify.IdentifyResult`, imported on first use (PEP 562): it
    loads the identification's filter, which a day never needs."""
    if name == "IdentifyResult":
        # loaded on use: filterpy and the identification only for identify's result
        from towtank.results.identify import IdentifyResult

        return IdentifyResult
    raise AttributeError(f"module 'towtank.results' has no attribute {name!r}")
