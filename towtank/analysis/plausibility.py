"""Plausibility of a day's hull coefficients: a lab's slips caught before they become results.

Each check is a sentence that names the likely cause, added to the day's warnings (the values
are still reported: a check can be wrong for an unusual body). docs/method.md "Plausibility".

- Added mass against the geometry. For a slender body of revolution the axial added mass is a
  few percent of the displaced mass ρV and the transverse one about ρV (a prolate spheroid of
  L/D = 7: k1 = 0.036, k2 = 0.93; Lamb 1932, Hydrodynamics §373, Table in Newman 1977, Marine
  Hydrodynamics §4.15). −X_udot outside [:data:`AXIAL_RANGE`]·ρV or −Y_vdot outside
  [:data:`TRANSVERSE_RANGE`]·ρV is implausible; values outside them by about 10³ point to a
  unit (a mass in grams, forces in mV, a missing gain).
- Signs: X_udot, Y_vdot, X_u|u|, Y_uv and Y_v|v| are negative for any body moving through
  water (added mass is positive, drag opposes the motion). A positive one is a force channel
  whose sign is reversed (a gain of the wrong sign), or a mass far off.
- C_D at α = 0 of a streamlined body lies in :data:`CD0_RANGE` and the transverse C_D,90 of a
  cylinder in :data:`CD90_RANGE`; far outside, the forces are in other units.
"""

from __future__ import annotations

import math

import pandas as pd

from towtank.reference.geometry import displaced_volume

__all__ = ["displaced_volume", "plausibility_warnings"]

#: Plausible −X_udot / (ρV) for a hull [-] (a sphere has 0.5, a slender body a few percent).
AXIAL_RANGE = (0.003, 0.6)
#: Plausible −Y_vdot / (ρV) for a hull [-] (a long cylinder has 1).
TRANSVERSE_RANGE = (0.2, 2.0)
#: Plausible C_D at α = 0 of a streamlined body on its frontal area [-].
CD0_RANGE = (0.05, 1.5)
#: Plausible transverse C_D,90 on the lateral area [-] (a cylinder in cross-flow: 0.3–1.3).
CD90_RANGE = (0.1, 3.0)
#: Coefficients that are negative for any body (SNAME convention, docs/method.md).
NEGATIVE = ("X_udot", "Y_vdot", "X_u|u|", "Y_uv", "Y_v|v|")

_UNITS_HINT = (
    "a value plausible only in other units: are the force channels in N (a gain left out, "
    "so the forces are in mV or V, or in gram-force), and is [model] mass_kg in kg?"
)


def _value(table: pd.DataFrame, symbol: str) -> float:
    rows = table.loc[table["symbol"] == symbol, "value"]
    return float(rows.iloc[0]) if len(rows) else math.nan


def plausibility_warnings(
    table: pd.DataFrame,
    *,
    rho: float,
    volume_m3: float | None,
    frontal_area_m2: float,
    lateral_area_m2: float,
    added_mass: bool = True,
) -> list[str]:
    """Sentences for the hull coefficients that no body of this geometry can have.

    Parameters
    ----------
    table : DataFrame
        The coefficient table (columns ``symbol`` and ``value``, SI model-scale values).
    rho : float
        Water density [kg/m³].
    volume_m3 : float or None
        Displaced volume [m³] (:func:`displaced_volume`); the added-mass checks need it.
    frontal_area_m2, lateral_area_m2 : float
        Reference areas of C_D at α = 0 and of the transverse C_D,90 [m²].
    added_mass : bool, default True
        Check X_udot and Y_vdot (sign and size against ρV). False in air, where the added
        mass (about ρ_air·V, a thousandth of the water's) is below the uncertainty of the
        weighed mass, so that its sign and size are noise (the day's note says so).

    Returns
    -------
    list of str
    """
    out: list[str] = []
    for sym in NEGATIVE:
        if not added_mass and sym.endswith("dot"):
            continue
        v = _value(table, sym)
        if math.isfinite(v) and v > 0:
            small = (", its gain left out (forces in V are too small beside the weighed "
                     "mass's inertia m·a)" if sym.endswith("dot") else "")
            out.append(
                f"{sym} = {v:+.4g} is positive, but it is negative for any body (added mass is "
                "positive, drag opposes the motion): is a force channel's sign reversed (the "
                f"sign of its gain){small}, or [model] mass_kg far off?"
            )
    if added_mass and volume_m3 is not None and rho > 0:
        disp = rho * volume_m3
        for sym, (lo, hi), what in (("X_udot", AXIAL_RANGE, "axial"),
                                    ("Y_vdot", TRANSVERSE_RANGE, "transverse")):
            v = _value(table, sym)
            if not math.isfinite(v) or v > 0:
                continue  # a positive one is named by the sign check
            k = -v / disp
            if not lo <= k <= hi:
                hint = _UNITS_HINT if (k > 20 * hi or k < lo / 20) else (
                    "check [model] mass_kg (the weighed mass of everything the balance "
                    "carries) and the force channels' gains")
                out.append(
                    f"{sym} = {v:.4g} kg is {k:.3g} times the displaced mass ρV = {disp:.4g} kg, "
                    f"but the {what} added mass of a hull is {lo:g}–{hi:g} ρV: {hint}"
                )
    q = 0.5 * rho
    for sym, area, (lo, hi), name in (("X_u|u|", frontal_area_m2, CD0_RANGE, "C_D at α = 0"),
                                      ("Y_v|v|", lateral_area_m2, CD90_RANGE, "C_D,90")):
        v = _value(table, sym)
        if not math.isfinite(v) or not area > 0:
            continue
        cd = -v / (q * area)
        if cd > 0 and not lo <= cd <= hi:
            hint = _UNITS_HINT if (cd > 5 * hi or cd < lo / 5) else (
                "check the reference area, and the drag channel's gain (left out, the forces "
                "are in V or mV)" if cd < lo else "check the reference area")
            out.append(f"{name} = {cd:.3g} (from {sym} = {v:.4g} kg/m) is outside the "
                       f"{lo:g}–{hi:g} of a streamlined hull: {hint}")
    return out
