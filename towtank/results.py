"""The results of a day, stage by stage: typed, frozen, printable.

``towtank.process_day`` returns a :class:`DayResult`; its fields are the results of the stages,
each a frozen dataclass with ``to_frame()`` (the DataFrame its CSV is written from), a short
``repr`` and an HTML form for notebooks::

    day.tare            TareResult      the sting tare of every group (tare.csv)
    day.hull            HullResult      hull coefficients (coefficients.csv), summary(), conf_int()
    day.fin_result      FinResult       fins against Sandia (fins.csv, fin_curves.csv)
    day.scaling_result  ScalingResult   the prototype (scaling.csv)
    day.vehicle         VehicleResult   the [vehicle] prediction (predicted.csv, model.json)

Like a statsmodels fit, ``day.hull.conf_int(alpha=0.05)`` is a DataFrame indexed by symbol with
columns ``lower`` and ``upper``, and ``day.hull.summary(alpha=0.05)`` the coefficient table.
"""

from __future__ import annotations

import html
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, TypeVar

import numpy as np
import pandas as pd

from towtank.analysis.fin_analysis import FinResult
from towtank.analysis.fins import FIN_TABLE_COLUMNS
from towtank.analysis.hull import (
    COEFFICIENT_COLUMNS,
    COEFFICIENT_EXTRA_COLUMNS,
    SYMBOLS,
    UNIT,
    Estimate,
    HullFit,
)
from towtank.analysis.scaling import ScalingResult, with_prototype_values
from towtank.analysis.similarity import SCALING_COLUMNS, SCALING_RECOMMENDED_COLUMNS
from towtank.ingest.protocol import Protocol
from towtank.messages import STAGES, Notice, Rejection, Stage, notices
from towtank.reduce.run import RunReduction
from towtank.reduce.tare import TareModel, tare_table
from towtank.vehicle.stage import VehiclePrediction

R = TypeVar("R")

__all__ = [
    "DayResult", "Estimate", "FinResult", "HullResult", "Notice", "Rejection", "STAGES",
    "ScalingResult", "Stage", "Summary", "TareResult", "VehicleResult", "notices",
]

def require(result: R | None, stage: str) -> R:
    """``result``, which the caller only reaches when its stage ran (a report page or sheet
    listed for it); ValueError naming the stage otherwise."""
    if result is None:
        raise ValueError(f"the day has no {stage} result")
    return result


def _esc(text: object) -> str:
    return html.escape(str(text))


def _level(alpha: float) -> str:
    return f"{100.0 * (1.0 - alpha):g} %"


@dataclass(frozen=True)
class Summary:
    """A printable coefficient table: ``print(summary)``, ``summary.table`` (a DataFrame) and
    its HTML form in a notebook."""

    title: str
    table: pd.DataFrame
    notes: tuple[str, ...] = ()

    def as_text(self) -> str:
        """The table as fixed-width text, framed like a statsmodels summary."""
        body = self.table.to_string(index=False, float_format=lambda v: f"{v:.5g}")
        width = max(len(line) for line in body.splitlines()) if len(self.table) else 60
        width = max(width, len(self.title))
        rule = "=" * width
        lines = [self.title.center(width), rule]
        body_lines = body.splitlines()
        lines += [body_lines[0], "-" * width, *body_lines[1:], rule]
        lines += list(self.notes)
        return "\n".join(lines)

    def __str__(self) -> str:
        return self.as_text()

    def __repr__(self) -> str:
        return self.as_text()

    def _repr_html_(self) -> str:
        notes = "".join(f"<p>{_esc(n)}</p>" for n in self.notes)
        return (f"<p><b>{_esc(self.title)}</b></p>"
                + self.table.to_html(index=False, float_format=lambda v: f"{v:.5g}") + notes)


@dataclass(frozen=True, repr=False)
class TareResult:
    """The sting tare of the day: one :class:`towtank.reduce.tare.TareModel` per tare group
    (T = t2·U|U| + t1·U + m_t·a for drag and lift)."""

    models: dict[str, TareModel] = field(default_factory=dict)

    def to_frame(self) -> pd.DataFrame:
        """tare.csv: one row per tare group and channel, with 95 % intervals."""
        return pd.DataFrame(tare_table(self.models))

    def __repr__(self) -> str:
        groups = ", ".join(sorted(self.models)) or "none"
        return f"TareResult(tare groups: {groups})"

    def _repr_html_(self) -> str:
        return f"<p><b>{_esc(repr(self))}</b></p>" + self.to_frame().to_html(index=False)


@dataclass(frozen=True, repr=False)
class HullResult:
    """The hull coefficients of the day with their uncertainty.

    ``fit`` is the :class:`towtank.analysis.hull.HullFit` (``estimates``, ``added_mass``,
    ``damping``, ``repeats``, ``lift_slope``); ``coefficients`` coefficients.csv as the hull
    stage gives it (the prototype values and the predicted columns are added by their own
    stages: :attr:`DayResult.coefficients`).
    """

    fit: HullFit
    coefficients: pd.DataFrame
    warnings: tuple[str, ...] = ()

    @property
    def estimates(self) -> dict[str, Estimate]:
        """{symbol: Estimate} in the order of coefficients.csv."""
        return {s: self.fit.estimates[s] for s in SYMBOLS if s in self.fit.estimates}

    def conf_int(self, alpha: float = 0.05) -> pd.DataFrame:
        """Two-sided intervals of level 1 − ``alpha`` of every coefficient [its unit, SI].

        value ∓ t₁₋α/₂(ν)·u_c with each estimate's own budget u_c and Welch–Satterthwaite
        degrees of freedom ν (GUM G.4.1); ``alpha`` = 0.05 gives coefficients.csv's ci_low and
        ci_high.

        Returns
        -------
        DataFrame
            Indexed by symbol, columns ``lower`` and ``upper``.
        """
        rows = {s: e.conf_int(alpha) for s, e in self.estimates.items()}
        frame = pd.DataFrame.from_dict(rows, orient="index", columns=["lower", "upper"])
        frame.index.name = "symbol"
        return frame

    def summary(self, alpha: float = 0.05) -> Summary:
        """The SUT-2 coefficient table, as a fit's summary: value, standard uncertainty,
        degrees of freedom, the interval of level 1 − ``alpha``, prime value and reference."""
        ci = self.conf_int(alpha)
        coef = self.coefficients.set_index("symbol")
        lo, hi = f"[{alpha / 2:g}", f"{1 - alpha / 2:g}]"
        rows = []
        for s, e in self.estimates.items():
            rows.append({
                "symbol": s, "value": e.value, "unit": UNIT[s], "std err": e.std_error,
                "dof": e.dof, lo: ci.loc[s, "lower"], hi: ci.loc[s, "upper"],
                "prime": float(coef.loc[s, "prime"]) if s in coef.index else math.nan,
                "ref prime": (float(coef.loc[s, "reference_prime"]) if s in coef.index
                              else math.nan),
                "runs": e.n_runs,
            })
        f = self.fit
        notes = (f"ρ = {f.rho:.6g} kg/m³, L = {f.length:.4g} m, m = {f.mass:.5g} kg; "
                 f"{_level(alpha)} intervals, Student's t at each estimate's degrees of "
                 "freedom (Welch–Satterthwaite).",)
        return Summary(title=f"Hull coefficients ({len(rows)} estimates)",
                       table=pd.DataFrame(rows), notes=notes)

    def to_frame(self) -> pd.DataFrame:
        """coefficients.csv of the hull stage (a copy)."""
        return self.coefficients.copy()

    def __repr__(self) -> str:
        return (f"HullResult({len(self.estimates)} coefficients: "
                f"{', '.join(self.estimates)}; rho = {self.fit.rho:.6g} kg/m³)")

    def _repr_html_(self) -> str:
        return self.summary()._repr_html_()


@dataclass(frozen=True, repr=False)
class VehicleResult:
    """The [vehicle] stage: the prediction (:class:`towtank.vehicle.stage.VehiclePrediction`,
    whose attributes it gives: ``profile``, ``predicted``, ``masses``, ``model``, ``powering``,
    ``pressure_hull``) and the hull coefficients with the predicted beside the measured."""

    prediction: VehiclePrediction
    coefficients: pd.DataFrame | None = None
    warnings: tuple[str, ...] = ()

    def __getattr__(self, name: str) -> Any:
        if name.startswith("__") or name == "prediction":
            raise AttributeError(name)
        return getattr(self.prediction, name)

    def to_frame(self) -> pd.DataFrame:
        """predicted.csv: one row per predicted coefficient."""
        return self.prediction.predicted.copy()

    def __repr__(self) -> str:
        return (f"VehicleResult({len(self.prediction.predicted)} predicted coefficients, "
                f"rho = {self.prediction.rho:.6g} kg/m³)")

    def _repr_html_(self) -> str:
        return f"<p><b>{_esc(repr(self))}</b></p>" + self.prediction.predicted.to_html(
            index=False, max_rows=30)


@dataclass(frozen=True, repr=False)
class DayResult:
    """Everything computed for a day; the report stage only formats it.

    Tables are pandas DataFrames, numbers SI. ``hull``, ``fin_result``, ``scaling_result`` and
    ``vehicle`` are the stages' results (None where the stage did not run); ``coefficients``,
    ``fins`` and ``scaling`` their CSV tables (with their headers when empty).
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
    fin_result: FinResult | None = None
    scaling_result: ScalingResult | None = None
    #: path -> sha256 of every input of the day (a mapping no code changes once made)
    inputs: Mapping[str, str] = field(default_factory=dict)
    report_date: str | None = None
    # rejected runs that were read: calibrated speed and forces at 10 Hz, for the report
    previews: dict[int, dict[str, np.ndarray]] = field(default_factory=dict)
    vehicle: VehicleResult | None = None
    #: symbol, prototype_value: the hull coefficients at prototype scale (scaling stage)
    prototype_values: pd.DataFrame | None = None

    @property
    def n_rejected(self) -> int:
        """Number of rejected runs."""
        return len(self.rejected)

    @property
    def tare(self) -> TareResult:
        """The sting tare of every group (tare.csv: ``day.tare.to_frame()``)."""
        return TareResult(dict(self.tares))

    @property
    def fins(self) -> pd.DataFrame:
        """fins.csv of the day: one row per fin run (empty without fin runs)."""
        if self.fin_result is not None:
            return self.fin_result.table
        return pd.DataFrame(columns=list(FIN_TABLE_COLUMNS))

    @property
    def scaling(self) -> pd.DataFrame:
        """scaling.csv of the day: one row per prototype speed (empty when not scaled)."""
        if self.scaling_result is not None:
            return self.scaling_result.table
        return pd.DataFrame(columns=list(SCALING_COLUMNS + SCALING_RECOMMENDED_COLUMNS))

    @property
    def coefficients(self) -> pd.DataFrame:
        """coefficients.csv of the day: the hull's coefficients with their prototype values
        and, with a [vehicle], the predicted beside them (empty without hull runs)."""
        if self.hull is None:
            return pd.DataFrame(columns=COEFFICIENT_COLUMNS + COEFFICIENT_EXTRA_COLUMNS)
        if self.vehicle is not None and self.vehicle.coefficients is not None:
            return self.vehicle.coefficients  # made from the hull's with the prototype values
        return with_prototype_values(self.hull.coefficients, self.prototype_values)

    def summary(self, alpha: float = 0.05) -> Summary:
        """The day at a glance: the hull's coefficient table (:meth:`HullResult.summary`) or,
        without hull coefficients, the runs by configuration and status."""
        if self.hull is not None:
            s = self.hull.summary(alpha)
            return Summary(title=f"{self.protocol.name}: {s.title}", table=s.table,
                           notes=(*s.notes, self._counts()))
        table = (self.runs.groupby(["config", "status"]).size().rename("runs").reset_index()
                 if len(self.runs) else pd.DataFrame(columns=["config", "status", "runs"]))
        return Summary(title=f"{self.protocol.name}: runs", table=table,
                       notes=(self._counts(),))

    def _counts(self) -> str:
        stages = [name for name, r in (("hull", self.hull), ("fins", self.fin_result),
                                       ("scaling", self.scaling_result),
                                       ("vehicle", self.vehicle)) if r is not None]
        n = len(self.warnings)
        return (f"{len(self.runs)} runs, {len(self.reductions)} reduced, {self.n_rejected} "
                f"rejected; {n} warning{'' if n == 1 else 's'}; stages: "
                f"{', '.join(stages) or 'none'}.")

    def __repr__(self) -> str:
        return f"DayResult({self.protocol.name!r}: {self._counts()})"

    def _repr_html_(self) -> str:
        return self.summary()._repr_html_()
