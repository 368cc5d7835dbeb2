"""The day's scaling to the prototype: resistance curve, form factor, prototype values.

From the steady hull runs at α = 0 the model resistance R(U) = k2·U|U| + k1·U is fitted by
ordinary least squares; the form factor 1 + k is found from the same runs where the model's
wetted area is known (:func:`towtank.analysis.similarity.form_factor`, ITTC 7.5-02-02-02); the
prototype speeds are then scaled by Froude's and Reynolds's laws and the ITTC-57 line
(:func:`towtank.analysis.similarity.scaling_table`, docs/method.md "Similarity and scaling"),
and every hull coefficient gets its prototype value, prime × ½ρ_p·L_p^k
(:func:`towtank.analysis.similarity.prototype_value`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
import pandas as pd

from towtank.analysis import similarity
from towtank.analysis.similarity import FormFactor, FormFactorTrend, ResistanceRecommendation
from towtank.ingest.protocol import Model, Protocol, Prototype, model_geometry

#: A hull run within this of α = 0 is a straight tow of the resistance curve [deg].
STRAIGHT_TOL_DEG = 0.5


@dataclass(frozen=True)
class ScalingFit:
    """Scaling of the day to the prototype (scaling.csv and its constants; the day's result,
    :class:`towtank.results.ScalingResult`, is built from it)."""

    table: pd.DataFrame  # scaling.csv
    resistance: tuple[float, float]  # k2 [N s²/m²], k1 [N s/m] of R = k2·U|U| + k1·U
    tested_speed_range: tuple[float, float]  # [m/s]
    form_factor: FormFactor | None
    statement: str
    rho_p: float  # [kg/m³]
    nu_p: float  # [m²/s]
    rho_m: float  # [kg/m³]
    nu_m: float  # [m²/s]
    scale: float  # λ = L_p / L_m [-]
    length_prototype: float = math.nan  # [m]
    wetted_area_prototype: float | None = None  # λ²·S_m [m²], None when S_m is not known
    delta_cf: float = 0.0
    #: which column of scaling.csv is R_p, and why
    recommendation: ResistanceRecommendation | None = None
    #: 1 + k against Re (None without 1 + k)
    form_factor_trend: FormFactorTrend | None = None
    form_factor_trend_text: str = ""
    #: the warning that prototype speeds give Re below [processing] laminar_re (their ITTC-57
    #: drag indicative only); "" when none does
    laminar_note: str = ""
    #: standard errors of k2, k1 [N s²/m², N s/m] and their residual degrees of freedom [-]
    #: (NaN and 0 when two straight runs fix the curve exactly)
    resistance_se: tuple[float, float] = (math.nan, math.nan)
    resistance_dof: float = math.nan


def prototype_values(coefficients: pd.DataFrame, rho_p: float, length_p: float) -> pd.DataFrame:
    """The prototype value of every hull coefficient: prime × ½ρ_p·L_p³ (added mass) or
    × ½ρ_p·L_p² (damping), :func:`towtank.analysis.similarity.prototype_value`.

    Parameters
    ----------
    coefficients : DataFrame
        coefficients.csv's ``symbol`` and ``prime`` columns.
    rho_p : float
        Prototype water density [kg/m³].
    length_p : float
        Prototype length [m].

    Returns
    -------
    DataFrame
        ``symbol``, ``prototype_value`` (SI, the coefficient's unit), one row per coefficient.
    """
    kinds = coefficients["symbol"].map(lambda s: "added_mass" if s.endswith("dot") else "damping")
    values = [float(similarity.prototype_value(pr, rho_p, length_p, k))
              for pr, k in zip(coefficients["prime"], kinds, strict=True)]
    return pd.DataFrame({"symbol": coefficients["symbol"].to_numpy(), "prototype_value": values})


def with_prototype_values(coefficients: pd.DataFrame, values: pd.DataFrame | None
                          ) -> pd.DataFrame:
    """coefficients.csv with the ``prototype_value`` of each symbol from ``values``
    (:func:`prototype_values`; NaN for a symbol it lacks); ``coefficients`` itself when
    ``values`` is None. A new table: ``coefficients`` is not changed."""
    if values is None:
        return coefficients
    by_symbol = dict(zip(values["symbol"], values["prototype_value"], strict=True))
    out = coefficients.copy()
    out["prototype_value"] = [by_symbol.get(s, math.nan) for s in out["symbol"]]
    return out


#: 1 + k below which the model's drag is too small for its wetted area to be a unit-free
#: reading: laminar flow over part of a small model can put 1 + k somewhat below 1 (the
#: ITTC-57 line is a turbulent one), but not below half of it.
MIN_ONE_PLUS_K = 0.5


def form_factor_warnings(one_plus_k: float, wetted_area_m2: float) -> list[str]:
    """The sentence a form factor 1 + k below 1 needs (ITTC 7.5-02-02-02: 1 + k = C_T/C_F0 at
    low speed, about 1.1–1.6 for a streamlined hull): below :data:`MIN_ONE_PLUS_K` the
    wetted area ``wetted_area_m2`` [m²] or the drag is in other units; between it and 1
    the flow over the model is partly laminar. None at or above 1."""
    if not math.isfinite(one_plus_k) or one_plus_k >= 1.0:
        return []
    if one_plus_k < MIN_ONE_PLUS_K:
        return [f"form factor 1 + k = {one_plus_k:.3g} is far below 1, which no hull has "
                f"(its drag less than the friction of its wetted area {wetted_area_m2:g} m²): "
                "is [model] wetted_area_m2 in other units (cm²?), or the drag? drag_ittc57 "
                "is not to be trusted."]
    return [f"form factor 1 + k = {one_plus_k:.3g} is below 1: the model's drag is less than "
            "the ITTC-57 friction of its wetted area, as with laminar flow over part of it "
            "(trip the boundary layer) or a wetted area given too large."]


def scale_to_prototype(
    runs: pd.DataFrame,
    model: Model,
    prototype: Prototype,
    *,
    scale: float,
    rho_m: float,
    nu_m: float,
    rho_p: float,
    nu_p: float,
    laminar_re: float,
    damping_alpha_max_deg: float,
    free_surface: bool = True,
) -> tuple[ScalingFit | None, list[str]]:
    """Scale the day's hull resistance to the prototype; the result and its warnings.

    The model resistance R(U) = k2·U|U| + k1·U is fitted by OLS to the steady hull runs at
    |α| ≤ 0.5° (two or more needed); 1 + k (:func:`towtank.analysis.similarity.form_factor`)
    needs the model's wetted area; then :func:`towtank.analysis.similarity.scaling_table`, the
    similarity statement and the recommended prototype resistance.

    Parameters
    ----------
    runs : DataFrame
        runs.csv of the day (``config``, ``status``, ``angle_deg``, ``speed_mean`` [m/s],
        ``drag_mean`` [N], ``rho`` [kg/m³], ``nu`` [m²/s], ``re`` [-]).
    model, prototype : Model, Prototype
        The protocol's [model] and [prototype].
    scale : float
        λ = L_p / L_m [-].
    rho_m, nu_m : float
        Tank water density [kg/m³] and kinematic viscosity [m²/s].
    rho_p, nu_p : float
        Prototype water's, likewise.
    laminar_re : float
        Reynolds number below which the flow need not be turbulent [-].
    damping_alpha_max_deg : float
        Largest |α| of the runs whose Reynolds range is the model's [deg].
    free_surface : bool, default True
        False in air (no waves, no depth, no Froude similarity).

    Returns
    -------
    (ScalingFit or None, list of str)
        None when fewer than two straight runs give the resistance curve.
    """
    # loaded on use: statsmodels loads while the workers reduce the runs
    from statsmodels.regression.linear_model import OLS

    warn: list[str] = []
    zero = runs[(runs["config"] == "hull") & (runs["status"] == "ok")
                & (np.abs(runs["angle_deg"]) <= STRAIGHT_TOL_DEG)]
    if len(zero) < 2:
        warn.append(
            "scaling.csv needs two or more steady hull runs at α = 0 for the resistance curve."
        )
        return None, warn
    u = zero["speed_mean"].to_numpy(float)
    r = zero["drag_mean"].to_numpy(float)
    res = OLS(r, np.column_stack([u * np.abs(u), u])).fit()
    k2, k1 = (float(v) for v in res.params)
    # two speeds fix the curve exactly: no residual freedom, so no standard error (NaN, where
    # statsmodels' bse would divide by zero degrees of freedom: ∞ and a RuntimeWarning)
    se = ((float(res.bse[0]), float(res.bse[1])) if res.df_resid >= 1
          else (math.nan, math.nan))
    ff = None
    one_plus_k = math.nan
    if model.wetted_area_m2 is not None:
        try:
            ff = similarity.form_factor(  # each run at its own water
                r, u, model.wetted_area_m2, zero["rho"].to_numpy(float),
                zero["nu"].to_numpy(float), model.length_m, re_min=laminar_re,
            )
            one_plus_k = float(ff.one_plus_k)
            warn += form_factor_warnings(one_plus_k, model.wetted_area_m2)
        except ValueError as exc:
            warn.append(f"form factor: {exc}")
    else:
        warn.append(
            "drag_ittc57 needs the model's wetted area ([model] wetted_area_m2 or a Myring "
            "description); it is left empty and no form factor is found."
        )
    table = similarity.scaling_table(
        np.asarray(prototype.speeds_m_s),
        scale=scale,
        length_model=model.length_m,
        length_prototype=prototype.length_m,
        rho_m=rho_m, nu_m=nu_m, rho_p=rho_p, nu_p=nu_p,
        resistance_model=lambda um: k2 * um * abs(um) + k1 * um,
        tested_speed_range=(float(u.min()), float(u.max())),
        wetted_area_model=model.wetted_area_m2,
        one_plus_k=one_plus_k,
        delta_cf=prototype.delta_cf,
    )
    hull_runs = runs[(runs["config"] == "hull") & (runs["status"] == "ok")
                     & (np.abs(runs["angle_deg"]) <= damping_alpha_max_deg)]
    # a run towed backwards (negative speed) has no Reynolds range of its own to compare
    re_ok = hull_runs["re"][np.isfinite(hull_runs["re"]) & (hull_runs["re"] > 0)]
    if len(re_ok) == 0:  # only backward tows: their size is the Reynolds number
        re_ok = np.abs(zero["re"])[np.isfinite(zero["re"]) & (zero["re"] != 0)]
    re_model = (float(re_ok.min()), float(re_ok.max()))
    re_proto = (float(table["re_prototype"].min()), float(table["re_prototype"].max()))
    air = not free_surface
    depth = model.depth_m if model.diameter_m is not None and not air else None
    statement = similarity.similarity_statement(
        re_model, re_proto, depth, model.diameter_m if depth is not None else None,
        turbulent_re=laminar_re, free_surface=not air,
    )
    deep_ratio = depth / model.diameter_m if depth is not None and model.diameter_m else None
    recommendation = similarity.recommend_resistance(
        deep_ratio, bool(np.isfinite(table["drag_ittc57"]).any()), free_surface=not air)
    table["drag_recommended"] = (table[recommendation.column] if recommendation.column in table
                                 else math.nan)
    table["recommended"] = recommendation.column
    trend, trend_text = None, ""
    if ff is not None:
        trend = similarity.form_factor_trend(ff.speed_reynolds, ff.speed_values)
        trend_text = similarity.form_factor_trend_statement(trend, ff.one_plus_k)
    result = ScalingFit(
        recommendation=recommendation, form_factor_trend=trend,
        form_factor_trend_text=trend_text,
        table=table, resistance=(k2, k1), tested_speed_range=(float(u.min()), float(u.max())),
        form_factor=ff, statement=statement, rho_p=rho_p, nu_p=nu_p, rho_m=rho_m, nu_m=nu_m,
        scale=scale, length_prototype=prototype.length_m,
        wetted_area_prototype=(model.wetted_area_m2 * scale**2
                               if model.wetted_area_m2 is not None else None),
        delta_cf=prototype.delta_cf,
        resistance_se=se, resistance_dof=float(res.df_resid),
    )
    outside = table.loc[~table["froude_in_tested_range"], "speed_prototype"].tolist()
    deep = air or (depth is not None and model.diameter_m is not None
                   and depth / model.diameter_m > similarity.DEEP_SUBMERGENCE_DEPTH_RATIO)
    if outside and not deep:  # deeply submerged, Froude scaling is not what counts
        warn.append(
            "Froude-scaled drag is extrapolated beyond the tested model speeds for prototype "
            "speeds " + ", ".join(f"{v:g}" for v in outside) + " m/s" + (
                " (the model ran near the surface, where Froude similarity is needed)."
                if depth is not None else
                " (give [model] depth_m: deeply submerged, Froude similarity is not needed).")
        )
    laminar = table.loc[table["re_prototype"] < laminar_re, "speed_prototype"]
    if len(laminar):
        note = ("prototype speeds " + ", ".join(f"{v:g}" for v in laminar) + " m/s give Re "
                f"below {laminar_re:g} ([processing] laminar_re), where the flow need not be "
                "turbulent: the ITTC-57 drag there is indicative only.")
        warn.append(note)
        result = replace(result, laminar_note=note)
    return result, warn


def model_scale(protocol: Protocol) -> float | None:
    """λ = L_p / L_m: [model] scale, else [prototype] length_m / [model] length_m, else None."""
    model, proto = protocol.model, protocol.prototype
    if model is None:
        return None
    if model.scale is not None:
        return model.scale
    return proto.length_m / model.length_m if proto is not None else None


def geometry_used(protocol: Protocol, scaling: ScalingFit | None) -> list[dict[str, Any]]:
    """The day's hull geometry with where each quantity came from; empty without a [model].

    ``scaling`` is the day's scaling result (its scale ratio), else the protocol's
    (:func:`model_scale`). See :func:`towtank.ingest.protocol.model_geometry`; the prototype's
    wetted area λ²·S_m is listed when the scale ratio is known.
    """
    model = protocol.model
    if model is None:
        return []
    scale = scaling.scale if scaling is not None else model_scale(protocol)
    return model_geometry(model, scale)
