"""Generated captive manoeuvring days with known truth: static drift, rudder, rotating arm,
pure sway, pure yaw and yaw with drift (FORMATS section 8).

The balance readings are made by inverting the reduction's equations: the hydrodynamic loads
of the truth (:data:`towtank.reduce.captive.REGRESSORS` times the derivatives) less the
model's inertia, the moment moved from O to the balance point; then the instruments of the
hull days (:mod:`towtank.testing.instruments`: zero offset, linear drift, noise, vibration,
mains hum). :func:`simulate_captive_run` gives one run's channels as arrays,
:func:`make_captive_day` a whole day on disk (protocol, run sheet, run files).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import pandas as pd

from towtank.analysis.captive import fit_captive
from towtank.ingest.schema import Processing
from towtank.reduce.captive import (
    PMM_TESTS,
    REGRESSORS,
    VERTICAL_REGRESSORS,
    body_kinematics,
    condition_captive,
    kinematics_at,
    reduce_captive,
    reference_x,
    regressors,
)
from towtank.reduce.run import find_phases
from towtank.reference.sets import reference_table
from towtank.results.stages import CaptiveResult
from towtank.results.summary import from_fit
from towtank.signal import conditioning
from towtank.testing.days import write_protocol, write_run_sheet, write_truth
from towtank.testing.instruments import Noise, draw_imperfections, recorded_channels
from towtank.testing.layouts import write_layout
from towtank.testing.numbertext import csv_text
from towtank.testing.profiles import plan_profile, sample_times

#: Horizontal symbols of the 14 derivatives of FORMATS section 8 and their vertical twins.
HORIZONTAL_SYMBOLS = tuple(f"{eq}_{k}" for k in REGRESSORS[:-1] for eq in ("Y", "N"))
VERTICAL_SYMBOLS = tuple(f"{eq}_{k}" for k in VERTICAL_REGRESSORS[:-1] for eq in ("Z", "M"))


def remus_derivatives(plane: str = "horizontal") -> dict[str, float]:
    """Prestero's (2001) REMUS values [SI] of the 14 derivatives of ``plane`` (lumped: what
    captive tests measure), from towtank/reference/data/remus_prestero2001.csv."""
    table = reference_table("remus-prestero2001")
    values = dict(zip(table["symbol"], table["value"].astype(float), strict=True))
    symbols = HORIZONTAL_SYMBOLS if plane == "horizontal" else VERTICAL_SYMBOLS
    return {s: values[s] for s in symbols}


@dataclass(frozen=True)
class CaptiveTruth:
    """The truth of a generated captive day.

    ``derivatives``: symbol -> value [SI] of the plane's model (Y_*, N_* or Z_*, M_*; the
    offsets Y_uu, N_uu / Z_uu, M_uu too). ``frequency_slope``: symbol -> d value / d omega' of
    a derivative that depends on the PMM frequency (value at omega' = value + slope (omega' -
    1)); X = X_u|u| u|u| + X_vv v^2 + X_rr r^2 [N] for fx. ``moment_ref``: the point the
    derivatives refer to, as ``[captive] moment_ref`` names it ("origin": O; "balance": the
    balance point, its velocities and moments).
    """

    derivatives: dict[str, float] = field(default_factory=lambda: {
        **remus_derivatives(), "Y_uu": 0.05, "N_uu": -0.02})
    mass_kg: float = 30.5
    izz_kg_m2: float = 3.45
    iyy_kg_m2: float = 3.45
    xg_m: float = 0.0
    balance_x_m: float = 0.05
    length_m: float = 1.33
    X_uu: float = -1.62
    X_vv: float = -20.0
    X_rr: float = -1.0
    roll_deg: float = 90.0
    frequency_slope: dict[str, float] = field(default_factory=dict)
    moment_ref: str = "origin"

    @classmethod
    def vertical(cls, **kw: Any) -> CaptiveTruth:
        """REMUS's vertical-plane derivatives (with offsets Z_uu, M_uu)."""
        return cls(derivatives={**remus_derivatives("vertical"), "Z_uu": 0.05,
                                "M_uu": -0.02}, **kw)

    @property
    def plane(self) -> str:
        """"horizontal" or "vertical", from the derivatives' symbols."""
        return "vertical" if any(s[0] in "ZM" for s in self.derivatives) else "horizontal"


@dataclass(frozen=True)
class CaptiveRunSpec:
    """One planned captive run: ``test`` and the sheet's values (angles [deg], radius [m],
    PMM amplitude [m] and frequency [Hz]); PMM runs have ``ramp_cycles`` of ramp-in and
    ramp-out around ``steady_cycles``."""

    run: int
    test: str
    speed: float = 1.5
    drift_deg: float = 0.0
    rudder_deg: float = 0.0
    radius_m: float = math.nan
    amplitude_m: float = math.nan
    frequency_hz: float = math.nan
    steady_cycles: int = 5
    ramp_cycles: int = 1

    def sheet_row(self) -> dict[str, Any]:
        """The run-sheet values of the run (NaN where not set)."""
        return {"test": self.test, "drift_deg": self.drift_deg, "rudder_deg": self.rudder_deg,
                "radius_m": self.radius_m, "pmm_amplitude_m": self.amplitude_m,
                "pmm_frequency_hz": self.frequency_hz}


def captive_day_plan(speed: float = 1.5) -> list[CaptiveRunSpec]:
    """A manoeuvring programme of 36 runs: static drift (±2 … ±12 deg), rudder (±10, ±20 deg
    straight, ±10 deg at 4 deg drift), rotating arm (R = ±2 … ±10 m, two with drift), pure
    sway and pure yaw (two amplitudes, two frequencies each) and yaw with drift."""
    specs: list[dict[str, Any]] = []
    specs += [{"test": "drift", "drift_deg": b} for b in (-12, -8, -4, -2, 0, 2, 4, 8, 12)]
    specs += [{"test": "rudder", "rudder_deg": d} for d in (-20, -10, 10, 20)]
    specs += [{"test": "rudder", "rudder_deg": d, "drift_deg": 4} for d in (-10, 10)]
    specs += [{"test": "arm", "radius_m": r} for r in (-10, -5, -3, -2, 2, 3, 5, 10)]
    specs += [{"test": "arm", "radius_m": 4, "drift_deg": b} for b in (-4, 4)]
    for test in ("sway", "yaw"):
        specs += [{"test": test, "amplitude_m": a, "frequency_hz": f}
                  for a in (0.1, 0.2) for f in (0.2, 0.35)]
    specs += [{"test": "yaw_drift", "amplitude_m": 0.15, "frequency_hz": 0.25, "drift_deg": b}
              for b in (-4, 4)]
    specs += [{"test": "sway", "amplitude_m": 0.3, "frequency_hz": 0.3}]
    return [CaptiveRunSpec(run=i + 1, speed=speed, **s) for i, s in enumerate(specs)]


# ================================================================================ the motion

def _ramp(t: np.ndarray, a: float, b: float, c: float, d: float
          ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Envelope 0 before a, raised-cosine up to 1 at b, 1 until c, down to 0 at d; with its
    first, second and third time derivatives."""
    e, e1, e2, e3 = (np.zeros_like(t) for _ in range(4))
    for lo, hi, sign in ((a, b, 1.0), (c, d, -1.0)):
        m = (t >= lo) & (t < hi)
        k = math.pi / (hi - lo)
        x = k * (t[m] - lo)
        e[m] = 0.5 * (1.0 - sign * np.cos(x))
        e1[m] = sign * 0.5 * k * np.sin(x)
        e2[m] = sign * 0.5 * k**2 * np.cos(x)
        e3[m] = -sign * 0.5 * k**3 * np.sin(x)
    e[(t >= b) & (t < c)] = 1.0
    return e, e1, e2, e3


def pmm_motion(t: np.ndarray, spec: CaptiveRunSpec, t0: float, speed: float
               ) -> dict[str, np.ndarray]:
    """The PMM's sway y [m] of O and yaw psi_p [rad] (with y', y'', psi', psi''), starting at
    ``t0`` [s]: y = y0 e(t) sin(omega (t - t0)) with ramp-in and ramp-out envelopes e; pure
    yaw and yaw with drift turn the model with its path, psi_p = atan(y'/U) (v = 0 at O)."""
    w = 2.0 * math.pi * spec.frequency_hz
    T = 1.0 / spec.frequency_hz
    nr, ns = spec.ramp_cycles, spec.steady_cycles
    e, e1, e2, e3 = _ramp(t, t0, t0 + nr * T, t0 + (nr + ns) * T, t0 + (2 * nr + ns) * T)
    s, c = np.sin(w * (t - t0)), np.cos(w * (t - t0))
    y0 = spec.amplitude_m
    y = y0 * e * s
    y1 = y0 * (e1 * s + w * e * c)
    y2 = y0 * (e2 * s + 2.0 * w * e1 * c - w * w * e * s)
    if spec.test == "sway":
        z = np.zeros_like(t)
        return {"y": y, "y1": y1, "y2": y2, "psi": z, "psi1": z, "psi2": z}
    y3 = y0 * (e3 * s + 3.0 * w * e2 * c - 3.0 * w**2 * e1 * s - w**3 * e * c)
    # psi = atan(a), a = y'/U: psi' = a'/(1 + a^2), psi'' = a''/(1 + a^2) - 2 a a'^2/(1 + a^2)^2
    a, a1, a2 = y1 / speed, y2 / speed, y3 / speed
    q = 1.0 + a * a
    return {"y": y, "y1": y1, "y2": y2, "psi": np.arctan(a), "psi1": a1 / q,
            "psi2": a2 / q - 2.0 * a * a1**2 / q**2}


# ================================================================================ the loads

def truth_loads(kin: Mapping[str, np.ndarray], truth: CaptiveTruth, rudder: float,
                omega_prime: float = math.nan) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Hydrodynamic X, Y [N] and N [N m] of the truth, rig axes, for ``rudder`` [rad], from
    ``kin`` of the point the truth refers to (``truth.moment_ref``) and about it (a vertical
    truth: w = -s v, q = s r, Z = -s Y, M = s N with s = sign(roll_deg))."""
    reg = regressors(kin, rudder)
    d = truth.derivatives

    def value(symbol: str) -> float:
        slope = truth.frequency_slope.get(symbol, 0.0)
        extra = slope * (omega_prime - 1.0) if math.isfinite(omega_prime) else 0.0
        return d.get(symbol, 0.0) + extra

    u, v, r = kin["u"], kin["v"], kin["r"]
    X = truth.X_uu * u * np.abs(u) + truth.X_vv * v**2 + truth.X_rr * r**2
    if truth.plane == "horizontal":
        Y = sum(value(f"Y_{k}") * reg[k] for k in REGRESSORS)
        N = sum(value(f"N_{k}") * reg[k] for k in REGRESSORS)
        return X, np.asarray(Y), np.asarray(N)
    s = math.copysign(1.0, truth.roll_deg)
    sign = {"uv": -s, "v|v|": -s, "ur": s, "r|r|": s, "vdot": -s, "rdot": s, "uudr": 1.0,
            "uu": 1.0}  # vertical regressor = sign * horizontal one
    Z = sum(value(f"Z_{kv}") * sign[k] * reg[k] for k, kv in zip(REGRESSORS,
                                                                 VERTICAL_REGRESSORS, strict=True))
    M = sum(value(f"M_{kv}") * sign[k] * reg[k] for k, kv in zip(REGRESSORS,
                                                                 VERTICAL_REGRESSORS, strict=True))
    return X, -s * np.asarray(Z), s * np.asarray(M)


def balance_readings(X: np.ndarray, Y: np.ndarray, N: np.ndarray,
                     kin: Mapping[str, np.ndarray], truth: CaptiveTruth
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """fx, fy [N], mz [N m] about the balance point: the inverse of
    :func:`towtank.reduce.captive.hydrodynamic_loads`, with X, Y, N, ``kin`` and the model's
    x_G and x_B taken at the point P the truth refers to (``truth.moment_ref``)."""
    u, v, r = kin["u"], kin["v"], kin["r"]
    ud, vd, rd = kin["udot"], kin["vdot"], kin["rdot"]
    ref = reference_x(truth.moment_ref, truth.balance_x_m)
    m, xg, xb = truth.mass_kg, truth.xg_m - ref, truth.balance_x_m - ref
    inertia = truth.izz_kg_m2 if truth.plane == "horizontal" else truth.iyy_kg_m2
    fx = X - m * (ud - v * r - xg * r**2)
    fy = Y - m * (vd + u * r + xg * rd)
    mz = N - xb * fy - (inertia + m * xg**2) * rd - m * xg * (vd + u * r)
    return fx, fy, mz


#: Steady carriage time around the PMM motion [s] (the window's trim and the filter's settling).
PMM_MARGIN_S = 1.5
SWAY_SIGMA_M = 2e-4
YAW_SIGMA_DEG = 0.02


def simulate_captive_run(
    spec: CaptiveRunSpec, truth: CaptiveTruth, *, noise: Noise | None = None,
    fs: float = 100.0, rng: np.random.Generator | int | None = None, accel: float = 0.5,
) -> pd.DataFrame:
    """One captive run's recorded channels: time [s], speed [m/s], fx, fy [N], mz [N m] and,
    for PMM runs, sway [m] and yaw [deg].

    The carriage runs a jerk-limited profile (:func:`towtank.testing.profiles.plan_profile`)
    whose plateau holds the PMM motion with :data:`PMM_MARGIN_S` either side.
    """
    rng = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng or 0)
    noise = Noise() if noise is None else noise
    pmm = spec.test in PMM_TESTS
    plateau = ((2 * spec.ramp_cycles + spec.steady_cycles) / spec.frequency_hz
               + 2 * PMM_MARGIN_S) if pmm else 8.0
    plan = plan_profile(spec.speed, accel, plateau_s=plateau, tank_length_m=1e4)
    t = sample_times(plan.duration, fs)
    U, a = plan.evaluate(t)
    beta, delta = math.radians(spec.drift_deg), math.radians(spec.rudder_deg)
    omega_prime = math.nan
    if pmm:
        mo = pmm_motion(t, spec, plan.t_plateau_start + PMM_MARGIN_S, spec.speed)
        kin = body_kinematics(U, beta + mo["psi"], psi_dot=mo["psi1"], psi_ddot=mo["psi2"],
                              y_dot=mo["y1"], y_ddot=mo["y2"], speed_dot=a)
        omega_prime = 2.0 * math.pi * spec.frequency_hz * truth.length_m / spec.speed
    elif spec.test == "arm":
        kin = {"u": U * math.cos(beta), "v": -U * math.sin(beta), "r": U / spec.radius_m,
               "udot": a * math.cos(beta), "vdot": -a * math.sin(beta),
               "rdot": a / spec.radius_m}
    else:
        kin = body_kinematics(U, beta, speed_dot=a)
    kin = kinematics_at(kin, reference_x(truth.moment_ref, truth.balance_x_m))
    X, Y, N = truth_loads(kin, truth, delta, omega_prime)
    fx, fy, mz = balance_readings(X, Y, N, kin, truth)
    first = recorded_channels(t, U, a, fx, fy, noise, draw_imperfections(noise, t.size, rng,
                                                                        False), fs)
    second = recorded_channels(t, U, a, mz, np.zeros_like(t), noise,
                               draw_imperfections(noise, t.size, rng, False), fs)
    out = {"time": t, "speed": first["speed"].to_numpy(), "fx": first["drag"].to_numpy(),
           "fy": first["lift"].to_numpy(), "mz": second["drag"].to_numpy()}
    if pmm:
        quiet = noise.balance_sigma == 0.0
        out["sway"] = mo["y"] + (0.0 if quiet else SWAY_SIGMA_M) * rng.standard_normal(t.size)
        out["yaw"] = np.degrees(mo["psi"]) + (0.0 if quiet else YAW_SIGMA_DEG) * (
            rng.standard_normal(t.size))
    return pd.DataFrame(out)


# ================================================================================== the day

#: Units of the run files' channels.
CHANNEL_UNITS = {"time": "s", "speed": "m/s", "fx": "N", "fy": "N", "mz": "N m", "sway": "m",
                 "yaw": "deg"}
#: Layouts of the generated run files: CSV with a units row, LabVIEW LVM, TDMS waveforms.
CAPTIVE_LAYOUTS = {"csv-units": "csv", "lvm": "lvm", "tdms-waveform": "tdms"}
SHEET_COLUMNS = ("run", "file", "config", "test", "plane", "angle_deg", "speed_nominal",
                 "accel_nominal", "tare_group", "status", "drift_deg", "rudder_deg", "radius_m",
                 "pmm_amplitude_m", "pmm_frequency_hz")


def write_captive_file(frame: pd.DataFrame, path: Path, layout: str) -> Path:
    """A run file in ``layout`` (:data:`CAPTIVE_LAYOUTS`): "csv-units" writes a header row, a
    units row and the data; the others go through :func:`towtank.testing.layouts.write_layout`."""
    units = {c: CHANNEL_UNITS[c] for c in frame.columns}
    if layout == "csv-units":
        head = ",".join(frame.columns) + "\n" + ",".join(units[c] for c in frame.columns) + "\n"
        body = csv_text(frame, header=False, float_format="%.7g")
        path.write_text(head + body, encoding="utf-8")
        return path
    return write_layout(layout, frame, path, "time", units)


def make_captive_day(
    folder: str | Path, *, truth: CaptiveTruth | None = None, seed: int = 0,
    layout: str = "csv-units", plane: str = "horizontal",
    plan: Sequence[CaptiveRunSpec] | None = None, noise: Noise | None = None,
    fs: float = 100.0,
) -> dict[str, Any]:
    """Write a captive day: ``protocol.toml``, ``run_sheet.csv`` and ``data/run_NNN.*``.

    Parameters
    ----------
    folder : str or Path
        Where the day goes (made if missing).
    truth : CaptiveTruth, optional
        Default REMUS (:class:`CaptiveTruth`, or :meth:`CaptiveTruth.vertical` for
        ``plane = "vertical"``).
    seed : int
        Seed of every random draw.
    layout : str
        "csv-units", "lvm" or "tdms-waveform".
    plane : {"horizontal", "vertical"}
        A vertical day has the model rolled by ``truth.roll_deg`` on the same rig.
    plan : sequence of CaptiveRunSpec, optional
        Default :func:`captive_day_plan`.
    noise : Noise, optional
        Default ``Noise()``.
    fs : float
        Sample rate [Hz].

    Returns
    -------
    dict
        The truth: ``derivatives``, the model's particulars and each run's spec (also
        written to ``truth.json``; a setting a run does not use is None).
    """
    if layout not in CAPTIVE_LAYOUTS:
        raise ValueError(f"layout must be one of {', '.join(CAPTIVE_LAYOUTS)}, not {layout!r}")
    if truth is None:
        truth = CaptiveTruth.vertical() if plane == "vertical" else CaptiveTruth()
    if truth.plane != plane:
        raise ValueError(f"the truth's derivatives are of the {truth.plane} plane, not {plane}")
    folder = Path(folder)
    (folder / "data").mkdir(parents=True, exist_ok=True)
    plan = list(plan) if plan is not None else captive_day_plan()
    streams = np.random.SeedSequence(seed).spawn(len(plan))
    rows = []
    for spec, stream in zip(plan, streams, strict=True):
        frame = simulate_captive_run(spec, truth, noise=noise, fs=fs,
                                     rng=np.random.default_rng(stream))
        name = f"run_{spec.run:03d}.{CAPTIVE_LAYOUTS[layout]}"
        write_captive_file(frame, folder / "data" / name, layout)
        rows.append({"run": spec.run, "file": name, "config": "hull", "plane": plane,
                     "angle_deg": spec.drift_deg, "speed_nominal": spec.speed,
                     "accel_nominal": 0.5,
                     "tare_group": "", "status": "ok", **spec.sheet_row()})
    write_run_sheet(rows, folder / "run_sheet.csv", SHEET_COLUMNS)
    model: dict[str, Any] = {
        "name": "REMUS captive model", "length_m": truth.length_m, "diameter_m": 0.191,
        "mass_kg": truth.mass_kg, "izz_kg_m2": truth.izz_kg_m2, "xg_m": truth.xg_m,
        "balance_x_m": truth.balance_x_m}
    if plane == "vertical":
        model["iyy_kg_m2"] = truth.iyy_kg_m2
    captive: dict[str, Any] = {"moment_ref": truth.moment_ref}
    if plane == "vertical":
        captive["roll_deg"] = truth.roll_deg
    write_protocol(
        folder / "protocol.toml", header="A generated captive manoeuvring day (towtank.testing"
        ".captive).",
        campaign={"name": f"captive {plane} seed {seed}", "run_sheet": "run_sheet.csv",
                  "data_dir": "data", "output_dir": "out"},
        water={"type": "fresh", "temperature_C": 18.0}, model=model, captive=captive)
    truth_dict = {"derivatives": dict(truth.derivatives), "plane": plane, "seed": seed,
            "model": model, "runs": [{k: (None if isinstance(v, float) and math.isnan(v) else v)
                                       for k, v in replace(s).__dict__.items()}
                                      for s in plan]}
    write_truth(truth_dict, folder / "truth.json")  # NaN (a setting not used) as null
    return truth_dict


# ====================================================================== in-process reduction

def reduce_simulated(frame: pd.DataFrame, spec: CaptiveRunSpec, truth: CaptiveTruth,
                     *, fs: float = 100.0, moment_ref: str | None = None) -> Any:
    """A simulated run reduced in-process as the day's pipeline does: one low-pass, the phases
    from the speed (:func:`towtank.reduce.run.find_phases`), the zero line between the still
    windows, then :func:`towtank.reduce.captive.reduce_captive` (RunError as the day's), with
    the loads referred to ``moment_ref`` (default: the truth's)."""
    p = Processing()
    t = frame["time"].to_numpy(dtype=float)
    channels = {("U" if k == "speed" else k): frame[k].to_numpy(dtype=float)
                for k in frame.columns if k != "time"}
    speed_f = conditioning.lowpass(channels["U"], fs, p.cutoff_hz, p.filter_order)
    ph = find_phases(t, speed_f, conditioning.derivative(speed_f, fs), fs, p,
                     steady_required=True)
    assert ph.steady is not None and ph.still_pre is not None
    zero_var: dict[str, float] = {}
    cond = condition_captive(t, channels, fs, cutoff_hz=p.cutoff_hz, order=p.filter_order,
                             still=(ph.still_pre, ph.still_post), steady=ph.steady,
                             zero_var=zero_var)
    model = SimpleNamespace(mass_kg=truth.mass_kg, izz_kg_m2=truth.izz_kg_m2,
                            iyy_kg_m2=truth.iyy_kg_m2, xg_m=truth.xg_m,
                            balance_x_m=truth.balance_x_m, length_m=truth.length_m)
    return reduce_captive(cond, fs, ph.steady, {**spec.sheet_row(), "plane": truth.plane},
                          model, run=spec.run, file=f"run_{spec.run:03d}", zero_var=zero_var,
                          moment_ref=truth.moment_ref if moment_ref is None else moment_ref)


def simulated_runs(truth: CaptiveTruth | None = None, *, seed: int = 0,
                   plan: Sequence[CaptiveRunSpec] | None = None, noise: Noise | None = None,
                   fs: float = 100.0, moment_ref: str | None = None) -> list[Any]:
    """A generated captive day's runs, reduced in-process (no files): list of CaptiveRun, the
    loads referred to ``moment_ref`` (default: the truth's)."""
    truth = CaptiveTruth() if truth is None else truth
    plan = list(plan) if plan is not None else captive_day_plan()
    streams = np.random.SeedSequence(seed).spawn(len(plan))
    return [reduce_simulated(simulate_captive_run(spec, truth, noise=noise, fs=fs,
                                                  rng=np.random.default_rng(stream)),
                             spec, truth, fs=fs, moment_ref=moment_ref)
            for spec, stream in zip(plan, streams, strict=True)]


def simulated_result(truth: CaptiveTruth | None = None, *, seed: int = 0,
                     plan: Sequence[CaptiveRunSpec] | None = None,
                     runs: Sequence[Any] | None = None) -> Any:
    """The :class:`towtank.results.stages.CaptiveResult` of a generated day (in-process);
    ``runs``, when given, are that day's :func:`simulated_runs`, made already."""
    truth = CaptiveTruth() if truth is None else truth
    if runs is None:
        runs = simulated_runs(truth, seed=seed, plan=plan)
    fit = fit_captive(list(runs), rho=998.6,
                      length_m=truth.length_m, plane=truth.plane, roll_deg=truth.roll_deg)
    return from_fit(CaptiveResult, fit)
