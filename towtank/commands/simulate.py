"""``towtank simulate``: a manoeuvre of a model.json (turning, zigzag, dive, spiral, glide)."""

from __future__ import annotations

import math
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from towtank.commands.storage import write_outputs_or_stop
from towtank.errors import ProtocolError
from towtank.report.manoeuvre_figure import save_manoeuvre_figure
from towtank.vehicle import schema
from towtank.vehicle.assumptions import guessed, guessed_line
from towtank.vehicle.glider import glide_table
from towtank.vehicle.glider_controls import (
    model_glider_problems,
    roll_mass_angle_for_static_roll_deg,
)
from towtank.vehicle.identify_log import parse_noise
from towtank.vehicle.model import read_model
from towtank.vehicle.simulate import (
    PROPULSION,
    manoeuvre_metrics,
    read_schedule,
    sample_models,
    simulate,
    trim_warning,
)

DEFAULT_RUDDER = {"turning": 15.0, "zigzag": 20.0, "spiral": 15.0, "dive": 0.0, "glide": 0.0,
                  "sine": 10.0, "schedule": 0.0}
DEFAULT_STERN = {"turning": 0.0, "zigzag": 0.0, "spiral": 5.0, "dive": 5.0, "glide": 0.0,
                 "sine": 0.0, "schedule": 0.0}


#: The files ``simulate`` writes.
SIMULATE_OUTPUTS = frozenset({"manoeuvre.csv", "metrics.csv", "manoeuvre.png", "glide_table.csv"})

#: The control derivatives each manoeuvre steers with (rudder, sternplanes).
_CONTROLS = {"rudder": ("Y_uudr", "N_uudr"), "sternplane": ("Z_uuds", "M_uuds")}


def _check_controls(model: dict, manoeuvre: str, rudder: float, stern: float,
                    name: str) -> None:
    """A manoeuvre that deflects a control surface the model does not have (its derivatives
    0 or missing: no [[vehicle.fins]] of that plane) would sail straight on: refused."""
    coef = model.get("coefficients", {}) or {}
    needs = []
    if manoeuvre in ("turning", "zigzag", "spiral", "glide", "sine") and rudder:
        needs.append("rudder")
    if manoeuvre == "dive" and stern:
        needs.append("sternplane")
    for plane in needs:
        symbols = _CONTROLS[plane]
        if not any(abs(float(coef.get(s) or 0.0)) > 0 for s in symbols):
            raise ProtocolError(
                f"{name}: the model has no {plane} ({' and '.join(symbols)} are 0 or missing), "
                f"so a {manoeuvre} manoeuvre would run straight on; describe the {plane} "
                f"fins in the protocol's [[vehicle.fins]] (plane = \"{plane}\") and run "
                "predict or process again.")


def _check_dive_angle(model: dict | None, manoeuvre: str, angle: float | None) -> list[str]:
    """--dive-angle-deg: a dive only, finite and within +-80 deg; the model's optional
    ``fin_limit_deg`` more than 0 and at most 45 deg."""
    problems = []
    if angle is not None:
        if manoeuvre != "dive":
            problems.append(f"--dive-angle-deg is for --manoeuvre dive, not {manoeuvre}.")
        elif not (math.isfinite(angle) and abs(angle) <= 80.0):
            problems.append(f"--dive-angle-deg must be within +-80 deg, not {angle:g}.")
    limit = None if model is None else model.get("fin_limit_deg")
    if limit is not None and not (isinstance(limit, (int, float)) and not isinstance(limit, bool)
                                  and 0 < limit <= 45):
        problems.append(f"model.json: 'fin_limit_deg' must be a number more than 0 and at "
                        f"most 45 deg, not {limit!r}.")
    return problems


def _check_roll(model: dict | None, manoeuvre: str, roll: float | None, name: str) -> list[str]:
    """The model's ``glider`` block, when it has one (its wings enter every simulation), and
    --roll-deg: a glide only, finite, within +-80 deg, and a model with a roll mass that can
    give that roll at rest."""
    glider = None if model is None else model.get("glider")
    if model is not None and glider is not None:  # its wings enter every simulation
        problems = model_glider_problems(model, name)
        if problems:
            return problems
    if roll is None:
        return []
    if manoeuvre != "glide":
        return [f"--roll-deg is for --manoeuvre glide, not {manoeuvre}."]
    if not (math.isfinite(roll) and abs(roll) <= 80.0):
        return [f"--roll-deg must be within +-80 deg, not {roll:g}."]
    if model is None or not roll:
        return []
    if glider is None:
        return [f"{name}: --roll-deg needs the model's roll mass, but it has no 'glider' block "
                "([vehicle.glider] with roll_mass_kg and roll_mass_radius_m)."]
    try:
        roll_mass_angle_for_static_roll_deg(model, roll)
    except ValueError as exc:
        return [f"{name}: --roll-deg {roll:g}: {exc}"]
    return []


def simulate_command(
    model_path: Path, manoeuvre: str, *, rudder_deg: float | None = None,
    sternplane_deg: float | None = None, speed: float | None = None,
    net_buoyancy_n: float | None = None, out: Path | None = None, samples: int = 0,
    duration_s: float | None = None, seed: int = 1, dive_angle_deg: float | None = None,
    roll_deg: float | None = None,
    period_s: float | None = None, schedule: Path | None = None, noise: str | None = None,
    sample_hz: float | None = None, propeller: str = "thrust",
) -> int:
    """Simulate, write manoeuvre.csv, metrics.csv and manoeuvre.png; print the metrics.

    With ``samples`` > 0 the measured coefficients are drawn ``samples`` times from their
    covariance and metrics.csv gains ci_low, ci_high (2.5 and 97.5 percentiles).
    ``propeller`` "rps" drives a powered manoeuvre by the model's propeller at a constant rate
    instead of a constant thrust (:func:`towtank.vehicle.simulate.propulsion`).
    """
    name = Path(model_path).name
    problems: list[str] = []
    model = None
    try:
        model = read_model(model_path)
    except schema.ModelError as exc:  # the options are checked too: every problem at once
        problems += exc.problems
    rudder = DEFAULT_RUDDER[manoeuvre] if rudder_deg is None else rudder_deg
    stern = DEFAULT_STERN[manoeuvre] if sternplane_deg is None else sternplane_deg
    u = speed if speed is not None else (
        float(model.get("design_speed_m_s", 1.5)) if model is not None else 1.5)
    problems += schema.check_simulation(
        model, manoeuvre, speed_m_s=u, rudder_deg=rudder, sternplane_deg=stern,
        duration_s=duration_s, net_buoyancy_n=net_buoyancy_n, samples=samples, name=name)
    problems += _check_dive_angle(model, manoeuvre, dive_angle_deg)
    problems += _check_roll(model, manoeuvre, roll_deg, name)
    problems += _check_propeller(model, manoeuvre, propeller, name)
    table, noise_sd, more = _check_new_inputs(manoeuvre, period_s, schedule, noise, sample_hz)
    problems += more
    if table is not None and duration_s is None:
        duration_s = float(table["t_s"].iloc[-1])
    if problems:
        raise ProtocolError(schema.joined(problems))
    assert model is not None  # read_model raised, and so problems stopped us, otherwise
    if manoeuvre == "glide" and net_buoyancy_n is None:
        net_buoyancy_n = float(model["buoyancy_N"]) - float(model["weight_N"])
    _check_controls(model, manoeuvre, rudder, stern, name)
    for said in schema.sign_warnings(model.get("coefficients") or {}):
        print(f"warning: {name}: {said}", file=sys.stderr)
    upright = schema.stability_warning(model.get("cg_m"), model.get("cb_m"), name)
    if upright:
        print(f"warning: {upright}", file=sys.stderr)
    if manoeuvre != "glide":  # a glide is out of trim on purpose
        warning = trim_warning(model, u, net_buoyancy_n)
        if warning:
            print(f"warning: {warning}", file=sys.stderr)
    kwargs: dict[str, Any] = dict(speed_m_s=u, rudder_deg=rudder, sternplane_deg=stern,
                                  net_buoyancy_n=net_buoyancy_n, duration_s=duration_s,
                                  dive_angle_deg=dive_angle_deg, roll_deg=roll_deg,
                                  propeller=propeller)
    if manoeuvre in ("sine", "schedule") or sample_hz is not None:
        kwargs.update(period_s=period_s, schedule=table, sample_hz=sample_hz)
    try:
        ts = simulate(model, manoeuvre, **kwargs)
        metrics = manoeuvre_metrics(ts)  # of the motion, before any --noise
        clean = ts
        if noise_sd:
            ts = _add_noise(ts, noise_sd, seed)
        if samples:
            draws = [manoeuvre_metrics(simulate(m, manoeuvre, **kwargs))
                     .set_index("metric")["value"] for m in sample_models(model, samples, seed)]
            table = pd.concat(draws, axis=1)
            alpha = 0.05  # the 95 % band of the draws
            lo = table.quantile(alpha / 2, axis=1)
            hi = table.quantile(1 - alpha / 2, axis=1)
            metrics["ci_low"] = metrics["metric"].map(lo)
            metrics["ci_high"] = metrics["metric"].map(hi)
    except ValueError as exc:
        raise ProtocolError(f"{name}: {exc}") from None
    metrics = _refer_to_assumptions(metrics, model, propeller)
    folder = Path(out) if out is not None else Path.cwd() / f"simulate_{manoeuvre}"

    def write(tmp: Path) -> None:
        ts.to_csv(tmp / "manoeuvre.csv", index=False, float_format="%.6g")
        if manoeuvre == "glide":  # the steady glides around this one (docs/method.md)
            net = float(net_buoyancy_n or 0.0)  # set above for a glide
            sign = -1.0 if net <= 0 else 1.0
            size = abs(net) or 1.0
            table = glide_table(model, [sign * size * f for f in (0.5, 1.0, 2.0)],
                                [sign * p for p in range(5, 50, 5)])
            table.to_csv(tmp / "glide_table.csv", index=False, float_format="%.6g")
        metrics.to_csv(tmp / "metrics.csv", index=False, float_format="%.6g")
        _figure(clean, metrics, manoeuvre, tmp / "manoeuvre.png",
                str(model.get("name", "model")))

    write_outputs_or_stop(folder, SIMULATE_OUTPUTS, write)
    with pd.option_context("display.width", 120):
        print(metrics.to_string(index=False))
    line = guessed_line(_used(model, propeller))
    if line:
        print(line)
    print(f"wrote {folder / 'manoeuvre.csv'}, metrics.csv and manoeuvre.png"
          + (f" ({samples} samples of the measured coefficients)" if samples else ""))
    return 0


#: The metrics whose note names the model's guessed inputs (they rest on the fins, the centre
#: of gravity and the inertia).
REFERRED = ("steady_turn_radius_m", "tactical_diameter_m", "steady_pitch_deg",
            "glide_angle_deg")


def _used(model: dict, propeller: str) -> list[dict]:
    """model.json's ``assumptions`` the run rests on: the propeller's only when it drives
    the run (``propeller`` "rps")."""
    return [a for a in model.get("assumptions") or []
            if propeller == "rps" or a.get("input") != "propeller"]


def _refer_to_assumptions(metrics: pd.DataFrame, model: dict,
                          propeller: str = "thrust") -> pd.DataFrame:
    """metrics.csv with the notes of :data:`REFERRED` (and ``speed_loss_percent``) naming the
    model's guessed inputs; the propeller only when it drives the run (``propeller`` "rps")."""
    names = [str(a["input"]) for a in guessed(_used(model, propeller))]
    if not names:
        return metrics
    out = metrics.copy()
    text = f"rests on assumed inputs ({', '.join(names)}: model.json 'assumptions')"
    pick = out["metric"].isin(REFERRED + ("speed_loss_percent",))
    out.loc[pick, "note"] = [f"{n}; {text}" if n else text for n in out.loc[pick, "note"]]
    return out


def _check_propeller(model: dict | None, manoeuvre: str, propeller: str,
                     name: str) -> list[str]:
    """--propeller: thrust or rps; rps for a powered manoeuvre (not a glide) of a model with
    a ``propeller`` block."""
    if propeller not in PROPULSION:
        return [f"--propeller must be one of {', '.join(PROPULSION)}, not {propeller!r}."]
    if propeller != "rps":
        return []
    if manoeuvre == "glide":
        return ["--propeller rps is for a powered manoeuvre; a glide has no propulsion."]
    if model is not None and not isinstance(model.get("propeller"), dict):
        return [f"{name}: --propeller rps needs the model's propeller, but it has no "
                "'propeller' block (give the protocol a [vehicle.propeller] with diameter_m, "
                "pitch_ratio and blade_area_ratio, and run predict again)."]
    return []


def _check_new_inputs(manoeuvre: str, period_s: float | None, schedule: Path | None,
                      noise: str | None, sample_hz: float | None) -> tuple:
    """--period-s, --schedule, --noise, --sample-hz: (the schedule table or None, the noise
    {column: sd}, the problems, one sentence each)."""

    problems: list[str] = []
    table = None
    if period_s is not None:
        if manoeuvre != "sine":
            problems.append(f"--period-s is for --manoeuvre sine, not {manoeuvre}.")
        elif not (math.isfinite(period_s) and 0.5 <= period_s <= 3600):
            problems.append(f"--period-s must lie within 0.5 and 3600 s, not {period_s:g}.")
    if (schedule is None) != (manoeuvre != "schedule"):
        problems.append("--schedule FILE goes with --manoeuvre schedule (and it needs one).")
    elif schedule is not None:
        try:
            table = read_schedule(schedule)
        except ValueError as exc:
            problems.append(str(exc))
        else:
            if table["t_s"].iloc[-1] <= 0:
                problems.append(f"{Path(schedule).name}: the schedule must reach past t = 0 s.")
    if sample_hz is not None and not (math.isfinite(sample_hz) and 0.1 <= sample_hz <= 1000):
        problems.append(f"--sample-hz must lie within 0.1 and 1000 Hz, not {sample_hz:g}.")
    noise_sd: dict[str, float] = {}
    if noise:
        try:
            noise_sd = parse_noise(noise)
        except ProtocolError as exc:
            problems.append(str(exc))
    return table, noise_sd, problems


def _add_noise(ts, noise_sd: dict[str, float], seed: int):  # noqa: ANN001, ANN202
    """manoeuvre.csv with independent Gaussian noise of ``noise_sd`` [the column's unit] on
    the named states (seeded: the same seed, the same record)."""

    rng = np.random.default_rng(seed)
    out = ts.copy()
    for col, sd in noise_sd.items():
        out[col] = out[col] + rng.normal(0.0, sd, len(out))
    out.attrs = dict(ts.attrs) | {"noise": dict(noise_sd)}
    return out


def _figure(ts, metrics, manoeuvre: str, path: Path, name: str) -> None:  # noqa: ANN001
    """manoeuvre.png: the track and the time histories (towtank.report.manoeuvre_figure)."""
    save_manoeuvre_figure(ts, manoeuvre, path, name)
