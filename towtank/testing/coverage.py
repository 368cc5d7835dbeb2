"""Coverage study: generated days under one signal condition, processed, against their truth.

For each condition (sample rate, mains hum, vibration in the filter's passband, 4× noise, long
runs, ...) and seed a synthetic SUT-2 day is written, processed in-process and compared with
its truth: whether each coefficient is present, its relative error, and whether its 95 %
interval holds the truth. :func:`summarise` gives the coverage per coefficient with its
Clopper–Pearson 95 % interval. ``scripts/coverage_study.py`` runs it from the command line.
"""

from __future__ import annotations

import dataclasses
import math
import shutil
import tempfile
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from scipy.stats import beta

from towtank.pipeline import process_day
from towtank.testing.days import (
    hull_day_plan,
    hull_protocol_sections,
    make_hull_day,
    write_protocol,
)
from towtank.testing.instruments import Noise

#: The coefficients whose intervals the study checks.
SYMBOLS = ("X_udot", "Y_vdot", "X_u|u|", "X_uv", "X_v|v|", "Y_v|v|")


def _long_plan() -> list[Any]:
    """The day's plan with every plateau 1200 s long (a long run: ramps < 0.5 % of it)."""
    return [dataclasses.replace(spec, plateau_s=1200.0) if spec.status != "void" else spec
            for spec in hull_day_plan()]


def _two_level_plan() -> list[Any]:
    """The day's plan with its transverse tows at two accelerations instead of three: the
    steady tows ramp at 0.2 m/s² like the second accelerated tow (Y_vdot from two levels)."""
    return [dataclasses.replace(spec, accel=0.2)
            if spec.angle_deg == 90.0 and spec.test != "accel" else spec
            for spec in hull_day_plan()]


def _noise(**kw: Any) -> Noise:
    return dataclasses.replace(Noise(), **kw)


_BASE = Noise()
#: name -> keyword arguments of :func:`towtank.testing.days.make_hull_day`.
CONDITIONS: dict[str, dict[str, Any]] = {
    "200hz": {"fs": 200.0},
    "1khz": {"fs": 1000.0},
    "100hz": {"fs": 100.0},
    "50hz": {"fs": 50.0},
    "hum_50hz": {"fs": 200.0, "noise": _noise(hum_amplitude=0.05)},
    "vibration_2.5hz": {"fs": 200.0, "noise": _noise(vibration_hz=(2.5, 2.5),
                                                     vibration_per_speed=0.005)},
    "noise_4x": {"fs": 200.0, "noise": _noise(balance_sigma=4 * _BASE.balance_sigma,
                                              speed_sigma=4 * _BASE.speed_sigma)},
    "long_runs": {"fs": 50.0, "runs": "long", "tank_length_m": 5000.0},
    "two_levels": {"fs": 200.0, "runs": "two_levels"},
}


#: Coefficients of the form X = m − M, which carry the weighing error of m one-for-one.
ADDED_MASSES = ("X_udot", "Y_vdot", "Z_wdot")

#: Largest |relative error| of each coefficient's fit (weighing error taken out) on a day of
#: the generator, the tolerances of tests/test_fit.py.
TOLERANCE = {"X_udot": 0.05, "Y_vdot": 0.02, "X_u|u|": 0.01, "Y_uv": 0.01, "Y_v|v|": 0.015,
             "X_uv": 0.20, "X_v|v|": 0.35}

#: Conditions whose errors scale with a larger noise: the tolerances grow with it.
NOISE_FACTOR = {"noise_4x": 4.0}


def tolerance(condition: str, symbol: str) -> float:
    """The largest |relative error| allowed for ``symbol`` on a day of ``condition``."""
    return TOLERANCE[symbol] * NOISE_FACTOR.get(condition, 1.0)


def weighed_mass(model: dict[str, Any], seed: int) -> float:
    """The model's mass as the lab weighs it: the true mass plus a weighing error drawn with
    the protocol's ``mass_uncertainty_kg`` (default 0.5 g) as its standard deviation [kg].

    The added masses' intervals include that uncertainty (docs/method.md); a study that gave the
    fit the exact mass would find them too wide (X_udot's 2.3× its errors at 0.5 g).
    """
    sigma = float(model.get("mass_uncertainty_kg", 0.0005))
    rng = np.random.default_rng([seed, 0x3A55])
    return round(float(model["mass_kg"]) + sigma * float(rng.standard_normal()), 7)


def day_result(condition: str, seed: int, workdir: Path | None = None) -> list[dict[str, Any]]:
    """One generated day under ``condition``: a row per symbol (present, value, interval,
    truth, relative error, inside)."""
    kw = dict(CONDITIONS[condition])
    if kw.get("runs") == "long":
        kw["runs"] = _long_plan()
    elif kw.get("runs") == "two_levels":
        kw["runs"] = _two_level_plan()
    tmp = Path(tempfile.mkdtemp(prefix=f"cov_{condition}_", dir=workdir))
    try:
        # float64 TDMS: the channels are rounded before they are written, so the reader gets
        # exactly the numbers of a CSV day (the same rows to the last bit) without the decimal
        # text, which costs most of a long or 1 kHz day
        truth = make_hull_day(tmp, seed=seed, file_format="tdms", sheet_format="csv", **kw)
        sections: dict[str, Any] = hull_protocol_sections(".", "out", sheet_format="csv")
        true_mass = float(sections["model"]["mass_kg"])
        sections["model"]["mass_kg"] = weighed_mass(sections["model"], seed)
        weighing_error = sections["model"]["mass_kg"] - true_mass
        protocol = write_protocol(tmp / "p.toml", **sections)
        day = process_day(protocol, jobs=1)
        coef = (day.hull.coefficients.set_index("symbol") if day.hull is not None
                else pd.DataFrame())
        rows = []
        for sym in SYMBOLS:
            t = float((truth.coefficients or {})[sym])
            present = sym in coef.index
            v = float(coef.loc[sym, "value"]) if present else math.nan
            lo = float(coef.loc[sym, "ci_low"]) if present else math.nan
            hi = float(coef.loc[sym, "ci_high"]) if present else math.nan
            rows.append({"condition": condition, "seed": seed, "symbol": sym,
                         "present": present, "value": v, "ci_low": lo, "ci_high": hi,
                         "truth": t, "rel_error": (v - t) / abs(t),
                         # the fit's own error: an added mass X = m − M carries the weighing
                         # error of m one-for-one, which the study knows and takes out here
                         "fit_rel_error": (v - (weighing_error if sym in ADDED_MASSES else 0.0)
                                           - t) / abs(t),
                         "inside": bool(present and lo <= t <= hi),
                         "rejected": len(day.rejected)})
        return rows
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def clopper_pearson(k: int, n: int, level: float = 0.95) -> tuple[float, float]:
    """Exact binomial interval for k successes in n trials (Clopper & Pearson 1934)."""
    a = 1.0 - level
    lo = 0.0 if k == 0 else float(beta.ppf(a / 2, k, n - k + 1))
    hi = 1.0 if k == n else float(beta.ppf(1 - a / 2, k + 1, n - k))
    return lo, hi


def summarise(rows: Iterable[dict[str, Any]]) -> pd.DataFrame:
    """Per condition and symbol: days, present, coverage with its Clopper–Pearson interval,
    median and largest |relative error|."""
    df = pd.DataFrame(list(rows))
    out = []
    for (cond, sym), g in df.groupby(["condition", "symbol"], sort=False):
        n = len(g)
        k = int(g["inside"].sum())
        lo, hi = clopper_pearson(k, n)
        err = g["rel_error"].abs()
        fit_err = g["fit_rel_error"].abs() if "fit_rel_error" in g else err
        out.append({"condition": cond, "symbol": sym, "days": n,
                    "present": int(g["present"].sum()), "coverage": k / n,
                    "cp_low": lo, "cp_high": hi, "median_abs_err": float(err.median()),
                    "max_abs_err": float(err.max()),
                    "max_fit_err": float(fit_err.max())})
    return pd.DataFrame(out)
