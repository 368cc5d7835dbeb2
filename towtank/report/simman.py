"""``--export simman``: the captive tests as the SIMMAN workshops exchange them.

Files in the output folder's ``export/simman/`` (docs/formats.md, "--export simman"):

====================  ===========================================================================
file                  content
====================  ===========================================================================
particulars.csv       quantity, value, unit: scale, L, mass, I_z (I_y), x_G, x of the balance,
                      x of the point P the moments refer to, draught, water temperature and
                      density, sample rate
static.csv            one row per static run (drift, rudder, arm) of the horizontal plane: its
                      setting, speed and the steady mean loads X, Y [N], N [N m] about P
                      (inertia removed) with their standard errors
static_vertical.csv   the same for the vertical plane (X, Z, M; w and q mapped from the rig)
pmm_run_NNN.csv       a PMM run's filtered, cycle-averaged period: t, X, Y, N, x, y, psi, u, v,
                      r, udot, vdot, rdot
pmm_fourier.csv       every PMM run's Fourier coefficients of X, Y, N over that period
                      (mean and harmonics 1 to 3, sin and cos) and the first harmonics averaged
                      cycle by cycle with their standard errors
====================  ===========================================================================

Everything comes from the day's captive results (nothing is read again): a day without captive
runs writes nothing and says so.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pandas as pd

from towtank.analysis.captive import mapped_rows, plane_names
from towtank.reduce.captive import PMM_TESTS, harmonic_fit, protocol_reference_x
from towtank.report.safetext import csv_text

if TYPE_CHECKING:
    from towtank.analysis.captive import CaptiveFit
    from towtank.reduce.captive import CaptiveRun
    from towtank.results import DayResult

#: Columns of a PMM run's period file (t, loads, positions, velocities, accelerations).
PERIOD_EXPORT = ("t", "X", "Y", "N", "x", "y", "psi", "u", "v", "r", "udot", "vdot", "rdot")
#: Harmonics of pmm_fourier.csv (besides the mean).
FOURIER_HARMONICS = (1, 2, 3)


def particulars(day: DayResult) -> pd.DataFrame:
    """particulars.csv: quantity, value, unit (empty value where the protocol does not say)."""
    m = day.protocol.model
    w = day.protocol.water
    runs = day.runs
    captive = runs[runs["captive_Y_N"].notna()] if "captive_Y_N" in runs.columns else runs
    fs = captive["fs_hz"].dropna()
    rho = captive["rho"].dropna()

    def get(name: str) -> float:
        v = getattr(m, name, None) if m is not None else None
        return math.nan if v is None else float(v)

    rows = [("scale", get("scale"), "-"), ("length_m", get("length_m"), "m"),
            ("mass_kg", get("mass_kg"), "kg"), ("izz_kg_m2", get("izz_kg_m2"), "kg m^2"),
            ("iyy_kg_m2", get("iyy_kg_m2"), "kg m^2"), ("xg_m", get("xg_m"), "m"),
            ("balance_x_m", get("balance_x_m"), "m"),
            ("moment_ref_x_m", protocol_reference_x(day.protocol.captive, m), "m"),
            ("draught_m", get("draught_m"), "m"),
            ("water_temperature_C", float(captive["water_temp_C"].dropna().mean())
             if captive["water_temp_C"].notna().any() else float(w.temperature_C), "degC"),
            ("rho_kg_m3", float(rho.mean()) if len(rho) else math.nan, "kg/m^3"),
            ("sample_rate_hz", float(fs.median()) if len(fs) else math.nan, "Hz")]
    return pd.DataFrame(rows, columns=["quantity", "value", "unit"])


def static_table(fit: CaptiveFit, roll_deg: float) -> pd.DataFrame:
    """The plane's static runs: run, file, test, speed [m/s], drift_deg, rudder_deg,
    radius_m, and the loads (plane names) with their standard errors."""
    (ef, em), _ = plane_names(fit.plane)
    recs = []
    for r in fit.runs:
        if r.test in PMM_TESTS:
            continue
        mean = mapped_rows(r, roll_deg).iloc[0]
        recs.append({"run": r.run, "file": csv_text(r.file), "test": r.test, "speed": r.speed,
                     "drift_deg": r.drift_deg, "rudder_deg": r.rudder_deg,
                     "radius_m": r.radius_m,
                     **{q: float(mean[q]) for q in ("X", ef, em)},
                     **{f"{q}_se": float(mean[f"{q}_se"]) for q in ("X", ef, em)}})
    return pd.DataFrame(recs, columns=["run", "file", "test", "speed", "drift_deg",
                                       "rudder_deg", "radius_m", "X", ef, em, "X_se",
                                       f"{ef}_se", f"{em}_se"])


def period_table(run: CaptiveRun) -> pd.DataFrame:
    """A PMM run's cycle-averaged period (:data:`PERIOD_EXPORT`): x [m] = U t, the distance
    towed from the period's start; y [m] the sway of O, psi [rad] the heading (drift + yaw),
    loads X, Y [N], N [N m] about the point P the day's moments refer to (O, or the balance
    point with ``[captive] moment_ref = "balance"``) with the inertia removed (rig axes)."""
    p = run.period
    out = p[[c for c in PERIOD_EXPORT if c in p.columns]].copy()
    out.insert(4, "x", run.speed * p["t"].to_numpy(dtype=float))
    return out[list(PERIOD_EXPORT)]


def fourier_table(runs: list[CaptiveRun], length_m: float) -> pd.DataFrame:
    """pmm_fourier.csv: per PMM run and load, the mean and the sin/cos coefficients of
    harmonics 1 to 3 of its cycle-averaged period, and the cycle-by-cycle first harmonics
    (``cycle_mean``, ``cycle_sin``, ``cycle_cos``) with their standard errors."""
    recs = []
    for r in runs:
        p = r.period.dropna()
        omega = 2.0 * math.pi * r.frequency_hz
        comps = r.rows.set_index("component")
        for q in ("X", "Y", "N"):
            coef = harmonic_fit(p["t"].to_numpy(dtype=float), p[q].to_numpy(dtype=float),
                                omega, FOURIER_HARMONICS)
            rec: dict[str, Any] = {
                "run": r.run, "test": r.test, "frequency_hz": r.frequency_hz,
                "amplitude_m": r.amplitude_m, "omega_prime": r.omega_prime(length_m),
                "cycles_used": r.cycles_used, "quantity": q, "mean": float(coef[0])}
            for j, k in enumerate(FOURIER_HARMONICS):
                rec[f"sin{k}"], rec[f"cos{k}"] = float(coef[1 + 2 * j]), float(coef[2 + 2 * j])
            for c in ("mean", "sin", "cos"):
                rec[f"cycle_{c}"] = float(comps.at[c, q])
                rec[f"cycle_{c}_se"] = float(comps.at[c, f"{q}_se"])
            recs.append(rec)
    return pd.DataFrame(recs)


def write_simman(day: DayResult, folder: str | Path, roll_deg: float = 90.0) -> list[str]:
    """Write ``folder/export/simman/`` (see the module docstring); the sentences to report
    (a day without captive results writes nothing and says so)."""
    fits = tuple(getattr(day, "captive_results", ()) or ())
    if not fits:
        return ["--export simman: the day has no captive results (no usable drift, rudder, "
                "arm or PMM runs), so nothing was exported"]
    out = Path(folder) / "export" / "simman"
    out.mkdir(parents=True, exist_ok=True)
    particulars(day).to_csv(out / "particulars.csv", index=False)
    pmm: list[CaptiveRun] = []
    length = fits[0].length_m
    for fit in fits:
        name = "static.csv" if fit.plane == "horizontal" else "static_vertical.csv"
        static_table(fit, roll_deg).to_csv(out / name, index=False)
        pmm += [r for r in fit.runs if r.test in PMM_TESTS and len(r.period)]
    for r in pmm:
        period_table(r).to_csv(out / f"pmm_run_{r.run:03d}.csv", index=False)
    if pmm:
        fourier_table(pmm, length).to_csv(out / "pmm_fourier.csv", index=False)
    return []


__all__ = ["PERIOD_EXPORT", "fourier_table", "particulars", "period_table", "static_table",
           "write_simman"]
