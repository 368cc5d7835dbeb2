"""What the report records of the day besides its tables: provenance (inputs with their sha256,
versions, settings, geometry and scaling used) and the test date with where it comes from.

Used by the workbook, the PDF and provenance.json alike, so that each says the same.
"""

from __future__ import annotations

import datetime as dt
import math
import platform
import struct
from dataclasses import asdict
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd
import scipy
from nptdms import TdmsFile

from towtank import __version__
from towtank.analysis.scaling import geometry_used
from towtank.ingest.readers import nptdms_quiet
from towtank.reduce.tare import tare_table
from towtank.reference.sets import reference_name

if TYPE_CHECKING:
    from towtank.ingest.protocol_types import Prototype
    from towtank.results import DayResult, ScalingResult, TareResult


def provenance(day: DayResult, extra: dict[str, Any] | None = None) -> dict[str, Any]:
    """Inputs with their sha256, program and library versions, settings used.

    A hull day also records the geometry used (each area and the volume with where it came
    from: given in the protocol, computed from the Myring description, or a default) and, when
    scaled, the prototype, its water and the form factor.
    """
    p = day.protocol
    if p.model is not None:
        extra = {"geometry": {"geometry_source": p.model.geometry_source,
                              "quantities": geometry_used(day.protocol, day.scaling)},
                 **(extra or {})}
    if day.scaling is not None:
        extra = {"scaling": _scaling_provenance(day.scaling, p.prototype),
                 **(extra or {})}
    if day.captive_results:
        extra = {"captive": captive_provenance(day), **(extra or {})}
    vehicle = getattr(day, "vehicle", None)
    if vehicle is not None and "assumptions" in vehicle.model:  # model.json's, the same list
        extra = {"assumptions": vehicle.model["assumptions"], **(extra or {})}
    settings = {
        "processing": asdict(p.processing),
        "trim_s_used": p.processing.trim,
        "water": medium_settings(p.water),
        "channels": {k: asdict(v) for k, v in p.channels.items()},
        "reference": p.campaign.reference,
        "reference_name": reference_name(p.campaign.reference),
    }
    if p.model is not None:  # stated standard uncertainties [kg], [m] (fit, coefficients_table)
        settings["model_uncertainty"] = {
            k: getattr(p.model, k)
            for k in ("mass_uncertainty_kg", "length_uncertainty_m", "diameter_uncertainty_m")
        }
    return {
        "program": "towtank",
        "version": __version__,
        "python": platform.python_version(),
        "libraries": {
            "numpy": np.__version__,
            "scipy": scipy.__version__,
            "pandas": pd.__version__,
        },
        "protocol": str(p.path),
        "campaign": p.campaign.name,
        "inputs": [{"path": k, "sha256": v} for k, v in day.inputs.items()],
        "settings": settings,
        "runs": {"total": int(len(day.sheet)), "rejected": day.n_rejected},
        "tare": _tare_provenance(day.tare),
        **(extra or {}),
    }


def medium_settings(water: Any) -> dict[str, Any]:
    """A [water] or [prototype.water] section as provenance.json gives it: water as before
    (type, temperature_C, salinity_g_kg); air with its pressure [Pa], relative humidity [%] and
    the formulations of its properties."""
    out = asdict(water)
    if not water.is_air:
        for key in ("pressure_Pa", "relative_humidity_pct"):
            out.pop(key, None)
        return out
    out.pop("salinity_g_kg", None)
    out["properties"] = ("density: CIPM-2007 (Picard et al. 2008, Metrologia 45, 149); "
                         "viscosity: Sutherland's law (White, Viscous Fluid Flow, 2006)")
    return out


def _tare_provenance(tare: TareResult) -> list[dict[str, Any]]:
    """The sting tare fits (tare.csv's rows): coefficients, intervals, runs and ranges."""
    table = tare_table(tare.models)
    return [{k: (v.item() if hasattr(v, "item") else v) for k, v in row.items()}
            for row in table.to_dict("records")]


def _scaling_provenance(sr: ScalingResult, proto: Prototype | None) -> dict[str, Any]:
    """The prototype, its water and the form factor behind scaling.csv."""
    ff = sr.form_factor
    return {
        "scale": sr.scale,
        "length_prototype_m": sr.length_prototype,
        "prototype_water": medium_settings(proto.water) if proto is not None else None,
        "rho_prototype": sr.rho_p,
        "nu_prototype": sr.nu_p,
        "wetted_area_prototype_m2": sr.wetted_area_prototype,
        "delta_cf": sr.delta_cf,
        "form_factor": None if ff is None else {
            "one_plus_k": ff.one_plus_k,
            "std": ff.std if math.isfinite(ff.std) else None,  # NaN (one speed): null
            "n_speeds": ff.n,
            "n_runs": ff.n_runs,
            "speeds_m_s": [float(v) for v in ff.speeds],
            "one_plus_k_per_speed": [float(v) for v in ff.speed_values],
            "re_range": list(ff.re_range),
            "trend": _trend(sr.form_factor_trend),
        },
        "recommended": None if sr.recommendation is None else {
            "column": sr.recommendation.column, "rule": sr.recommendation.rule},
    }


def _trend(trend: Any) -> dict[str, Any] | None:
    """The form factor's slope against Re (similarity.FormFactorTrend); null when untested."""
    if trend is None or not math.isfinite(trend.slope):
        return None
    return {"slope_per_re": trend.slope, "ci_low": trend.ci_low, "ci_high": trend.ci_high,
            "dof": trend.dof, "p_value": trend.p_value, "significant": trend.significant}


# ------------------------------------------------------------------------------ test date
def _iso(value: Any) -> str | None:
    """A date-like value as YYYY-MM-DD, or None."""
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return None
    ts = pd.to_datetime(str(value).strip(), errors="coerce")
    return None if ts is pd.NaT or pd.isna(ts) else ts.strftime("%Y-%m-%d")


def _gzip_mtime(path: Path) -> str | None:
    """The modification time stored in a gzip header (0 = not stored), as a date."""
    try:
        with open(path, "rb") as fh:
            head = fh.read(10)
    except OSError:
        return None
    if len(head) < 10 or head[:2] != b"\x1f\x8b":
        return None
    (mtime,) = struct.unpack("<I", head[4:8])
    if mtime == 0:
        return None
    return dt.datetime.fromtimestamp(mtime, dt.UTC).strftime("%Y-%m-%d")


def _tdms_date(path: Path) -> str | None:
    """The newest datetime property (e.g. wf_start_time) in a TDMS file's metadata."""
    try:
        with nptdms_quiet():  # npTDMS's warnings about a damaged file: no date, no stderr
            meta = TdmsFile.read_metadata(str(path))
        objs = [meta] + list(meta.groups())
        objs += [c for g in meta.groups() for c in g.channels()]
    except Exception:  # noqa: BLE001 - a date is optional; a damaged file just has none
        return None
    dates = []
    for obj in objs:
        for value in getattr(obj, "properties", {}).values():
            if isinstance(value, np.datetime64 | dt.datetime):
                iso = _iso(value)
                if iso and iso > "1904-01-01":
                    dates.append(iso)
    return max(dates) if dates else None


def date_from_inputs(day: DayResult) -> str | None:
    """The newest date recorded in the inputs themselves, or None.

    Looked for, in this order: a ``date`` or ``test_date`` column of the run sheet; the
    timestamps stored inside the run files (the gzip header of .csv.gz files, datetime
    properties of TDMS files). File-system times are never used: they change with a copy.
    """
    sheet = day.sheet
    for col in ("test_date", "date"):
        if col in sheet.columns:
            dates = [d for d in (_iso(v) for v in sheet[col]) if d]
            if dates:
                return max(dates)
    data_dir = day.protocol.campaign.data_dir
    dates = []
    for red in day.reductions.values():
        path = data_dir / red.file
        name = path.name.lower()
        if name.endswith(".gz"):
            d = _gzip_mtime(path)
        elif name.endswith(".tdms"):
            d = _tdms_date(path)
        else:
            d = None
        if d:
            dates.append(d)
    return max(dates) if dates else None


def report_date(day: DayResult) -> tuple[str | None, str]:
    """The test date printed in the report and where it comes from.

    ``day.report_date`` (the command line's --date), then the protocol's [report] date or
    [campaign] test_date, then :func:`date_from_inputs`; (None, "not given") otherwise.
    """
    if day.report_date:
        return str(day.report_date), "given on the command line"
    p = day.protocol
    report = getattr(p, "report", None)
    if report is not None and getattr(report, "date", None):
        return str(report.date), "protocol [report] date"
    if getattr(p.campaign, "test_date", None):
        return str(p.campaign.test_date), "protocol [campaign] test_date"
    found = date_from_inputs(day)
    if found:
        return found, "newest date recorded in the run sheet or run files"
    return None, "not given"


def creation_date(date: str | None) -> dt.datetime | None:
    """The PDF's CreationDate: midnight UTC of the report date (None if there is none)."""
    iso = _iso(date) if date else None
    if iso is None:
        return None
    return dt.datetime.strptime(iso, "%Y-%m-%d").replace(tzinfo=dt.UTC)


def captive_provenance(day: DayResult) -> dict[str, Any]:
    """The options a captive day was reduced with, as ITTC 7.5-02-06-02 asks them stated: the
    moment reference, the rigid-body terms removed (mass, inertia, x_G), the PMM cycles kept
    of each run, the vertical plane's roll, where static means came from and how the fit
    weighted its rows."""
    p = day.protocol
    assert p.model is not None
    m, options = p.model, p.captive
    pmm = day.pmm
    tol = options.amplitude_tolerance if options is not None else 0.05
    min_cycles = options.min_cycles if options is not None else 3
    reference = options.moment_ref if options is not None else "origin"
    return {
        "moment_reference": reference,
        "moment_transfer": ("N_O = mz + balance_x_m * fy" if reference == "origin" else
                            "none: N = mz about the balance point, the velocities and x_G "
                            "taken there (v_B = v + balance_x_m * r, x_G - balance_x_m)"),
        "balance_x_m": m.balance_x_m,
        "inertia_removed": {"mass_kg": m.mass_kg, "izz_kg_m2": m.izz_kg_m2,
                            "iyy_kg_m2": m.iyy_kg_m2, "xg_m": m.xg_m},
        "pmm_cycles_used": {str(int(r)): int(c) for r, c in zip(pmm["run"], pmm["cycles_used"],
                                                                strict=True)},
        "pmm_cycle_rule": (
            f"whole cycles inside the steady window whose sway amplitude is within "
            f"{100 * tol:g} % of the full cycles' median (ramp-in and ramp-out cycles "
            f"dropped); at least {min_cycles} kept cycles; measured frequency and amplitude "
            f"within {100 * tol:g} % of the sheet's"),
        "roll_deg_vertical": options.roll_deg if options is not None else 90.0,
        "means": str(options.means) if options is not None and options.means else "",
        "means_prime": bool(options.means_prime) if options is not None else False,
        "fit": {c.plane: {"weights": "1/var(load - regressors x derivatives) of each run's "
                                     "component, from its covariance over the PMM cycles or "
                                     "the steady window's blocks (the zero's variance "
                                     "included); the intervals widened by the reduced chi^2 "
                                     "when the model is rejected (p < 0.01)",
                          "reduced_chi2": dict(c.chi2_reduced)}
                for c in day.captive_results},
    }
