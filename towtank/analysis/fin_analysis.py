"""The day's fins: the fin runs against the Sandia NACA 0015 section data and lifting-line theory.

:func:`analyse_fins` chains :mod:`towtank.analysis.fins`: the per-run table
(:func:`~towtank.analysis.fins.fin_table`), the lift slope, stall and minimum drag per speed
group (:func:`~towtank.analysis.fins.fin_curves`), forces against speed and, with the fin's
position ``x_m``, the control derivatives (:func:`~towtank.analysis.fins.control_derivatives`),
with the sentences the day's report carries.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
import pandas as pd

from towtank.analysis import fins
from towtank.analysis.plausibility import fin_plausibility_warnings
from towtank.ingest.protocol import Fin
from towtank.reference import sandia


@dataclass(frozen=True)
class FinFit:
    """The fins of the day against the Sandia NACA 0015 section data (the day's result,
    :class:`towtank.results.FinResult`, is built from it)."""

    table: pd.DataFrame  # fins.csv
    curves: pd.DataFrame  # fin_curves.csv
    force_vs_speed: pd.DataFrame
    aspect_ratio: float  # effective aspect ratio [-]
    oswald_e: float  # [-]
    control: pd.DataFrame | None  # fin_control.csv
    #: the lift slope of every speed group (:func:`towtank.analysis.fins.lift_slope_estimates`)
    slopes: pd.DataFrame = field(default_factory=pd.DataFrame)
    warnings: tuple[str, ...] = ()


def analyse_fins(runs: pd.DataFrame, fin: Fin) -> tuple[FinFit | None, list[str]]:
    """The fin analysis of a day and its warnings; None without usable fin runs.

    Parameters
    ----------
    runs : DataFrame
        runs.csv of the day (``config``, ``status``, ``run``, ``angle_deg`` [deg],
        ``speed_mean`` [m/s], ``re`` [-], ``cl``, ``cd`` [-], ``drag_mean``, ``lift_mean`` [N],
        ``rho`` [kg/m³]).
    fin : Fin
        The protocol's [fin]: chord and span [m], mounting, Oswald e, position x_m [m],
        largest angle of the linear range [deg].

    Returns
    -------
    (FinFit or None, list of str)
        A run beyond ±180° (the section data's range) is left out with a sentence; Sandia's Re
        clamp is said once; a lift slope no fin can have is named with its likely slip
        (:func:`towtank.analysis.plausibility.fin_plausibility_warnings`); any other Python
        warning goes on as a warning.
    """
    sel = runs[(runs["config"] == "fin") & (runs["status"] == "ok")]
    if sel.empty:
        return None, []
    rejected = runs[(runs["config"] == "fin") & (runs["status"] == "rejected")]
    warn: list[str] = []
    beyond = sel["angle_deg"].abs() > 180.0  # the section data stop there (ValueError)
    for run, angle in zip(sel.loc[beyond, "run"], sel.loc[beyond, "angle_deg"], strict=True):
        warn.append(f"run {run}: fin angle {angle:g}° is outside −180…180°, the range of the "
                    "Sandia section data; the run is left out of the fin analysis.")
    sel = sel[~beyond]
    if sel.empty:
        return None, warn
    mounting: Literal["free", "wall"] = "wall" if fin.mounting == "wall" else "free"
    ar = float(fins.effective_aspect_ratio(fin.span_m, fin.chord_m, mounting))
    linear_max = fin.linear_max_deg
    # Sandia's Re clamp (Re outside 1e4-1e7) goes to the day's warnings, so that the report
    # and provenance carry it; any other warning goes on as a Python warning
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        table = fins.fin_table(sel, ar, fin.oswald_e)
        curves = fins.fin_curves(table, linear_max, aspect_ratio=ar, e=fin.oswald_e)
    for w in caught:
        if issubclass(w.category, sandia.SandiaRangeWarning):
            text = f"fin: {w.message}"
            if text not in warn:
                warn.append(text)
        else:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    warn += fins.low_reynolds_warnings(table)
    warn += fins.lift_slope_warnings(curves, linear_max, rejected)
    warn += fin_plausibility_warnings(curves, table, ar)
    warn += fins.two_dimensional_warning(curves, ar)
    control = None
    if fin.x_m is not None and len(curves):
        slope, source = fins.control_lift_slope(curves, linear_max)
        if np.isfinite(slope):
            rho = float(sel["rho"].mean())
            control = fins.control_derivatives(slope, fin.area, fin.x_m, rho, source)
        else:
            warn.append(f"fin control derivatives: {source}; fin_control.csv is not written.")
    result = FinFit(
        table=table, curves=curves, force_vs_speed=fins.force_vs_speed(table),
        aspect_ratio=ar, oswald_e=fin.oswald_e, control=control,
        slopes=fins.lift_slope_estimates(table, linear_max), warnings=tuple(warn),
    )
    return result, warn
