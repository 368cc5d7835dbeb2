"""runs.csv: one row per run of the sheet, with each usable run's means and coefficients.

:func:`run_table` joins the run sheet, the reductions and the rejections of a day
(docs/formats.md §5): a run's ``status`` is ``ok``, ``void`` (the sheet says so) or
``rejected`` (its ``reason`` is ``str()`` of its :class:`towtank.messages.Rejection`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import pandas as pd

from towtank.analysis.run_coefficients import run_coefficients
from towtank.analysis.similarity import medium_at
from towtank.ingest.protocol_types import Protocol
from towtank.messages import Rejection
from towtank.reduce.captive import CaptiveRun
from towtank.reduce.run import RunReduction

__all__ = ["CAPTIVE_COLUMNS", "EXTRA_COLUMNS", "RUN_COLUMNS", "captive_columns", "run_table"]

#: runs.csv columns of a captive run: its hydrodynamic loads (inertia removed, the moment about
#: O) as the steady mean (static tests) or the cycle mean (PMM), and the PMM cycles used.
CAPTIVE_COLUMNS = ["captive_X_N", "captive_Y_N", "captive_N_Nm", "pmm_cycles"]

RUN_COLUMNS = [
    "run", "file", "config", "angle_deg", "status", "reason", "speed_mean", "accel_mean",
    "drag_mean", "lift_mean", "tare_drag", "cd", "cl", "re", "fn",
]
EXTRA_COLUMNS = [
    "test", "tare_group", "speed_nominal", "accel_nominal", "water_temp_C", "rho", "nu",
    "speed_std", "speed_source", "speed_u", "drag_std", "lift_tare", "cd_lateral", "cd_ref",
    "ref_area", "ref_area_m2", "zero_drag", "drift_drag", "zero_lift",
    "drift_lift", "still_pre_start_s", "still_pre_end_s", "accel_start_s", "accel_end_s",
    "steady_start_s", "steady_end_s", "decel_start_s", "decel_end_s", "window_source",
    "fs_hz", "n_samples", "sha256", "notes", "remarks",
]


def captive_columns(red: RunReduction) -> dict[str, float]:
    """runs.csv's :data:`CAPTIVE_COLUMNS` of a captive run's reduction (docs/formats.md)."""
    cr = CaptiveRun.from_arrays(red.run, red.file, red.captive)
    mean = cr.rows[cr.rows["component"] == "mean"].iloc[0]
    return {"captive_X_N": float(mean["X"]), "captive_Y_N": float(mean["Y"]),
            "captive_N_Nm": float(mean["N"]),
            "pmm_cycles": float(cr.cycles_used) if cr.cycles_used else math.nan}


def run_table(
    protocol: Protocol,
    sheet: pd.DataFrame,
    reductions: Mapping[int, RunReduction],
    rejected: Mapping[int, Rejection],
) -> pd.DataFrame:
    """runs.csv: one row per run of the sheet (docs/formats.md §5), then extension columns;
    each usable run's coefficients from
    :func:`towtank.analysis.run_coefficients.run_coefficients`."""
    rows = []
    model, fin = protocol.model, protocol.fin
    for rec in sheet.to_dict("records"):
        run = int(rec["run"])
        status = "void" if rec["status"] == "void" else "ok"
        reason = rec["remarks"] if status == "void" else ""
        if run in rejected:
            status, reason = "rejected", str(rejected[run])
        row: dict[str, Any] = {c: math.nan for c in RUN_COLUMNS + EXTRA_COLUMNS}
        row.update(dict.fromkeys(CAPTIVE_COLUMNS, math.nan))
        row.update(
            run=run, file=rec["file"], config=rec["config"], angle_deg=rec["angle_deg"],
            status=status, reason=reason, test=rec["test"], tare_group=rec["tare_group"],
            speed_nominal=rec["speed_nominal"], accel_nominal=rec["accel_nominal"],
            water_temp_C=rec["water_temp_C"], remarks=rec["remarks"], notes="",
            window_source="", sha256="", ref_area="",
        )
        red = reductions.get(run)
        if red is not None and status == "ok":
            rho, nu = medium_at(protocol.water, rec["water_temp_C"])
            u = red.speed_mean
            row.update(
                speed_mean=u, accel_mean=red.accel_mean, drag_mean=red.drag_mean,
                lift_mean=red.lift_mean, tare_drag=red.tare_drag, lift_tare=red.tare_lift,
                rho=rho, nu=nu, speed_std=red.speed_std, speed_source=red.speed_source,
                speed_u=red.speed_u, drag_std=red.drag_std,
                zero_drag=red.zero_drag, drift_drag=red.drift_drag, zero_lift=red.zero_lift,
                drift_lift=red.drift_lift, window_source=red.window_source, fs_hz=red.fs,
                n_samples=red.n_samples, sha256=red.sha256, notes="; ".join(red.notes),
            )
            for name in ("still_pre", "accel", "steady", "decel"):
                w = red.windows.get(name)
                if w is not None:
                    row[f"{name}_start_s"], row[f"{name}_end_s"] = w
            if red.captive:  # its loads are in the captive stage's tables, not a C_D
                row.update(captive_columns(red))
            else:
                row.update(run_coefficients(str(rec["config"]), float(rec["angle_deg"]),
                                            red.drag_mean, red.lift_mean, u, rho, nu, model,
                                            fin))
        rows.append(row)
    captive = any(r.captive for r in reductions.values())
    columns = RUN_COLUMNS + EXTRA_COLUMNS + (CAPTIVE_COLUMNS if captive else [])
    df = pd.DataFrame(rows, columns=columns)
    extra = [c for c in sheet.columns if c not in df.columns and c not in ("sheet_row",
                                                                           "sheet_error",
                                                                           "window_start_s",
                                                                           "window_end_s")]
    for c in extra:
        df[c] = sheet[c].to_numpy()
    if "segment" in df.columns:  # whole numbers from 1 (a run's acquisition), empty for none
        df["segment"] = pd.to_numeric(df["segment"], errors="coerce").round().astype("Int64")
    for c in ("window_start_s", "window_end_s"):
        if sheet[c].notna().any():
            df[c] = sheet[c].to_numpy()
    return df
