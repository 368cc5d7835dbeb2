"""Plausibility of a day's hull coefficients and fin lift: a lab's slips caught before they
become results.

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
- A fin's lift slope against what a fin can have (:func:`fin_plausibility_warnings`): from
  :data:`FIN_SLOPE_LOW` times its finite-span slope to :data:`FIN_SLOPE_HIGH` times its
  section's. Far below, the lift and drag channels are swapped (then C_D rises with α as a
  lift does), a lift gain was left out or the lift is in another unit; negative, the lift's
  sign is reversed; far above, the lift is in a smaller unit or the fin's area too small.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import pandas as pd

from towtank.analysis import fins
from towtank.reference.geometry import displaced_volume

__all__ = ["displaced_volume", "fin_plausibility_warnings", "plausibility_warnings"]

#: Plausible −X_udot / (ρV) for a hull [-] (a sphere has 0.5, a slender body a few percent).
AXIAL_RANGE = (0.003, 0.6)
#: Plausible −Y_vdot / (ρV) for a hull [-] (a long cylinder has 1).
TRANSVERSE_RANGE = (0.2, 2.0)
#: Plausible C_D at α = 0 of a streamlined body on its frontal area [-].
CD0_RANGE = (0.05, 1.5)
#: Plausible transverse C_D,90 on the lateral area [-] (a cylinder in cross-flow: 0.3–1.3).
CD90_RANGE = (0.1, 3.0)
#: A fin's measured lift slope below this times its finite-span (lifting-line) slope is
#: implausible [-]: see :func:`fin_plausibility_warnings`.
FIN_SLOPE_LOW = 0.3
#: ... and above this times the larger of its section's slope and 2π [-].
FIN_SLOPE_HIGH = 1.5
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


def _slope_text(x: float) -> str:
    """A slope or a ratio as read: 5882, 5.94, 0.061."""
    return f"{x:.0f}" if abs(x) >= 100 else f"{x:.2f}" if abs(x) >= 0.1 else f"{x:.2g}"


def _span(values: list[float], text: Callable[[float], str] = _slope_text) -> str:
    """"0.061–0.072" (the least and the largest; "-5.3 to -4.1" below 0), or one value when
    they read the same."""
    lo, hi = text(min(values)), text(max(values))
    return lo if lo == hi else f"{lo} to {hi}" if min(values) < 0 else f"{lo}–{hi}"


def _and(items: list[str], word: str = "and") -> str:
    """"a, b and c" ("a, b or c" with ``word`` "or")."""
    return items[0] if len(items) == 1 else f"{', '.join(items[:-1])} {word} {items[-1]}"


def fin_plausibility_warnings(curves: pd.DataFrame, table: pd.DataFrame,
                              aspect_ratio: float) -> list[str]:
    """Sentences for the fin lift slopes that no fin of this geometry can have.

    Each speed group's measured linear-range lift slope a (``fin_curves.csv``) is set against
    the same fit through the same angles of what the fin can have: a_3D, the lifting-line
    slope of the fin's effective aspect ratio on the Sandia NACA 0015 section at the group's
    Re (``lift_slope_3d``), and a_2D, the section's own (``lift_slope_sandia_2d``). A fin's
    slope lies between the two: a_3D with free tips, a_2D when it spans the test section or
    has end plates. The band is wider than that on both sides, so that no real fin is flagged:

    - below :data:`FIN_SLOPE_LOW` · a_3D: for an effective aspect ratio of 0.5 or more,
      low-aspect-ratio theory (Helmbold 1942, a = a0/(√(1 + k²) + k), k = a0/(π·AR)) gives
      about 0.6 of the lifting line's a0/(1 + k) or more (half of it only as AR → 0), and a
      fin stated as on a wall (``mounting = "wall"``, AR doubled) that was tested free keeps
      about 0.6 of its expectation or more: both together leave about 0.37;
    - above :data:`FIN_SLOPE_HIGH` · max(a_2D, 2π): a fin's slope is at most its section's,
      and no section exceeds thin-aerofoil theory by much (the inviscid slope of a 15 % thick
      section is about 2π(1 + 0.77 t/c) = 1.12·2π, a viscous one is lower; Abbott & von
      Doenhoff 1959, Theory of Wing Sections); the tank's walls add a few per cent (Barlow,
      Rae & Pope 1999, Low-Speed Wind Tunnel Testing), so 1.5 leaves room for the scatter of
      a slope fitted to a few angles.

    The slips it catches change the slope by a factor of 3 or more: the lift and drag channels
    swapped (a is then C_D's slope, near 0; the sentence says "swapped?" when C_D rises with α
    as a lift does: its slope over the same angles is within the band and above |a|), a lift
    gain left out (the lift in V: a gain of 25 N/V leaves 1/25 of a), the lift in kgf (1/9.81;
    lbf, 1/4.45, only where the fin's slope is near its finite-span one), a reversed sign
    (a < 0), or the lift in mV or gram-force (a far above). One sentence per kind of slip,
    naming the groups, the measured and expected slopes and the band; the values are still
    reported (a check can be wrong for an unusual fin).

    Parameters
    ----------
    curves : DataFrame
        fin_curves.csv (:func:`towtank.analysis.fins.fin_curves` with ``aspect_ratio``:
        speed_group [m/s], lift_slope, lift_slope_sandia_2d, lift_slope_3d [1/rad],
        slope_angles_deg).
    table : DataFrame
        fins.csv (:func:`towtank.analysis.fins.fin_table`: speed_group, angle_deg, cl, cd).
    aspect_ratio : float
        The fin's effective aspect ratio [-], for the sentence.

    Returns
    -------
    list of str
    """
    kinds: dict[tuple[bool, str], list[dict[str, float]]] = {}
    for row in curves.to_dict("records"):
        a, a3, a2 = (float(row[k]) for k in ("lift_slope", "lift_slope_3d",
                                                 "lift_slope_sandia_2d"))
        if not (math.isfinite(a) and math.isfinite(a3) and math.isfinite(a2)) or a3 <= 0:
            continue
        low, high = FIN_SLOPE_LOW * a3, FIN_SLOPE_HIGH * max(a2, 2.0 * math.pi)
        if low <= a <= high:
            continue
        angles = [float(v) for v in str(row["slope_angles_deg"]).split()]
        group = table[(table["speed_group"] == row["speed_group"])
                      & table["angle_deg"].isin(angles) & table["cl"].notna()]
        cd_slope = fins.linear_slope(group["angle_deg"], group["cd"])
        swapped = (math.isfinite(cd_slope) and low <= abs(cd_slope) <= high
                   and abs(cd_slope) > abs(a))
        size = "low" if abs(a) < low else "high" if abs(a) > high else "in"
        kinds.setdefault((a < 0, size), []).append({
            "speed": float(row["speed_group"]), "a": a, "a3": a3, "a2": a2, "low": low,
            "high": high, "cd_slope": cd_slope, "swapped": float(swapped)})
    out = []
    for (negative, size), rows in kinds.items():
        def col(key: str, rows: list[dict[str, float]] = rows) -> list[float]:
            return [r[key] for r in rows]
        speeds = _and([f"{v:.2f}" for v in col("speed")])
        ratio = _span([a / a3 for a, a3 in zip(col("a"), col("a3"), strict=True)])
        head = (f"fin lift slope = {_span(col('a'))} /rad at U ≈ {speeds} m/s is {ratio} times "
                f"the {_span(col('a3'))} /rad expected of this fin (lifting line at effective "
                f"aspect ratio {aspect_ratio:.3g}; the NACA 0015 section's own slope is "
                f"{_span(col('a2'))} /rad), outside the {_slope_text(min(col('low')))}–"
                f"{_slope_text(max(col('high')))} /rad a fin can have")
        if size != "high" and all(col("swapped")):
            out.append(f"{head}, and C_D rises {_span([abs(v) for v in col('cd_slope')])} /rad "
                       "with α over the same angles as a lift does: lift and drag channels "
                       "swapped? (check [channels] lift and drag)")
            continue
        slips = ["the lift channel's sign reversed (the sign of its gain)"] if negative else []
        if size == "low":
            slips += ["a lift gain left out (the lift in V or mV: a gain of 25 N/V left out "
                      "gives 1/25 of the slope)", "the lift in another unit than N (kgf, lbf)",
                      "the lift and drag channels swapped"]
        elif size == "high":
            slips += ["the lift in a smaller unit than N (mV with a gain per V, gram-force)",
                      "a lift gain too large", "[fin] chord_m × span_m smaller than the fin"]
        else:
            slips += ["the angles counted the other way round"]
        out.append(f"{head}: {_and(slips, 'or')}?")
    return out
