"""The results of the stages of a day: the tare, the hull, the fins, the scaling, the vehicle.

Each is a frozen dataclass with ``to_frame()`` (the DataFrame its CSV is written from), a short
``repr`` and an HTML form for notebooks; the ones with estimates speak the vocabulary of
:class:`towtank.results.summary.Estimates` (``params``, ``bse``, ``conf_int``, ``summary``).
The stages return their fits (:class:`~towtank.analysis.hull.HullFit`,
:class:`~towtank.analysis.fin_analysis.FinFit`, :class:`~towtank.analysis.scaling.ScalingFit`,
:class:`~towtank.vehicle.stage.VehiclePrediction`); the day's wiring builds these from them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Generic, TypeVar

import pandas as pd

from towtank.analysis.captive import CaptiveFit
from towtank.analysis.fin_analysis import FinFit
from towtank.analysis.hull import SYMBOLS, UNIT, Estimate, HullFit
from towtank.analysis.scaling import ScalingFit
from towtank.reduce.tare import TARE_TERMS, TareModel, tare_table
from towtank.results.summary import (
    CONF_INT_COLUMNS,
    Estimates,
    Summary,
    bounds_text,
    esc,
    estimate_frame,
    estimates_summary,
    level_text,
)
from towtank.vehicle.hull import HullProfile
from towtank.vehicle.stage import VehiclePrediction

__all__ = ["CaptiveResult", "FinResult", "FromPrediction", "HullResult", "ScalingResult",
           "TareResult", "VehicleResult"]

T = TypeVar("T")


#: The units of the coefficients of a tare fit T = t2·U|U| + t1·U + m_t·a (TARE_TERMS).
TARE_UNITS = ("N s²/m²", "N s/m", "kg")


@dataclass(frozen=True, repr=False)
class TareResult(Estimates):
    """The sting tare of the day: one :class:`towtank.reduce.tare.TareModel` per tare group
    (T = t2·U|U| + t1·U + m_t·a for drag and lift). Its estimates are the coefficients of
    every fit, symbol ``<group>.<channel>.<term>`` (``A.drag.t2``)."""

    models: dict[str, TareModel] = field(default_factory=dict)

    def estimate_frame(self) -> pd.DataFrame:
        """t2 [N s²/m²], t1 [N s/m], m_t [kg] of every group and channel with their standard
        errors (clustered by sting run) and degrees of freedom (∞: a normal interval)."""
        rows = []
        for group in sorted(self.models):
            model = self.models[group]
            for channel, fit in (("drag", model.drag), ("lift", model.lift)):
                if fit is None:
                    continue
                rows += [(f"{group}.{channel}.{term}", float(v), float(s), fit.interval_dof, unit)
                         for term, unit, v, s in zip(TARE_TERMS, TARE_UNITS, fit.coef,
                                                     fit.std_errors, strict=True)]
        return estimate_frame(*zip(*rows, strict=True)) if rows else estimate_frame(
            [], [], [], [], [])

    def summary_title(self) -> str:
        return f"Sting tare ({', '.join(sorted(self.models)) or 'no tare groups'})"

    def to_frame(self) -> pd.DataFrame:
        """tare.csv: one row per tare group and channel, with 95 % intervals."""
        return pd.DataFrame(tare_table(self.models))

    def __repr__(self) -> str:
        groups = ", ".join(sorted(self.models)) or "none"
        return f"TareResult(tare groups: {groups})"


@dataclass(frozen=True, repr=False)
class HullResult(Estimates):
    """The hull coefficients of the day with their uncertainty.

    ``fit`` is the :class:`towtank.analysis.hull.HullFit` (``estimates``, ``added_mass``,
    ``damping``, ``repeats``, ``lift_slope``); ``coefficients`` coefficients.csv as the hull
    stage gives it (the prototype values and the predicted columns are added by their own
    stages: :attr:`towtank.results.DayResult.coefficients`).
    """

    fit: HullFit
    coefficients: pd.DataFrame
    warnings: tuple[str, ...] = ()

    @property
    def estimates(self) -> dict[str, Estimate]:
        """{symbol: Estimate} in the order of coefficients.csv."""
        return {s: self.fit.estimates[s] for s in SYMBOLS if s in self.fit.estimates}

    def estimate_frame(self) -> pd.DataFrame:
        """Every coefficient [its unit, SI] with its combined standard uncertainty u_c and
        Welch–Satterthwaite degrees of freedom."""
        est = self.estimates.values()
        return estimate_frame([e.symbol for e in est], [e.value for e in est],
                              [e.std_error for e in est], [e.dof for e in est],
                              [UNIT[e.symbol] for e in est])

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
        frame = pd.DataFrame.from_dict(rows, orient="index", columns=CONF_INT_COLUMNS)
        frame.index.name = "symbol"
        return frame

    def summary(self, alpha: float = 0.05) -> Summary:
        """The SUT-2 coefficient table, as a fit's summary: value, standard uncertainty,
        degrees of freedom, the interval of level 1 − ``alpha``, prime value and reference."""
        ci = self.conf_int(alpha)
        coef = self.coefficients.set_index("symbol")
        lo, hi = bounds_text(alpha)
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
                 f"{level_text(alpha)} intervals, Student's t at each estimate's degrees of "
                 "freedom (Welch–Satterthwaite).",)
        return Summary(title=f"Hull coefficients ({len(rows)} estimates)",
                       table=pd.DataFrame(rows), notes=notes)

    def to_frame(self) -> pd.DataFrame:
        """coefficients.csv of the hull stage (a copy)."""
        return self.coefficients.copy()

    def __repr__(self) -> str:
        return (f"HullResult({len(self.estimates)} coefficients: "
                f"{', '.join(self.estimates)}; rho = {self.fit.rho:.6g} kg/m³)")


@dataclass(frozen=True, repr=False)
class FinResult(FinFit, Estimates):
    """The fins of the day against the Sandia NACA 0015 section data: the
    :class:`~towtank.analysis.fin_analysis.FinFit` (``table`` fins.csv, ``curves``
    fin_curves.csv, ``control`` fin_control.csv or None, ``force_vs_speed``,
    ``aspect_ratio``, ``oswald_e``, ``slopes``, ``warnings``); its estimates are the measured
    lift slopes dC_L/dα of the speed groups [1/rad], symbol ``lift_slope@<speed> m/s``."""

    def estimate_frame(self) -> pd.DataFrame:
        """The linear-range lift slope of every speed group [1/rad] with its OLS standard
        error and residual degrees of freedom."""
        s = self.slopes
        if s.empty:
            return estimate_frame([], [], [], [], [])
        return estimate_frame([f"lift_slope@{g:.2f} m/s" for g in s["speed_group"]],
                              s["value"], s["std_error"], s["dof"], ["1/rad"] * len(s))

    def summary_title(self) -> str:
        return f"Fin lift slopes ({len(self.slopes)} speed groups)"

    def to_frame(self) -> pd.DataFrame:
        """fins.csv: one row per fin run."""
        return self.table.copy()

    def __repr__(self) -> str:
        return (f"FinResult({len(self.table)} fin runs, {len(self.curves)} speed groups, "
                f"AR_eff = {self.aspect_ratio:.4g}, e = {self.oswald_e:g})")


@dataclass(frozen=True, repr=False)
class ScalingResult(ScalingFit, Estimates):
    """Scaling of the day to the prototype: the :class:`~towtank.analysis.scaling.ScalingFit`
    (``table`` scaling.csv, ``resistance``, ``form_factor``, ``recommendation``, the waters
    and the scale). Its estimates: the resistance curve's k2 [N s²/m²] and k1 [N s/m]
    (OLS) and, with the wetted area, the form factor 1 + k [-] (mean of the tested speeds,
    standard error s/√n)."""

    def estimate_frame(self) -> pd.DataFrame:
        """k2, k1 and 1 + k with their standard errors and degrees of freedom."""
        (k2, k1), (s2, s1) = self.resistance, self.resistance_se
        rows = [("k2", k2, s2, self.resistance_dof, "N s²/m²"),
                ("k1", k1, s1, self.resistance_dof, "N s/m")]
        ff = self.form_factor
        if ff is not None:
            se = ff.std / math.sqrt(ff.n) if ff.n > 1 else math.nan
            rows.append(("1+k", ff.one_plus_k, se, ff.n - 1.0, "-"))
        return estimate_frame(*zip(*rows, strict=True))

    def summary_title(self) -> str:
        return f"Resistance curve and form factor (λ = {self.scale:g})"

    def to_frame(self) -> pd.DataFrame:
        """scaling.csv: one row per prototype speed."""
        return self.table.copy()

    def __repr__(self) -> str:
        k2, k1 = self.resistance
        ff = (f", 1 + k = {self.form_factor.one_plus_k:.4g}" if self.form_factor is not None
              else "")
        return (f"ScalingResult(λ = {self.scale:g}, {len(self.table)} prototype speeds, "
                f"R = {k2:.4g}·U|U| {k1:+.4g}·U{ff})")


class FromPrediction(Generic[T]):
    """A field of the :class:`~towtank.vehicle.stage.VehiclePrediction`, read through the
    :class:`VehicleResult` (typed ``T``, read only)."""

    def __set_name__(self, owner: type, name: str) -> None:
        self.name = name

    def __get__(self, result: VehicleResult | None, owner: type | None = None) -> T:
        if result is None:
            raise AttributeError(self.name)
        value: T = getattr(result.prediction, self.name)
        return value


@dataclass(frozen=True, repr=False)
class VehicleResult:
    """The [vehicle] stage: the prediction (:class:`towtank.vehicle.stage.VehiclePrediction`)
    and the hull coefficients with the predicted beside the measured.

    The prediction's fields read through it: ``predicted`` (predicted.csv), ``model``
    (model.json), ``profile`` (the hull), ``masses``, ``rho`` [kg/m³], ``nu`` [m²/s],
    ``powering`` (powering.csv or None) and ``pressure_hull`` (pressure_hull.csv or None).
    """

    prediction: VehiclePrediction
    coefficients: pd.DataFrame | None = None
    warnings: tuple[str, ...] = ()

    predicted = FromPrediction[pd.DataFrame]()
    model = FromPrediction[dict[str, Any]]()
    profile = FromPrediction[HullProfile]()
    masses = FromPrediction[dict[str, Any]]()
    rho = FromPrediction[float]()
    nu = FromPrediction[float]()
    powering = FromPrediction["pd.DataFrame | None"]()
    pressure_hull = FromPrediction["pd.DataFrame | None"]()

    def to_frame(self) -> pd.DataFrame:
        """predicted.csv: one row per predicted coefficient."""
        return self.prediction.predicted.copy()

    def __repr__(self) -> str:
        return (f"VehicleResult({len(self.prediction.predicted)} predicted coefficients, "
                f"rho = {self.prediction.rho:.6g} kg/m³)")

    def _repr_html_(self) -> str:
        return f"<p><b>{esc(repr(self))}</b></p>" + self.prediction.predicted.to_html(
            index=False, max_rows=30)



@dataclass(frozen=True, repr=False)
class CaptiveResult(CaptiveFit, Estimates):
    """The captive derivatives of a plane (:class:`towtank.analysis.captive.CaptiveFit`):
    Y_uv, N_uv, ... (Z_uw, M_uw, ... in the vertical plane) with their 95 % intervals on the
    fit's n - p degrees of freedom; ``to_frame()`` their coefficients.csv rows."""

    def estimate_frame(self) -> pd.DataFrame:
        """Every derivative [its unit, SI] with its standard error and degrees of freedom."""
        est = list(self.estimates.values())
        return estimate_frame([e.symbol for e in est], [e.value for e in est],
                              [e.std_error for e in est], [e.dof for e in est],
                              [e.unit for e in est])

    def summary_title(self) -> str:
        return f"Captive derivatives, {self.plane} plane ({len(self.runs)} runs)"

    def summary(self, alpha: float = 0.05) -> Summary:
        """The derivatives with their intervals of level 1 − ``alpha``, the fit's warnings
        and notes."""
        return estimates_summary(self.summary_title(), self.estimate_frame(),
                                 self.conf_int(alpha), alpha, (*self.warnings, *self.notes))

    def to_frame(self) -> pd.DataFrame:
        """coefficients.csv rows of the derivatives (:meth:`CaptiveFit.table`)."""
        return self.table()

    def __repr__(self) -> str:
        return f"CaptiveResult({self.plane}: {len(self.estimates)} derivatives, " \
               f"{len(self.runs)} runs)"
