"""Predicted beside measured: coefficients.csv's ``predicted`` columns and the day's model.

For a processed day whose protocol has a ``[vehicle]``, every measured coefficient is set beside
its prediction (:mod:`towtank.vehicle.predict`) as prime values, so that a prediction for the
prototype (``[vehicle] scale``) compares with the model's measurement:
``predicted_diff_pct = (prime - predicted_prime) / |predicted_prime| * 100``. The model.json of
the day takes the measured values (converted through their primes to the vehicle's length and
the protocol's water) with the covariance of their standard errors, and the prediction for
every other term. Coefficients measured by captive tests (:data:`CAPTIVE_METHODS`) are totals:
model.json takes them converted to the Fossen form once
(:func:`towtank.vehicle.model.totals_to_fossen`), unless ``[captive] form = "fossen"``; and only
when they refer to the vehicle's origin O: with ``[captive] moment_ref = "balance"`` and the
balance away from O they refer to the balance point, and model.json keeps the prediction for
them (:func:`captive_reference_note`).
"""

from __future__ import annotations

import math
import re
from typing import Any

import numpy as np
import pandas as pd

from towtank.errors import TowtankError
from towtank.reduce.captive import protocol_reference_x
from towtank.vehicle.model import FORMS
from towtank.vehicle.predict import prime_exponent
from towtank.vehicle.stage import VehiclePrediction, predict_vehicle

__all__ = ["CAPTIVE_METHODS", "FAR_PCT", "captive_form", "captive_reference_note", "day_vehicle",
           "drag_side_only",
           "measured_forms", "measured_for_vehicle", "with_predicted"]

#: A measured prime further than this from its prediction is a warning [%].
FAR_PCT = 50.0
#: The captive tests a coefficients.csv ``method`` names (FORMATS section 8): a coefficient
#: they measured is a total, holding the added-mass part of C_A(nu).
CAPTIVE_METHODS = ("static drift", "rudder", "rotating arm", "pure sway", "pure yaw",
                   "yaw and drift", "means table")
_CAPTIVE_RE = re.compile(r"\b(" + "|".join(CAPTIVE_METHODS) + r")\b", re.IGNORECASE)


def captive_form(protocol: Any) -> str:
    """``[captive] form`` of the protocol: ``"total"`` (default) or ``"fossen"``."""
    captive = getattr(protocol, "captive", None)
    form = captive.get("form") if isinstance(captive, dict) else getattr(captive, "form", None)
    if form is None:
        return "total"
    if form not in FORMS:
        raise TowtankError(f"[captive] form must be one of {', '.join(map(repr, FORMS))}, "
                           f"not {form!r}.")
    return str(form)


def captive_reference_note(protocol: Any) -> str | None:
    """Why the captive derivatives stay out of model.json, or None when they refer to O.

    With ``[captive] moment_ref = "balance"`` and ``[model] balance_x_m`` ≠ 0, the
    derivatives refer to the balance point (:func:`towtank.reduce.captive.reference_x`), not
    to the origin O of the vehicle's equations of motion: N_O = N_B + x_B·Y and v_B = v +
    x_B·r change the moment and the yaw-rate derivatives, and v_B|v_B| is no term at O."""
    x = protocol_reference_x(getattr(protocol, "captive", None),
                             getattr(protocol, "model", None))
    if x == 0.0:
        return None
    return (f"the captive derivatives refer to the balance point, {x:g} m from O ([captive] "
            "moment_ref = \"balance\"), not to the vehicle's origin: model.json keeps the "
            "prediction for them; process with moment_ref = \"origin\" to put them in.")


def measured_forms(coefficients: pd.DataFrame, form: str = "total") -> dict[str, str]:
    """The form of each coefficient a captive test measured: ``form`` for the rows whose
    ``method`` names a captive test (:data:`CAPTIVE_METHODS`); the others are not listed."""
    if "method" not in coefficients:
        return {}
    return {str(sym): form for sym, method in zip(coefficients["symbol"],
                                                  coefficients["method"], strict=True)
            if isinstance(method, str) and _CAPTIVE_RE.search(method)}


def measured_for_vehicle(
    coefficients: pd.DataFrame, rho: float, length_m: float | None
) -> tuple[dict[str, float], tuple[list[str], np.ndarray]]:
    """Measured SI values for the vehicle and their covariance (diagonal of the standard
    errors: the fits report no correlations between coefficients).

    ``length_m`` None: the vehicle is the tested model, the values are taken as measured.
    Otherwise value_vehicle = prime * 1/2 rho L^k and std = std_error * value_vehicle / value,
    k from :func:`towtank.vehicle.predict.prime_exponent`.
    """
    values: dict[str, float] = {}
    sds: dict[str, float] = {}
    for _, row in coefficients.iterrows():
        sym, prime, value = str(row["symbol"]), row.get("prime"), row.get("value")
        if prime is None or not np.isfinite(float(prime)) or float(value) == 0.0:
            continue
        factor = (float(value) / float(prime) if length_m is None
                  else 0.5 * rho * length_m ** prime_exponent(sym))
        values[sym] = float(prime) * factor
        sd = float(row.get("std_error", math.nan))
        if math.isfinite(sd):
            sds[sym] = abs(sd / float(value) * float(prime) * factor)
    symbols = list(sds)
    return values, (symbols, np.diag([sds[s] ** 2 for s in symbols]))


def with_predicted(coefficients: pd.DataFrame, predicted: pd.DataFrame) -> tuple[
        pd.DataFrame, list[str]]:
    """coefficients.csv with ``predicted`` (prime) and ``predicted_diff_pct``; the warnings."""
    out = coefficients.copy()
    pred = dict(zip(predicted["symbol"], predicted["prime"], strict=True))
    out["predicted"] = [pred.get(s, math.nan) for s in out["symbol"]]
    p = out["prime"].astype(float)
    q = out["predicted"].astype(float)
    out["predicted_diff_pct"] = np.where(np.isfinite(q) & (q != 0), (p - q) / q.abs() * 100.0,
                                         np.nan)
    far = [(s, pm, pq, d)
           for s, pm, pq, d in zip(out["symbol"], p, q, out["predicted_diff_pct"], strict=True)
           if math.isfinite(d) and abs(d) > FAR_PCT]
    side = drag_side_only(out)
    warnings = [
        f"{s}: the measured prime {pm:.4g} is {d:+.0f} % from the predicted {pq:.4g} "
        f"(more than ±{FAR_PCT:g} %): check the measurement or the [vehicle] geometry."
        for s, pm, pq, d in far if s not in side
    ]
    known = [(s, pm, pq, d) for s, pm, pq, d in far if s in side]
    if known:
        _, pm, pq, d = known[0]
        names = " and ".join(s for s, *_ in known)
        warnings.append(
            f"{names}: the measured prime {pm:.4g} is {d:+.0f} % from the predicted {pq:.4g} "
            f"(more than ±{FAR_PCT:g} %), as expected: the SUT-2 method (report eq. 15) "
            "measures only the drag's side component (Y_uv = X_u|u|), while the prediction "
            "from the [vehicle] geometry includes the hull's lift; model.json takes the "
            "measured value, without that lift.")
    return out, warnings


def drag_side_only(coefficients: pd.DataFrame) -> set[str]:
    """Y_uv and Z_uw when measured as the SUT-2 report does (its eq. 15): the side component of
    the drag alone, so that their prime equals X_u|u|'s. A geometry prediction adds the hull's
    lift, so that these two differ from it by design, not by a measurement fault."""
    primes = dict(zip(coefficients["symbol"], coefficients["prime"].astype(float), strict=True))
    xuu = primes.get("X_u|u|", math.nan)
    return {s for s in ("Y_uv", "Z_uw") if s in primes and math.isfinite(xuu)
            and math.isclose(primes[s], xuu, rel_tol=1e-9)}


def day_vehicle(protocol: Any, coefficients: pd.DataFrame | None) -> tuple[
        VehiclePrediction, pd.DataFrame | None, list[str]]:
    """The day's prediction and model (measured values first), coefficients.csv with the
    predicted columns (None without measured coefficients) and the warnings."""
    try:
        first = predict_vehicle(protocol)
    except ValueError as exc:  # e.g. a hull table that cannot be read: the day goes on
        raise TowtankError(f"[vehicle]: no prediction ({exc})") from None
    if coefficients is None or coefficients.empty:
        return first, None, []
    length: float | None = first.profile.length
    model, vehicle = getattr(protocol, "model", None), protocol.vehicle
    if model is not None and model.myring is not None and vehicle.hull == "myring" and (
            vehicle.myring == {k: float(getattr(model.myring, k)) for k in vehicle.myring}):
        length = None if vehicle.scale == 1.0 else model.length_m * vehicle.scale
    forms = measured_forms(coefficients, captive_form(protocol))
    note = captive_reference_note(protocol) if forms else None
    usable = (coefficients[~coefficients["symbol"].isin(list(forms))] if note is not None
              else coefficients)
    measured, cov = measured_for_vehicle(usable, first.rho, length)
    result = predict_vehicle(protocol, measured, cov, {} if note is not None else forms)
    table, warnings = with_predicted(coefficients, result.predicted)
    return result, table, [*warnings, *([note] if note is not None else [])]
