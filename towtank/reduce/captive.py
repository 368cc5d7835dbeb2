"""Per-run reduction of captive manoeuvring runs: static drift, rudder, rotating arm and PMM.

Pure functions on arrays (FORMATS section 8; ITTC 7.5-02-06-02, Captive Model Test):

* :func:`body_kinematics` – u, v, r and their time derivatives of the origin O from the
  carriage speed, the PMM sway of O and the heading;
* :func:`drag_lift_to_body` – a balance that reports drag and lift along and across the tow,
  rotated into body axes by the drift angle;
* :func:`hydrodynamic_loads` – the balance readings less the model's inertia, the moment
  transferred from the balance point to O;
* :func:`regressors` – the terms of the manoeuvring model (:data:`REGRESSORS`);
* :func:`static_run` and :func:`pmm_run` – one run reduced to its components (a static run's
  steady mean; a PMM run's cycle-averaged mean, in-phase and quadrature first harmonics),
  the unit of information of the joint fit (:mod:`towtank.analysis.captive`);
* :func:`reduce_captive` – the one entry of the day's pipeline.

This module never loads pandas at import (the workers start light); :class:`CaptiveRun`'s
tables are built on first use.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from towtank.errors import RunError
from towtank.signal import conditioning
from towtank.signal.drift import check_drift

if TYPE_CHECKING:
    # loaded on use: pandas only for the tables (the workers start light)
    import pandas as pd

#: The regressors of the horizontal-plane model, in this order (Y = sum Y_k * regressor_k).
REGRESSORS = ("uv", "v|v|", "ur", "r|r|", "vdot", "rdot", "uudr", "uu")
#: The vertical twins of :data:`REGRESSORS` (same order).
VERTICAL_REGRESSORS = ("uw", "w|w|", "uq", "q|q|", "wdot", "qdot", "uuds", "uu")
#: Captive tests: static ones reduce to a steady mean, PMM ones to cycle harmonics.
STATIC_TESTS = ("drift", "rudder", "arm")
PMM_TESTS = ("sway", "yaw", "yaw_drift")
TESTS = STATIC_TESTS + PMM_TESTS
PLANES = ("horizontal", "vertical")
#: Components of a run: a static run has "mean"; a PMM run "mean", "sin" and "cos".
COMPONENTS = ("mean", "sin", "cos")
LOADS = ("X", "Y", "N")
ROW_COLUMNS = ("component", *LOADS, *(f"{q}_se" for q in LOADS), *REGRESSORS)
#: The quantities of a component row's covariance (:attr:`CaptiveRun.cov`), in this order.
COV_NAMES = ("Y", "N", *REGRESSORS)
CYCLE_COLUMNS = ("cycle", "t_start", "Y_in", "Y_quad", "N_in", "N_quad", "Y_0", "N_0")
PERIOD_COLUMNS = ("phase", "t", "X", "Y", "N", "y", "psi", "u", "v", "r", "udot", "vdot",
                  "rdot")
#: Tolerance of the measured PMM frequency and amplitude against the sheet's [-].
PMM_TOLERANCE = 0.05
#: A PMM cycle is kept when its sway amplitude is within this fraction of the median cycle's.
CYCLE_AMPLITUDE_TOLERANCE = 0.05
MIN_CYCLES = 3
#: Phase bins of the cycle-averaged period.
PERIOD_BINS = 72
#: Non-overlapping blocks of the steady window whose means give a static run's standard error.
STATIC_BLOCKS = 8
#: Harmonics of the least-squares fit of the PMM motion (besides the mean).
MOTION_HARMONICS = (1, 3)
#: Columns of a run's load trace (:func:`load_trace`): the whole run at :data:`TRACE_HZ`.
TRACE_COLUMNS = ("t", "X", "Y", "N", "sway", "yaw")
#: Rate of the load trace drawn in the report's thumbnails and watch's latest-run plot [Hz].
TRACE_HZ = 10.0
_ARRAYS_VERSION = 3.0


# ================================================================================ kinematics

def body_kinematics(
    speed: np.ndarray | float,
    psi: np.ndarray | float,
    *,
    psi_dot: np.ndarray | float = 0.0,
    psi_ddot: np.ndarray | float = 0.0,
    y_dot: np.ndarray | float = 0.0,
    y_ddot: np.ndarray | float = 0.0,
    speed_dot: np.ndarray | float = 0.0,
) -> dict[str, np.ndarray]:
    """Body-axis velocities and accelerations of O on the carriage (FORMATS section 8).

    u = U cos(psi) + y' sin(psi), v = -U sin(psi) + y' cos(psi), r = psi', and their time
    derivatives u', v', r'.

    Parameters
    ----------
    speed : array_like
        Carriage speed U [m/s].
    psi : array_like
        Heading relative to the tow direction, drift + PMM yaw [rad], positive nose to starboard.
    psi_dot, psi_ddot : array_like
        psi' [rad/s] and psi'' [rad/s^2].
    y_dot, y_ddot : array_like
        PMM sway velocity y' [m/s] and acceleration y'' [m/s^2] of O, positive to starboard.
    speed_dot : array_like
        U' [m/s^2].

    Returns
    -------
    dict
        u, v [m/s], r [rad/s], udot, vdot [m/s^2], rdot [rad/s^2].
    """
    U, p, pd_, pdd = (np.asarray(x, dtype=float) for x in (speed, psi, psi_dot, psi_ddot))
    yd, ydd, Ud = (np.asarray(x, dtype=float) for x in (y_dot, y_ddot, speed_dot))
    c, s = np.cos(p), np.sin(p)
    u = U * c + yd * s
    v = -U * s + yd * c
    udot = Ud * c - U * s * pd_ + ydd * s + yd * c * pd_
    vdot = -Ud * s - U * c * pd_ + ydd * c - yd * s * pd_
    shape = np.broadcast(U, p, pd_, pdd, yd, ydd, Ud).shape
    return {k: np.broadcast_to(x, shape).astype(float) for k, x in
            (("u", u), ("v", v), ("r", pd_), ("udot", udot), ("vdot", vdot), ("rdot", pdd))}


def arm_kinematics(speed: np.ndarray | float, drift: float, radius_m: float
                   ) -> dict[str, np.ndarray]:
    """Rotating arm: u = U cos(beta), v = -U sin(beta), r = U/R, accelerations zero.

    ``speed`` U [m/s] of O along its path, ``drift`` beta [rad], ``radius_m`` R [m] of O's
    path, positive with the centre to starboard.
    """
    U = np.asarray(speed, dtype=float)
    zero = np.zeros_like(U)
    return {"u": U * math.cos(drift), "v": -U * math.sin(drift), "r": U / radius_m,
            "udot": zero, "vdot": zero, "rdot": zero}


def drag_lift_to_body(drag: np.ndarray | float, lift: np.ndarray | float, drift: float
                      ) -> tuple[np.ndarray, np.ndarray]:
    """Body-axis balance forces (fx, fy) [N] from carriage-axis drag and lift [N].

    fx = -drag cos(beta) + lift sin(beta), fy = drag sin(beta) + lift cos(beta), with drag the
    balance's force along the tow (positive pulling the model forward), lift the water's force
    across it (positive to starboard) and ``drift`` beta [rad].
    """
    d, li = np.asarray(drag, dtype=float), np.asarray(lift, dtype=float)
    c, s = math.cos(drift), math.sin(drift)
    return -d * c + li * s, d * s + li * c


def hydrodynamic_loads(
    fx: np.ndarray, fy: np.ndarray, mz: np.ndarray, kin: Mapping[str, np.ndarray], *,
    mass_kg: float, izz_kg_m2: float, xg_m: float, balance_x_m: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Hydrodynamic X, Y [N] and N [N m] about the reference point P from the balance
    readings (FORMATS section 8; P = O unless ``[captive] moment_ref = "balance"``).

    X = fx + m (u' - v r - x_G r^2); Y = fy + m (v' + u r + x_G r');
    N = mz + x_B fy + (I_zG + m x_G^2) r' + m x_G (v' + u r), with the kinematics of P and
    x_G, x_B measured from P (the rigid body's equations about any point of its x axis).

    Parameters
    ----------
    fx, fy : ndarray
        Balance forces, body axes, zeroed [N].
    mz : ndarray
        Balance yaw moment about x = ``balance_x_m``, zeroed [N m].
    kin : mapping
        :func:`body_kinematics` of P (:func:`kinematics_at` to move them from O).
    mass_kg, izz_kg_m2, xg_m, balance_x_m : float
        m [kg], I_zG [kg m^2] about the CG, x_G [m] and x_B [m] from P.
    """
    u, v, r = kin["u"], kin["v"], kin["r"]
    ud, vd, rd = kin["udot"], kin["vdot"], kin["rdot"]
    m = mass_kg
    X = fx + m * (ud - v * r - xg_m * r**2)
    Y = fy + m * (vd + u * r + xg_m * rd)
    N = mz + balance_x_m * fy + (izz_kg_m2 + m * xg_m**2) * rd + m * xg_m * (vd + u * r)
    return X, Y, N


def kinematics_at(kin: Mapping[str, np.ndarray], x_m: float) -> dict[str, np.ndarray]:
    """The body-axis kinematics of the point x = ``x_m`` [m] on the x axis from those of O:
    v_P = v + x_P r and v_P' = v' + x_P r'; u, u', r and r' are the same (a rigid body)."""
    out = dict(kin)
    if x_m:
        out["v"] = kin["v"] + x_m * kin["r"]
        out["vdot"] = kin["vdot"] + x_m * kin["rdot"]
    return out


def reference_x(moment_ref: str, balance_x_m: float | None) -> float:
    """x [m] from O of the point the derivatives refer to: 0 for ``[captive] moment_ref =
    "origin"``; the balance point ``balance_x_m`` for ``"balance"`` (0 when it is not given:
    the balance's point is then the origin the model's x_G is measured from)."""
    return float(balance_x_m or 0.0) if moment_ref == "balance" else 0.0


def protocol_reference_x(captive: Any, model: Any) -> float:
    """:func:`reference_x` of a protocol's ``[captive]`` section (its ``moment_ref``; a dict
    or the section's object; None: "origin") and ``[model]`` (its ``balance_x_m``)."""
    ref = (captive.get("moment_ref") if isinstance(captive, dict)
           else getattr(captive, "moment_ref", None))
    return reference_x(str(ref or "origin"), getattr(model, "balance_x_m", None))


def moment_point(ref_x_m: float) -> str:
    """Where the moments are taken, for a caption: "about O", or "about the balance point (x =
    ... m from O)" when the derivatives refer to a point ``ref_x_m`` [m] from O
    (:func:`reference_x`)."""
    return "about O" if ref_x_m == 0.0 else f"about the balance point (x = {ref_x_m:g} m from O)"


def regressors(kin: Mapping[str, np.ndarray], rudder: float) -> dict[str, np.ndarray]:
    """The model's regressors (:data:`REGRESSORS`) from :func:`body_kinematics`; ``rudder``
    delta [rad]."""
    u, v, r = kin["u"], kin["v"], kin["r"]
    return {"uv": u * v, "v|v|": v * np.abs(v), "ur": u * r, "r|r|": r * np.abs(r),
            "vdot": np.asarray(kin["vdot"], dtype=float),
            "rdot": np.asarray(kin["rdot"], dtype=float),
            "uudr": u**2 * rudder, "uu": u**2}


# =========================================================================== the run result

@dataclass(frozen=True)
class CaptiveRun:
    """One captive run reduced to the components the joint fit uses (see module docstring).

    ``rows``: one row per component ("mean"; PMM also "sin", "cos") with X, Y [N], N [N m]
    about O (inertia removed), their standard errors and each regressor's component
    (:data:`REGRESSORS`, rig axes, horizontal names). ``cycles``: a PMM run's kept cycles with
    their first harmonics. ``period``: the cycle-averaged period in :data:`PERIOD_BINS` phase
    bins (empty for static runs). ``cov``: per component row, the covariance of the row's
    Y, N and regressors (:data:`COV_NAMES`) as the run's scatter gives it (over cycles or
    blocks of the steady window, the zero's uncertainty added to the mean's Y and N), shape
    (rows, 10, 10); None when unknown (a lab's table of means). ``trace``: the whole run's
    measured loads and motion at :data:`TRACE_HZ` for its plots (:func:`load_trace`).
    """

    run: int
    file: str
    test: str
    plane: str
    speed: float
    drift_deg: float
    rudder_deg: float
    radius_m: float
    frequency_hz: float
    amplitude_m: float
    cycles_used: int
    rows: pd.DataFrame
    cycles: pd.DataFrame
    period: pd.DataFrame
    notes: tuple[str, ...] = ()
    cov: np.ndarray | None = None
    #: the whole run's measured loads and motion for its plots (:func:`load_trace`, columns
    #: :data:`TRACE_COLUMNS`), shape (samples, 6); None when not recorded
    trace: np.ndarray | None = None

    def omega_prime(self, length_m: float) -> float:
        """omega' = omega L / U [-] with L = ``length_m`` [m] (NaN for static runs)."""
        return 2.0 * math.pi * self.frequency_hz * length_m / self.speed

    def to_arrays(self) -> dict[str, np.ndarray]:
        """Plain float arrays that :meth:`from_arrays` turns back into this run exactly."""
        scalars = [_ARRAYS_VERSION, TESTS.index(self.test), PLANES.index(self.plane),
                   self.speed, self.drift_deg, self.rudder_deg, self.radius_m,
                   self.frequency_hz, self.amplitude_m, float(self.cycles_used)]
        rows = self.rows.copy()
        rows["component"] = [COMPONENTS.index(c) for c in rows["component"]]
        text = "\x00".join(self.notes).encode("utf-8")
        n_cov = len(COV_NAMES) ** 2
        cov = (np.full((len(rows), n_cov), np.nan) if self.cov is None
               else np.asarray(self.cov, dtype=float).reshape(len(rows), n_cov))
        return {
            "cov": cov,
            "scalars": np.array(scalars, dtype=float),
            "rows": rows[list(ROW_COLUMNS)].to_numpy(dtype=float).reshape(-1, len(ROW_COLUMNS)),
            "cycles": self.cycles[list(CYCLE_COLUMNS)].to_numpy(dtype=float).reshape(
                -1, len(CYCLE_COLUMNS)),
            "period": self.period[list(PERIOD_COLUMNS)].to_numpy(dtype=float).reshape(
                -1, len(PERIOD_COLUMNS)),
            "notes": np.frombuffer(text, dtype=np.uint8).astype(float),
            "has_notes": np.array([float(bool(self.notes))]),
            "trace": (np.empty((0, len(TRACE_COLUMNS))) if self.trace is None
                      else np.asarray(self.trace, dtype=float)),
        }

    @classmethod
    def from_arrays(cls, run: int, file: str, arrays: Mapping[str, np.ndarray]) -> CaptiveRun:
        """The run :meth:`to_arrays` gave; ValueError on anything malformed."""
        # loaded on use: pandas only for the tables (the workers start light)
        import pandas as pd

        try:
            sc = _float_array(arrays, "scalars", 1)
            rows = _float_array(arrays, "rows", 2)
            cycles = _float_array(arrays, "cycles", 2)
            period = _float_array(arrays, "period", 2)
            notes_b = _float_array(arrays, "notes", 1)
            has_notes = _float_array(arrays, "has_notes", 1)
            cov = _float_array(arrays, "cov", 2)
            trace = _float_array(arrays, "trace", 2)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"malformed captive arrays: {exc}") from None
        if sc.size != 10 or sc[0] != _ARRAYS_VERSION:
            raise ValueError("malformed captive arrays: 'scalars' is not a captive run's")
        test, plane = _code(sc[1], TESTS, "test"), _code(sc[2], PLANES, "plane")
        for name, a, width in (("rows", rows, len(ROW_COLUMNS)),
                               ("cycles", cycles, len(CYCLE_COLUMNS)),
                               ("period", period, len(PERIOD_COLUMNS)),
                               ("trace", trace, len(TRACE_COLUMNS))):
            if a.shape[1] != width:
                raise ValueError(f"malformed captive arrays: '{name}' has {a.shape[1]} columns, "
                                 f"not {width}")
        if rows.shape[0] not in (1, 3):
            raise ValueError("malformed captive arrays: a run has 1 or 3 component rows")
        if cov.shape != (rows.shape[0], len(COV_NAMES) ** 2):
            raise ValueError("malformed captive arrays: 'cov' does not match the rows")
        comps = [_code(c, COMPONENTS, "component") for c in rows[:, 0]]
        if comps != list(COMPONENTS[: rows.shape[0]]):
            raise ValueError("malformed captive arrays: components out of order")
        if not (np.isfinite(trace[:, :4]).all() and np.all(np.diff(trace[:, 0]) > 0)):
            raise ValueError("malformed captive arrays: 'trace' is not a run's loads in time")
        if not math.isfinite(sc[3]) or sc[3] <= 0 or sc[9] < 0 or sc[9] != int(sc[9]):
            raise ValueError("malformed captive arrays: speed or cycle count out of range")
        if (notes_b.size and (np.any(notes_b < 0) or np.any(notes_b > 255)
                              or np.any(notes_b != np.round(notes_b)))):
            raise ValueError("malformed captive arrays: 'notes' is not text")
        if has_notes.size != 1 or has_notes[0] not in (0.0, 1.0) or (
                has_notes[0] == 0.0 and notes_b.size):
            raise ValueError("malformed captive arrays: 'has_notes' does not match 'notes'")
        try:
            text = notes_b.astype(np.uint8).tobytes().decode("utf-8")
        except UnicodeDecodeError:
            raise ValueError("malformed captive arrays: 'notes' is not UTF-8 text") from None
        notes = tuple(text.split("\x00")) if has_notes[0] == 1.0 else ()
        rows_df = pd.DataFrame(rows, columns=list(ROW_COLUMNS))
        rows_df["component"] = comps
        return cls(
            run=int(run), file=str(file), test=test, plane=plane, speed=float(sc[3]),
            drift_deg=float(sc[4]), rudder_deg=float(sc[5]), radius_m=float(sc[6]),
            frequency_hz=float(sc[7]), amplitude_m=float(sc[8]), cycles_used=int(sc[9]),
            rows=rows_df,
            cycles=pd.DataFrame(cycles, columns=list(CYCLE_COLUMNS)).astype(
                {"cycle": int}),
            period=pd.DataFrame(period, columns=list(PERIOD_COLUMNS)),
            notes=notes,
            cov=None if np.all(np.isnan(cov)) else cov.reshape(
                -1, len(COV_NAMES), len(COV_NAMES)),
            trace=trace if trace.size else None,
        )


def _float_array(arrays: Mapping[str, np.ndarray], key: str, ndim: int) -> np.ndarray:
    if key not in arrays:
        raise ValueError(f"no '{key}'")
    a = np.asarray(arrays[key])
    if a.dtype.kind not in "fiu" or a.ndim != ndim:
        raise ValueError(f"'{key}' is not a {ndim}-d array of numbers")
    return a.astype(float)


def _code(x: float, names: tuple[str, ...], what: str) -> str:
    if not (math.isfinite(x) and x == int(x) and 0 <= x < len(names)):
        raise ValueError(f"malformed captive arrays: {what} code {x!r}")
    return names[int(x)]


def _rows_frame(rows: list[dict[str, Any]]) -> pd.DataFrame:
    # loaded on use: pandas only for the tables (the workers start light)
    import pandas as pd

    return pd.DataFrame(rows, columns=list(ROW_COLUMNS))


def _empty(columns: tuple[str, ...]) -> pd.DataFrame:
    # loaded on use: pandas only for the tables (the workers start light)
    import pandas as pd

    return pd.DataFrame({c: np.array([], dtype=int if c == "cycle" else float)
                         for c in columns})


# ================================================================================ static runs

def block_mean_se(x: np.ndarray, n_blocks: int = STATIC_BLOCKS) -> float:
    """Standard error of the mean of ``x`` from ``n_blocks`` non-overlapping block means
    (the batch-means estimator: blocks longer than the filter's memory are independent)."""
    means = block_means(x, n_blocks)
    if means.size < 2:
        return math.nan
    return float(np.std(means, ddof=1) / math.sqrt(n_blocks))


def block_means(x: np.ndarray, n_blocks: int = STATIC_BLOCKS) -> np.ndarray:
    """The means of ``n_blocks`` equal non-overlapping blocks of ``x`` (the tail that does not
    fill a block left out); empty when ``x`` is shorter than ``n_blocks``."""
    x = np.asarray(x, dtype=float)
    n = x.size // n_blocks
    return x[: n * n_blocks].reshape(n_blocks, n).mean(axis=1) if n else np.array([])


def mean_cov(parts: np.ndarray) -> np.ndarray:
    """Covariance [units^2] of the mean of ``parts`` (shape (k, q): k independent parts, block
    or cycle values, of q quantities): their sample covariance over k."""
    parts = np.asarray(parts, dtype=float)
    return np.atleast_2d(np.cov(parts, rowvar=False, ddof=1)) / parts.shape[0]


def zero_variance(x: np.ndarray, t: np.ndarray, pre: tuple[int, int],
                  post: tuple[int, int] | None, at: float) -> float:
    """Variance [units^2] of the zero line (:func:`towtank.signal.conditioning.zero_line`)
    of the filtered channel ``x`` at time ``at`` [s]: each still window's mean has the
    batch-means variance of its :data:`STATIC_BLOCKS` blocks, weighted by the line's
    interpolation between the windows' mid-times (the pre-window's alone without ``post``)."""
    var_pre = block_mean_se(x[pre[0]:pre[1]]) ** 2
    if post is None or post[1] - post[0] < 2:
        return var_pre
    var_post = block_mean_se(x[post[0]:post[1]]) ** 2
    t0, t1 = float(np.mean(t[pre[0]:pre[1]])), float(np.mean(t[post[0]:post[1]]))
    w = (at - t0) / (t1 - t0) if t1 > t0 else 0.0
    return (1.0 - w) ** 2 * var_pre + w**2 * var_post


def load_zero_variance(zero_var: Mapping[str, float], drift: float, balance_x_m: float
                       ) -> tuple[float, float]:
    """Variances of Y [N^2] and N [N^2 m^2] from the zero variances of the balance channels
    (``fy``, ``mz``, or a drift run's ``drag``, ``lift``; missing: 0) at ``drift`` [rad],
    with N = mz + x_B fy (``balance_x_m`` x_B [m])."""
    if "fy" in zero_var:
        fy = zero_var["fy"]
    else:
        fy = (math.sin(drift) ** 2 * zero_var.get("drag", 0.0)
              + math.cos(drift) ** 2 * zero_var.get("lift", 0.0))
    return fy, zero_var.get("mz", 0.0) + balance_x_m**2 * fy


def _with_zero(cov: np.ndarray, var_y: float, var_n: float) -> np.ndarray:
    """``cov`` (of :data:`COV_NAMES`) with the zero's variances added to Y's and N's."""
    out = np.array(cov, dtype=float)
    out[0, 0] += var_y
    out[1, 1] += var_n
    return out


@dataclass(frozen=True)
class RunSetting:
    """What the sheet sets for a captive run: ``test`` (:data:`TESTS`), ``plane``, drift and
    rudder angles [deg], arm radius [m], PMM amplitude [m] and frequency [Hz] (NaN: not set)."""

    test: str
    plane: str = "horizontal"
    drift_deg: float = 0.0
    rudder_deg: float = 0.0
    radius_m: float = math.nan
    pmm_amplitude_m: float = math.nan
    pmm_frequency_hz: float = math.nan

    @classmethod
    def from_row(cls, row: Mapping[str, Any]) -> RunSetting:
        """The setting of a run-sheet row (missing or empty values take the defaults)."""
        def num(name: str, default: float) -> float:
            value = row.get(name)
            try:
                x = float(value) if value is not None and str(value).strip() != "" else default
            except (TypeError, ValueError):
                raise RunError(f"the sheet's {name} {value!r} is not a number") from None
            return default if math.isnan(x) else x

        test = str(row.get("test", "")).strip().lower()
        if test not in TESTS:
            raise RunError(f"the sheet's test {row.get('test')!r} is not a captive test "
                           f"({', '.join(TESTS)})")
        plane = str(row.get("plane") or "horizontal").strip().lower() or "horizontal"
        if plane not in PLANES:
            raise RunError(f"the sheet's plane {row.get('plane')!r} is neither 'horizontal' "
                           "nor 'vertical'")
        s = cls(test=test, plane=plane, drift_deg=num("drift_deg", 0.0),
                rudder_deg=num("rudder_deg", 0.0), radius_m=num("radius_m", math.nan),
                pmm_amplitude_m=num("pmm_amplitude_m", math.nan),
                pmm_frequency_hz=num("pmm_frequency_hz", math.nan))
        s.check()
        return s

    def check(self) -> None:
        """RunError (one sentence) for a setting no run can have."""
        if not abs(self.drift_deg) < 90.0:
            raise RunError(f"the drift angle {self.drift_deg:g} deg is beyond +-90 deg")
        if self.test == "arm" and not (math.isfinite(self.radius_m) and self.radius_m != 0.0):
            raise RunError(f"a rotating-arm run needs a non-zero radius_m, not {self.radius_m:g}")
        if self.test in PMM_TESTS:
            for name, x in (("pmm_amplitude_m", self.pmm_amplitude_m),
                            ("pmm_frequency_hz", self.pmm_frequency_hz)):
                if not (math.isfinite(x) and x > 0.0):
                    raise RunError(f"a PMM run needs a positive {name} in the sheet, not {x:g}")


@dataclass(frozen=True)
class Inertia:
    """The model on the balance: mass m [kg], I [kg m^2] about its CG (I_zG; I_yG for a
    vertical-plane run), x_G [m] and the balance point x_B [m] from O, and the point P the
    derivatives refer to, x_P [m] from O (:func:`reference_x`: 0, or x_B)."""

    mass_kg: float
    inertia_kg_m2: float
    xg_m: float
    balance_x_m: float
    ref_x_m: float = 0.0

    @property
    def moment_arm_m(self) -> float:
        """x_B - x_P [m]: N about P = mz + (x_B - x_P) fy."""
        return self.balance_x_m - self.ref_x_m

    def at_ref(self, kin: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
        """The kinematics of P from those of O (:func:`kinematics_at`)."""
        return kinematics_at(kin, self.ref_x_m)

    def loads(self, fx: np.ndarray, fy: np.ndarray, mz: np.ndarray,
              kin: Mapping[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:func:`hydrodynamic_loads` about P with this model; ``kin`` those of P
        (:meth:`at_ref`)."""
        return hydrodynamic_loads(fx, fy, mz, kin, mass_kg=self.mass_kg,
                                  izz_kg_m2=self.inertia_kg_m2, xg_m=self.xg_m - self.ref_x_m,
                                  balance_x_m=self.moment_arm_m)


def static_run(
    t: np.ndarray, speed: np.ndarray, fx: np.ndarray, fy: np.ndarray, mz: np.ndarray,
    steady: tuple[int, int], setting: RunSetting, inertia: Inertia, *, run: int = 0,
    file: str = "", notes: tuple[str, ...] = (), zero_var: tuple[float, float] = (0.0, 0.0),
) -> CaptiveRun:
    """A static drift, rudder or rotating-arm run reduced to its steady mean.

    Loads and regressors are taken sample by sample over the steady window [i0, i1) and
    averaged; the covariance of the mean's Y, N and regressors is that of
    :data:`STATIC_BLOCKS` block means (:func:`mean_cov`), plus the zero's variances
    ``zero_var`` (Y [N^2], N [N^2 m^2]); X's standard error is :func:`block_mean_se`'s.

    Parameters
    ----------
    t : ndarray
        Time [s].
    speed : ndarray
        Filtered carriage speed U [m/s] (of O along its path on the arm).
    fx, fy, mz : ndarray
        Zeroed balance readings, body axes [N], [N], [N m].
    steady : tuple of int
        The steady window's indices [i0, i1).
    setting : RunSetting
        The sheet's values.
    inertia : Inertia
        The model on the balance.
    """
    i0, i1 = steady
    beta, delta = math.radians(setting.drift_deg), math.radians(setting.rudder_deg)
    U = np.asarray(speed[i0:i1], dtype=float)
    if setting.test == "arm":
        kin = inertia.at_ref(arm_kinematics(U, beta, setting.radius_m))
    else:
        kin = inertia.at_ref(body_kinematics(U, beta))
    X, Y, N = inertia.loads(fx[i0:i1], fy[i0:i1], mz[i0:i1], kin)
    reg = regressors(kin, delta)
    row: dict[str, Any] = {"component": "mean"}
    for name, x in (("X", X), ("Y", Y), ("N", N)):
        row[name] = float(np.mean(x))
    row.update({k: float(np.mean(x)) for k, x in reg.items()})
    series = {"Y": Y, "N": N, **reg}
    cov = _with_zero(mean_cov(np.column_stack([block_means(np.broadcast_to(series[k], U.shape))
                                               for k in COV_NAMES])), *zero_var)
    row.update({"X_se": block_mean_se(X), "Y_se": math.sqrt(cov[0, 0]),
                "N_se": math.sqrt(cov[1, 1])})
    return CaptiveRun(
        run=run, file=file, test=setting.test, plane=setting.plane, speed=float(np.mean(U)),
        drift_deg=setting.drift_deg, rudder_deg=setting.rudder_deg,
        radius_m=setting.radius_m if setting.test == "arm" else math.nan,
        frequency_hz=math.nan, amplitude_m=math.nan, cycles_used=0,
        rows=_rows_frame([row]), cycles=_empty(CYCLE_COLUMNS), period=_empty(PERIOD_COLUMNS),
        notes=notes, cov=cov[None],
    )


# =================================================================================== PMM runs

def harmonic_design(t: np.ndarray, omega: float,
                    harmonics: tuple[int, ...] = MOTION_HARMONICS) -> np.ndarray:
    """Columns 1, sin(k omega t), cos(k omega t) for each k of ``harmonics``."""
    cols = [np.ones_like(t)]
    for k in harmonics:
        cols += [np.sin(k * omega * t), np.cos(k * omega * t)]
    return np.column_stack(cols)


def harmonic_fit(t: np.ndarray, x: np.ndarray, omega: float,
                 harmonics: tuple[int, ...] = MOTION_HARMONICS) -> np.ndarray:
    """Least-squares coefficients [mean, sin_k, cos_k for each k] of ``x`` at times ``t`` [s]
    and the fundamental ``omega`` [rad/s]."""
    coef, *_ = np.linalg.lstsq(harmonic_design(t, omega, harmonics), x, rcond=None)
    return coef


def harmonic_eval(coef: np.ndarray, t: np.ndarray, omega: float, order: int = 0,
                  harmonics: tuple[int, ...] = MOTION_HARMONICS) -> np.ndarray:
    """The ``order``-th time derivative (0, 1, 2) of the harmonic series ``coef`` at ``t``."""
    out = np.full_like(t, coef[0] if order == 0 else 0.0, dtype=float)
    for j, k in enumerate(harmonics):
        a, b, w = coef[1 + 2 * j], coef[2 + 2 * j], k * omega
        s, c = np.sin(w * t), np.cos(w * t)
        if order == 0:
            out += a * s + b * c
        elif order == 1:
            out += w * (a * c - b * s)
        else:
            out += -w * w * (a * s + b * c)
    return out


def upward_crossings(t: np.ndarray, y: np.ndarray, hysteresis: float) -> np.ndarray:
    """Times [s] of the upward zero crossings of ``y`` (linear interpolation), each counted
    only after ``y`` has been below ``-hysteresis`` since the last one (noise cannot add
    crossings)."""
    armed = False
    out = []
    for i in range(1, y.size):
        if y[i - 1] < -hysteresis:
            armed = True
        if armed and y[i - 1] < 0.0 <= y[i]:
            out.append(t[i - 1] + (t[i] - t[i - 1]) * (-y[i - 1]) / (y[i] - y[i - 1]))
            armed = False
    return np.asarray(out, dtype=float)


@dataclass(frozen=True)
class Cycles:
    """The kept PMM cycles: their start times [s] (each ends where the next starts, the last at
    ``t_end``), the sway amplitude of each [m] and the cycles dropped."""

    starts: np.ndarray
    t_end: float
    amplitudes: np.ndarray
    dropped: int

    @property
    def frequency_hz(self) -> float:
        """Measured PMM frequency [Hz]: kept cycles over their span."""
        return self.starts.size / (self.t_end - self.starts[0])


@dataclass(frozen=True)
class SteadyCycles:
    """Every cycle of the sway between upward zero crossings inside the steady window, and
    which of them :func:`pmm_cycles` keeps: ``crossings`` [s] (cycle k spans crossings k and
    k + 1), ``amplitudes`` [m] (half the peak-to-peak of each), the reference amplitude
    ``reference`` [m] (the median of the full-amplitude cycles), ``in_tolerance`` (within
    the tolerance of it) and ``kept`` (the cycles' indices: the longest unbroken sequence of
    those in tolerance)."""

    crossings: np.ndarray
    amplitudes: np.ndarray
    reference: float
    in_tolerance: np.ndarray
    kept: np.ndarray


def steady_cycles(t: np.ndarray, y: np.ndarray, steady: tuple[int, int], *,
                  tolerance: float = CYCLE_AMPLITUDE_TOLERANCE) -> SteadyCycles:
    """The cycles of the sway ``y`` [m] at times ``t`` [s] within the steady window [i0, i1)
    and the choice of the kept ones, within ``tolerance`` [-] of the reference amplitude
    (FORMATS section 8; see :func:`pmm_cycles`)."""
    i0, i1 = steady
    ys = y[i0:i1] - float(np.mean(y[i0:i1]))
    ts = t[i0:i1]
    span = float(np.max(ys) - np.min(ys)) if ys.size else 0.0
    cross = upward_crossings(ts, ys, 0.1 * span / 2.0)
    amps = np.array([
        0.5 * float(np.ptp(ys[(ts >= a) & (ts < b)])) for a, b in zip(cross[:-1], cross[1:],
                                                                      strict=True)])
    keep = np.zeros(amps.size, dtype=bool)
    ref = math.nan
    if amps.size:
        # the median of the full-amplitude cycles: the median cycle's when most cycles are
        # steady, and still the steady cycles' when ramp cycles outnumber them
        ref = float(np.median(amps[amps >= 0.9 * np.max(amps)]))
        keep = np.abs(amps - ref) <= tolerance * ref
    idx = np.flatnonzero(keep)
    if idx.size:  # the longest run of consecutive kept cycles
        breaks = np.flatnonzero(np.diff(idx) > 1)
        groups = np.split(idx, breaks + 1)
        idx = max(groups, key=len)
    return SteadyCycles(crossings=cross, amplitudes=amps, reference=ref, in_tolerance=keep,
                        kept=idx)


def pmm_cycles(t: np.ndarray, y: np.ndarray, steady: tuple[int, int], *,
               min_cycles: int = MIN_CYCLES,
               tolerance: float = CYCLE_AMPLITUDE_TOLERANCE) -> Cycles:
    """The whole steady PMM cycles of the sway ``y`` [m] (FORMATS section 8; shared rules).

    t = 0 at an upward zero crossing of y - mean(y); a cycle spans consecutive upward
    crossings; kept are the cycles wholly inside the steady window [i0, i1) whose amplitude
    (half the peak-to-peak) is within ``tolerance`` [-] of the median of the full-amplitude
    cycles (those within 10 % of the largest), the longest unbroken sequence
    (:func:`steady_cycles`). RunError when fewer than ``min_cycles`` remain (the protocol's
    ``[captive] min_cycles`` and ``amplitude_tolerance``).
    """
    sc = steady_cycles(t, y, steady, tolerance=tolerance)
    idx, cross, amps = sc.kept, sc.crossings, sc.amplitudes
    if idx.size < min_cycles:
        raise RunError(
            f"the run has {idx.size} whole steady PMM cycle{'' if idx.size == 1 else 's'}; at "
            f"least {min_cycles} are needed (ramp-in and ramp-out cycles are dropped)")
    return Cycles(starts=cross[idx], t_end=float(cross[idx[-1] + 1]), amplitudes=amps[idx],
                  dropped=int(amps.size - idx.size))


@dataclass(frozen=True)
class CycleVerdict:
    """One cycle of a PMM run's sway as :func:`pmm_cycles` judges it: its span [s], its
    amplitude [m] (half the peak-to-peak), whether it is kept and, if not, why."""

    start: float
    end: float
    amplitude: float
    kept: bool
    reason: str = ""


def cycle_verdicts(t: np.ndarray, y: np.ndarray, steady: tuple[int, int], *,
                   tolerance: float = CYCLE_AMPLITUDE_TOLERANCE) -> list[CycleVerdict]:
    """Every cycle of the sway ``y`` [m] over the whole record, in time order, each kept or
    dropped with its reason (``towtank inspect``): the cycles inside the steady window
    [i0, i1) exactly as :func:`pmm_cycles` chooses them (:func:`steady_cycles`), and the
    cycles that reach outside it (the same zero line and hysteresis over the whole record),
    which are never kept."""
    i0, i1 = steady
    sc = steady_cycles(t, y, steady, tolerance=tolerance)
    mean = float(np.mean(y[i0:i1]))
    span = float(np.ptp(y[i0:i1])) if i1 > i0 else 0.0
    lo, hi = float(t[i0]), float(t[i1 - 1])
    out = []
    whole = upward_crossings(t, y - mean, 0.1 * span / 2.0)
    for a, b in zip(whole[:-1], whole[1:], strict=True):
        if a < lo or b > hi:
            part = (t >= a) & (t < b)
            out.append(CycleVerdict(float(a), float(b), 0.5 * float(np.ptp(y[part])), False,
                                    "outside the steady window"))
    kept = set(sc.kept.tolist())
    for k, amp in enumerate(sc.amplitudes):
        a, b = float(sc.crossings[k]), float(sc.crossings[k + 1])
        if k in kept:
            reason = ""
        elif not sc.in_tolerance[k]:
            reason = (f"amplitude {amp:.4g} m is {100 * (amp / sc.reference - 1):+.1f} % from "
                      f"the steady cycles' {sc.reference:.4g} m (more than "
                      f"{100 * tolerance:g} %: ramp-in or ramp-out)")
        else:
            reason = "not in the longest unbroken sequence of steady cycles"
        out.append(CycleVerdict(a, b, float(amp), k in kept, reason))
    return sorted(out, key=lambda c: c.start)


def first_harmonic(t: np.ndarray, x: np.ndarray, omega: float) -> tuple[float, float, float]:
    """(mean, in-phase, quadrature) of ``x`` over one cycle: x ~ x0 + x_in sin(omega t) +
    x_quad cos(omega t) + third harmonic, by least squares (``t`` [s] from the cycle's start)."""
    coef = harmonic_fit(t, x, omega)
    return float(coef[0]), float(coef[1]), float(coef[2])


def pmm_run(
    t: np.ndarray, speed: np.ndarray, fx: np.ndarray, fy: np.ndarray, mz: np.ndarray,
    sway: np.ndarray, yaw: np.ndarray | None, steady: tuple[int, int], setting: RunSetting,
    inertia: Inertia, *, length_m: float = math.nan, run: int = 0, file: str = "",
    notes: tuple[str, ...] = (), min_cycles: int = MIN_CYCLES,
    tolerance: float = PMM_TOLERANCE, zero_var: tuple[float, float] = (0.0, 0.0),
) -> CaptiveRun:
    """A pure-sway, pure-yaw or yaw-with-drift PMM run reduced to its cycle harmonics.

    The kept cycles (:func:`pmm_cycles`) set t = 0 and the measured frequency; the motion
    (y, psi and their derivatives) is the least-squares series (mean, 1st and 3rd harmonic)
    of the recorded ``sway`` [m] and ``yaw`` [deg] over the kept cycles; U the steady mean.
    Each cycle's loads and regressors are split into mean, sin and cos parts; the run's
    component is their mean over cycles, the covariance of its Y, N and regressors their
    scatter over the cycles (:func:`mean_cov`), the mean's with the zero's variances
    ``zero_var`` (Y [N^2], N [N^2 m^2]) added.

    Parameters
    ----------
    t, speed, fx, fy, mz : ndarray
        As :func:`static_run`.
    sway : ndarray
        Lateral position of O [m], positive to starboard.
    yaw : ndarray or None
        The PMM's yaw angle [deg] added to the drift angle (None: 0, a pure-sway rig).
    steady : tuple of int
        The carriage's steady window [i0, i1).
    setting : RunSetting
        The sheet's values (amplitude and frequency checked within :data:`PMM_TOLERANCE`).
    inertia : Inertia
        The model on the balance.
    length_m : float
        L [m], for the omega' of the note (optional).
    min_cycles : int
        Fewest whole steady cycles the run needs (:func:`pmm_cycles`).
    tolerance : float
        Largest relative departure of a cycle's amplitude from the median cycle's and of the
        measured frequency and amplitude from the sheet's [-].
    """
    # loaded on use: pandas only for the tables (the workers start light)
    import pandas as pd

    cyc = pmm_cycles(t, sway, steady, min_cycles=min_cycles, tolerance=tolerance)
    f = cyc.frequency_hz
    f_set, y_set = setting.pmm_frequency_hz, setting.pmm_amplitude_m
    sel = (t >= cyc.starts[0]) & (t < cyc.t_end)
    ts = t[sel] - cyc.starts[0]
    omega = 2.0 * math.pi * f
    y_coef = harmonic_fit(ts, sway[sel], omega)
    y0 = math.hypot(y_coef[1], y_coef[2])
    if abs(f - f_set) > tolerance * f_set:
        raise RunError(f"the PMM frequency measured from the sway, {f:.4g} Hz, is not within "
                       f"{tolerance:.0%} of the sheet's pmm_frequency_hz {f_set:g} Hz")
    if abs(y0 - y_set) > tolerance * y_set:
        raise RunError(f"the PMM sway amplitude measured, {y0:.4g} m, is not within "
                       f"{tolerance:.0%} of the sheet's pmm_amplitude_m {y_set:g} m")
    beta, delta = math.radians(setting.drift_deg), math.radians(setting.rudder_deg)
    yaw_rad = np.radians(yaw[sel]) if yaw is not None else np.zeros(ts.size)
    U = float(np.mean(speed[steady[0]:steady[1]]))
    edges = np.append(cyc.starts, cyc.t_end) - cyc.starts[0]
    per_cycle: dict[str, list[tuple[float, float, float]]] = {}
    whole: dict[str, list[np.ndarray]] = {}
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        m = (ts >= a) & (ts < b)
        tc = ts[m] - a
        # the cycle's own motion fit: noise of the motion channels varies from cycle to cycle
        # and so enters the components' standard errors
        y_c = harmonic_fit(tc, sway[sel][m], omega)
        p_c = harmonic_fit(tc, yaw_rad[m], omega)
        psi = beta + harmonic_eval(p_c, tc, omega)
        kin = inertia.at_ref(body_kinematics(
            U, psi, psi_dot=harmonic_eval(p_c, tc, omega, 1),
            psi_ddot=harmonic_eval(p_c, tc, omega, 2),
            y_dot=harmonic_eval(y_c, tc, omega, 1), y_ddot=harmonic_eval(y_c, tc, omega, 2)))
        X, Y, N = inertia.loads(fx[sel][m], fy[sel][m], mz[sel][m], kin)
        series = {"X": X, "Y": Y, "N": N, **regressors(kin, delta)}
        for k, x in series.items():
            per_cycle.setdefault(k, []).append(first_harmonic(tc, x, omega))
        for k, x in {**series, "y": harmonic_eval(y_c, tc, omega), "psi": psi, **kin}.items():
            whole.setdefault(k, []).append(np.asarray(x))
    comp = {k: np.array(v) for k, v in per_cycle.items()}  # (cycles, 3)
    n_c = cyc.starts.size
    rows = []
    covs = []
    for j, name in enumerate(COMPONENTS):
        row: dict[str, Any] = {"component": name}
        cov = mean_cov(np.column_stack([comp[k][:, j] for k in COV_NAMES]))
        covs.append(_with_zero(cov, *zero_var) if name == "mean" else cov)
        for q in LOADS:
            row[q] = float(np.mean(comp[q][:, j]))
        row["X_se"] = float(np.std(comp["X"][:, j], ddof=1) / math.sqrt(n_c))
        row["Y_se"], row["N_se"] = (math.sqrt(covs[-1][i, i]) for i in (0, 1))
        row.update({k: float(np.mean(comp[k][:, j])) for k in REGRESSORS})
        rows.append(row)
    cycles = pd.DataFrame({
        "cycle": np.arange(n_c), "t_start": cyc.starts,
        "Y_in": comp["Y"][:, 1], "Y_quad": comp["Y"][:, 2],
        "N_in": comp["N"][:, 1], "N_quad": comp["N"][:, 2],
        "Y_0": comp["Y"][:, 0], "N_0": comp["N"][:, 0]}, columns=list(CYCLE_COLUMNS))
    t_kept = np.concatenate([ts[(ts >= a) & (ts < b)] for a, b in zip(edges[:-1], edges[1:],
                                                                       strict=True)])
    period = cycle_average(t_kept, f, {k: np.concatenate(v) for k, v in whole.items()})
    more = [f"{n_c} whole steady PMM cycles kept, {cyc.dropped} dropped (ramp-in, ramp-out or "
            "outside the steady window)"]
    if math.isfinite(length_m):
        more.append(f"omega' = {omega * length_m / U:.3g}")
    return CaptiveRun(
        run=run, file=file, test=setting.test, plane=setting.plane, speed=U,
        drift_deg=setting.drift_deg, rudder_deg=setting.rudder_deg, radius_m=math.nan,
        frequency_hz=f, amplitude_m=y0, cycles_used=n_c, rows=_rows_frame(rows),
        cycles=cycles, period=period, notes=(*notes, *more), cov=np.array(covs),
    )


def cycle_average(ts: np.ndarray, frequency_hz: float, series: Mapping[str, np.ndarray],
                  bins: int = PERIOD_BINS) -> pd.DataFrame:
    """The cycle-averaged period: each series averaged in ``bins`` phase bins of the cycles
    starting at ts = 0 (:data:`PERIOD_COLUMNS`; ``t`` [s] the bins' centres)."""
    # loaded on use: pandas only for the tables (the workers start light)
    import pandas as pd

    phase = np.mod(ts * frequency_hz, 1.0)
    k = np.minimum((phase * bins).astype(int), bins - 1)
    count = np.bincount(k, minlength=bins).astype(float)
    count[count == 0] = np.nan
    centre = (np.arange(bins) + 0.5) / bins
    out: dict[str, np.ndarray] = {"phase": centre, "t": centre / frequency_hz}
    for name in PERIOD_COLUMNS[2:]:
        out[name] = np.bincount(k, weights=np.asarray(series[name], dtype=float),
                                minlength=bins) / count
    return pd.DataFrame(out, columns=list(PERIOD_COLUMNS))


# ============================================================================ the one entry

def load_trace(t: np.ndarray, fs: float, fx: np.ndarray, fy: np.ndarray, mz: np.ndarray,
               balance_x_m: float = 0.0, sway: np.ndarray | None = None,
               yaw: np.ndarray | None = None, rate_hz: float = TRACE_HZ) -> np.ndarray:
    """The whole run's measured loads and motion at ``rate_hz`` for its plots.

    Columns :data:`TRACE_COLUMNS`: ``t`` [s]; X, Y [N] the zeroed balance forces in body
    axes and N [N m] the moment about the reference point P (mz + (x_B - x_P) fy,
    ``balance_x_m`` = x_B - x_P [m]; 0: about the balance point), the model's inertia not
    removed (what the balance measured); the PMM ``sway`` [m] and ``yaw`` [deg] (NaN when
    absent). Each row is the mean of the samples of
    one 1/``rate_hz`` block (the loads are not low-passed; the block mean is their filter).
    """
    t = np.asarray(t, dtype=float)
    n = t.size
    nan = np.full(n, np.nan)
    cols = [t, np.asarray(fx, float), np.asarray(fy, float),
            np.asarray(mz, float) + balance_x_m * np.asarray(fy, float),
            nan if sway is None else np.asarray(sway, float),
            nan if yaw is None else np.asarray(yaw, float)]
    step = max(1, int(round(fs / rate_hz)))
    starts = np.arange(0, n, step)
    counts = np.diff(np.append(starts, n))
    return np.column_stack([np.add.reduceat(c, starts) / counts for c in cols])



def model_inertia(model: Any, plane: str, moment_ref: str = "origin"
                  ) -> tuple[Inertia, tuple[str, ...]]:
    """:class:`Inertia` of the protocol's model for a run in ``plane`` (vertical: I_yG from
    ``iyy_kg_m2``, else ``izz_kg_m2`` with a note), its derivatives referred to the point
    ``moment_ref`` names (:func:`reference_x`); RunError when mass or inertia is missing."""
    def value(name: str) -> float | None:
        x = getattr(model, name, None)
        return None if x is None else float(x)

    notes: tuple[str, ...] = ()
    inertia = value("izz_kg_m2")
    if plane == "vertical":
        iyy = value("iyy_kg_m2")
        if iyy is None and inertia is not None:
            notes = ("a vertical-plane run: [model] iyy_kg_m2 not given, izz_kg_m2 used as "
                     "the pitch inertia",)
        inertia = iyy if iyy is not None else inertia
    mass, xg = value("mass_kg"), value("xg_m")
    if mass is None or inertia is None or xg is None:
        raise RunError("a captive run needs [model] mass_kg, izz_kg_m2 and xg_m to remove "
                       "the model's inertia")
    bx = value("balance_x_m")
    bx = 0.0 if bx is None else bx
    return Inertia(mass, inertia, xg, bx, reference_x(moment_ref, bx)), notes


def body_forces(channels: Mapping[str, np.ndarray], drift: float
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(fx, fy, mz) of a captive run's channels: fx, fy as recorded, or rotated from drag and
    lift (:func:`drag_lift_to_body`); RunError naming a missing channel."""
    if "mz" not in channels:
        raise RunError("the file has no mz channel (the balance's yaw moment), which a captive "
                       "run needs")
    if "fx" in channels and "fy" in channels:
        return (np.asarray(channels["fx"], float), np.asarray(channels["fy"], float),
                np.asarray(channels["mz"], float))
    if "drag" in channels and "lift" in channels:
        fx, fy = drag_lift_to_body(channels["drag"], channels["lift"], drift)
        return fx, fy, np.asarray(channels["mz"], float)
    if "fy" in channels:
        raise RunError("the file has fy but no fx channel (the balance's axial force), which a "
                       "captive run needs beside fy and mz")
    raise RunError("the file has neither fx and fy nor drag and lift channels, which a "
                   "captive run needs")


def reduce_captive(
    raw_channels: Mapping[str, np.ndarray], fs: float, steady_window: tuple[int, int],
    row: Mapping[str, Any], model: Any, *, run: int = 0, file: str = "",
    min_cycles: int = MIN_CYCLES, amplitude_tolerance: float = PMM_TOLERANCE,
    zero_var: Mapping[str, float] | None = None, moment_ref: str = "origin",
) -> CaptiveRun:
    """One captive run reduced: the day pipeline's entry.

    Parameters
    ----------
    raw_channels : mapping
        The run's conditioned channels (:func:`condition_captive`): ``t`` [s], ``U``
        [m/s], ``fx``, ``fy`` [N] (or ``drag``, ``lift`` [N], carriage axes), ``mz`` [N m];
        PMM runs ``sway`` [m] and ``yaw`` [deg] (absent: 0).
    fs : float
        Sample rate [Hz].
    steady_window : tuple of int
        The carriage's steady window [i0, i1) (indices).
    row : mapping
        The run-sheet row (test, plane, drift_deg, rudder_deg, radius_m, pmm_amplitude_m,
        pmm_frequency_hz).
    model : object
        The protocol's Model (mass_kg, izz_kg_m2, xg_m, balance_x_m, iyy_kg_m2, length_m).
    min_cycles, amplitude_tolerance : int, float
        The protocol's ``[captive] min_cycles`` and ``amplitude_tolerance`` [-]
        (:func:`pmm_run`).
    zero_var : mapping, optional
        Variance of each balance channel's zero at the steady window [N^2, N^2 m^2]
        (:func:`condition_captive`'s ``zero_var``); absent: 0.
    moment_ref : {"origin", "balance"}
        The protocol's ``[captive] moment_ref``: the loads, the regressors and the
        derivatives refer to O, or to the balance point (:func:`reference_x`).

    Raises
    ------
    RunError
        One sentence for a run that cannot be used.
    """
    setting = RunSetting.from_row(row)
    inertia, notes = model_inertia(model, setting.plane, moment_ref)
    t = np.asarray(raw_channels["t"], dtype=float)
    U = np.asarray(raw_channels["U"], dtype=float)
    i0, i1 = steady_window
    if not (0 <= i0 < i1 <= t.size) or i1 - i0 < STATIC_BLOCKS * 2:
        raise RunError("the steady window is too short for a captive run")
    fx, fy, mz = body_forces(raw_channels, math.radians(setting.drift_deg))
    z_var = load_zero_variance(zero_var or {}, math.radians(setting.drift_deg),
                               inertia.moment_arm_m)
    sway, yaw = raw_channels.get("sway"), raw_channels.get("yaw")
    trace = load_trace(t, fs, fx, fy, mz, inertia.moment_arm_m, sway, yaw)
    if setting.test in STATIC_TESTS:
        return replace(static_run(t, U, fx, fy, mz, (i0, i1), setting, inertia, run=run,
                                  file=file, notes=notes, zero_var=z_var), trace=trace)
    if "sway" not in raw_channels:
        raise RunError("the file has no sway channel, which a PMM run needs")
    if setting.test in ("yaw", "yaw_drift") and yaw is None:
        raise RunError("the file has no yaw channel, which a PMM yaw run needs")
    cr = pmm_run(t, U, fx, fy, mz, np.asarray(raw_channels["sway"], float),
                 None if yaw is None else np.asarray(yaw, float), (i0, i1), setting,
                 inertia, length_m=float(getattr(model, "length_m", math.nan)), run=run,
                 file=file, notes=notes, min_cycles=min_cycles, tolerance=amplitude_tolerance,
                 zero_var=z_var)
    return replace(cr, trace=trace)


def condition_captive(
    t: np.ndarray, channels: Mapping[str, np.ndarray], fs: float, *,
    cutoff_hz: float = 4.0, order: int = 4, still: tuple[tuple[int, int], tuple[int, int] | None],
    steady: tuple[int, int] | None = None, said: list[str] | None = None,
    zero_var: dict[str, float] | None = None,
) -> dict[str, np.ndarray]:
    """The channels conditioned: ``U``, ``sway`` and ``yaw`` low-passed (one zero-phase
    filter); the balance channels zeroed, not filtered: the recorded samples less a straight
    line between the still windows before and after the run, fitted to the low-passed channel
    (:func:`towtank.signal.conditioning.zero_line`). The steady means and the PMM cycles'
    harmonics are the loads' filters; a low-pass would carry a ramp's transient (a step of r')
    into the first and last kept cycles.
    ``channels`` holds ``U`` and the balance and PMM channels; returns them with ``t``.

    With the ``steady`` window [i0, i1) and a post-run still window, each balance channel's
    drift is judged as the drag's is (:func:`towtank.signal.drift.check_drift`): a balance
    that had not settled raises RunError, a large drift's sentence is appended to ``said``.
    With ``steady``, ``zero_var`` receives each balance channel's zero variance at the
    steady window's middle (:func:`zero_variance`).
    """
    names = list(channels)
    filt = conditioning.lowpass(np.column_stack([channels[k] for k in names]), fs, cutoff_hz,
                                order)
    out: dict[str, np.ndarray] = {"t": np.asarray(t, dtype=float)}
    pre, post = still
    for j, name in enumerate(names):
        x = filt[:, j]
        if name in ("fx", "fy", "mz", "drag", "lift"):
            if steady is not None and post is not None and post[1] - post[0] >= 2:
                base = float(np.mean(x[pre[0]:pre[1]]))
                load = abs(float(np.mean(x[steady[0]:steady[1]])) - base)
                notes: list[str] = []
                check_drift(out["t"], x, pre, post, load, name, None, notes, notes)
                if said is not None:
                    said += notes[:1]
            if steady is not None and zero_var is not None:
                mid = 0.5 * (float(out["t"][steady[0]]) + float(out["t"][steady[1] - 1]))
                zero_var[name] = zero_variance(x, out["t"], pre, post, mid)
            zero, _, _ = conditioning.zero_line(t, x, pre, post)
            x = np.asarray(channels[name], dtype=float) - zero
        out[name] = x
    return out
