"""The instruments of the synthetic runs: balance imperfections (zero offset, drift, noise,
vibration, mains hum), a run's recorded channels, and the run files as labs write them."""

from __future__ import annotations

import gzip
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np
import pandas as pd
from nptdms import ChannelObject, GroupObject, RootObject, TdmsWriter

from towtank.reference.air import air_properties
from towtank.reference.water import water_properties
from towtank.testing.labchannels import LabChannels
from towtank.testing.layouts import (
    balance_frame,
    layout_channels,
    write_carriage_log,
    write_layout,
    write_zero_file,
)
from towtank.testing.numbertext import csv_text
from towtank.testing.profiles import plan_profile, sample_times
from towtank.testing.truth import (
    REFERENCE_FS,
    ChannelStyle,
    Config,
    FinTruth,
    HullTruth,
    TareTruth,
    model_forces,
    sut2_hull_truth,
    tare_forces,
)


@dataclass(frozen=True)
class Noise:
    """Imperfections of the recorded channels. White-noise sigmas are given at 1 kHz and scaled
    by sqrt(fs / 1000), so that the noise density is the same at any sampling rate.

    Parameters
    ----------
    zero_offset : float, default 0.3
        Balance zero offset drawn uniformly in [-zero_offset, zero_offset] per run and channel [N].
    drift : float, default 0.005
        Linear drift over the whole run, total uniformly in [-drift, drift] [N].
    balance_sigma : float, default 0.005
        White balance noise at 1 kHz [N].
    vibration_per_speed : float, default 0.0015
        Carriage vibration amplitude per unit speed [N per m/s] (3 mN at 2 m/s).
    vibration_hz : tuple of float, default (8.0, 15.0)
        Range of the vibration frequency drawn per run [Hz].
    hum_amplitude : float, default 0.002
        Mains hum amplitude [N].
    hum_hz : float, default 50.0
        Mains frequency [Hz].
    speed_hum_amplitude : float, default 0.0
        Mains hum on the recorded speed [m/s], at ``hum_hz``; its phase is the sum of the two
        force channels' hum phases (uniform, and no new draw: a seed gives the same run).
    speed_sigma : float, default 0.001
        White noise of the recorded speed at 1 kHz [m/s].
    speed_quantum : float, default 1e-4
        Resolution of the recorded speed [m/s]; 0 for none.
    accel_sigma : float, default 0.02
        White noise of the optional accel channel at 1 kHz [m/s^2].
    wake : float, default 0.0
        A wake (or ringing) still on the balance when the carriage stops, as a fraction of the
        plateau drag [-]; it decays exponentially after the stop.
    wake_decay_s : float, default 3.0
        Time constant of the wake's decay [s].
    """

    zero_offset: float = 0.3
    drift: float = 0.005
    balance_sigma: float = 0.005
    vibration_per_speed: float = 0.0015
    vibration_hz: tuple[float, float] = (8.0, 15.0)
    hum_amplitude: float = 0.002
    hum_hz: float = 50.0
    speed_hum_amplitude: float = 0.0
    speed_sigma: float = 0.001
    speed_quantum: float = 1e-4
    accel_sigma: float = 0.02
    wake: float = 0.0
    wake_decay_s: float = 3.0

    @classmethod
    def quiet(cls) -> Noise:
        """No noise, no zero offset, no drift: recorded channels equal the truth."""
        return cls(
            zero_offset=0.0,
            drift=0.0,
            balance_sigma=0.0,
            vibration_per_speed=0.0,
            hum_amplitude=0.0,
            speed_sigma=0.0,
            speed_quantum=0.0,
            accel_sigma=0.0,
        )


# ==================================================================================== forces

def _as_rng(rng: np.random.Generator | int | None) -> np.random.Generator:
    if isinstance(rng, np.random.Generator):
        return rng
    return np.random.default_rng(0 if rng is None else rng)


def medium_properties(temperature_C: float, water_type: str) -> Any:
    """The medium's properties: ITTC water, or air (``"air"``: CIPM-2007 at 101325 Pa and
    50 % relative humidity, Sutherland viscosity; the protocol's defaults)."""
    if water_type == "air":
        return air_properties(temperature_C)
    return water_properties(temperature_C, water_type)


def simulate_run(
    config: Config,
    angle_deg: float,
    speed: float,
    accel: float,
    *,
    hull: HullTruth | None = None,
    tare: TareTruth | None = None,
    fin: FinTruth | None = None,
    noise: Noise | None = None,
    water: Any = None,
    fs: float = 1000.0,
    rng: np.random.Generator | int | None = None,
    jerk: float = 4.0,
    decel: float | None = None,
    plateau_s: float | None = None,
    pre_still_s: float = 3.0,
    post_still_s: float = 3.0,
    tank_length_m: float = 100.0,
    accel_channel: bool = False,
    temperature_C: float = 18.0,
    water_type: str = "fresh",
) -> tuple[pd.DataFrame, dict[str, Any]]:
    """Simulate one run: the recorded channels and the run's exact truth.

    drag_raw = D_model + F_tare + zero + drift(t) + vibration + hum + white noise, the same for
    lift with its own offset, drift and phases; speed = U + white noise, quantised; the optional
    accel channel = a + white noise.

    Parameters
    ----------
    config : {"hull", "fin", "sting"}
        What is mounted; ``"sting"`` records the mounting (tare) force alone.
    angle_deg : float
        Angle to the tow [deg].
    speed : float
        Set speed [m/s].
    accel : float
        Set acceleration [m/s^2].
    hull : HullTruth, optional
        Default :func:`sut2_hull_truth` at the run's density (hull runs).
    tare : TareTruth, optional
        Mounting force; default none (sting runs then record only zero, drift and noise).
    fin : FinTruth, optional
        Default :class:`FinTruth` (fin runs).
    noise : Noise, optional
        Default ``Noise()`` (realistic); ``Noise.quiet()`` for exact channels.
    water : object with ``rho`` [kg/m^3] and ``nu`` [m^2/s], optional
        Default ``towtank.reference.water.water_properties(temperature_C, water_type)``.
    fs : float, default 1000.0
        Sampling rate [Hz].
    rng : numpy.random.Generator or int, optional
        Random source, or a seed for one (default seed 0).
    jerk, decel, plateau_s, pre_still_s, post_still_s, tank_length_m
        Carriage profile, see :func:`plan_profile` ([m/s^3], [m/s^2], [s], [s], [s], [m]).
    accel_channel : bool, default False
        Record an ``accel`` channel.
    temperature_C : float, default 18.0
        Water temperature [degC], used only when ``water`` is not given.
    water_type : str, default "fresh"
        ``fresh``, ``sea`` or ``air`` (at 101325 Pa and 50 % relative humidity), used only
        when ``water`` is not given.

    Returns
    -------
    frame : pandas.DataFrame
        Columns ``time`` [s], ``speed`` [m/s], (``accel`` [m/s^2],) ``drag`` [N], ``lift`` [N].
    truth : dict
        Per-run truth: set speed and acceleration, phase boundaries [s], plateau model drag and
        lift (zero, drift, tare removed) [N], plateau tare [N], inertia along the tow [kg],
        plateau coefficients and Reynolds number, water, realised offsets and drifts [N].
    """
    if config not in ("hull", "fin", "sting"):
        raise ValueError(f"config must be 'hull', 'fin' or 'sting', not {config!r}.")
    rng = _as_rng(rng)
    noise = Noise() if noise is None else noise
    if water is None:
        water = medium_properties(temperature_C, water_type)
    rho, nu = float(water.rho), float(water.nu)
    if config == "hull" and hull is None:
        hull = sut2_hull_truth(rho)
    if config == "fin" and fin is None:
        fin = FinTruth()
    tare = TareTruth.none() if tare is None else tare

    plan = plan_profile(
        speed,
        accel,
        jerk=jerk,
        pre_still_s=pre_still_s,
        post_still_s=post_still_s,
        plateau_s=plateau_s,
        decel=decel,
        tank_length_m=tank_length_m,
    )
    t = sample_times(plan.duration, fs)
    u, a = plan.evaluate(t)

    d_model, l_model = model_forces(config, angle_deg, u, a, hull=hull, fin=fin, rho=rho, nu=nu)
    d_tare, l_tare = tare_forces(u, a, tare)
    draws = _draw_imperfections(noise, t.size, rng, accel_channel)
    truth = _plateau_truth(config, angle_deg, plan, hull=hull, fin=fin, tare=tare, rho=rho,
                           nu=nu, fs=fs, t=t, draws=draws)
    wake = np.zeros_like(t)
    if noise.wake:
        t_stop = float(plan.phases()["t_decel_end"])
        after = t >= t_stop
        wake[after] = (noise.wake * truth["drag_model"]
                       * np.exp(-(t[after] - t_stop) / noise.wake_decay_s))
    frame = _recorded_channels(t, u, a, d_model + d_tare + wake, l_model + l_tare, noise,
                               draws, fs)
    truth["inertia_drag"] = truth["m_eff"] * plan.accel
    truth["tare_m_t"] = float(tare.m_t)
    return frame, truth


def _draw_imperfections(
    noise: Noise, n: int, rng: np.random.Generator, accel_channel: bool
) -> dict[str, Any]:
    """A run's random draws, always in this order (so a seed gives the same run whatever the
    amplitudes): zero offsets and drifts [-1, 1) of drag and lift, vibration frequency [Hz],
    four phases [rad], white noise of drag, lift and speed, and of the accel channel."""
    zero = noise.zero_offset * rng.uniform(-1.0, 1.0, size=2)
    drift = noise.drift * rng.uniform(-1.0, 1.0, size=2)
    vib_hz = float(rng.uniform(*noise.vibration_hz))
    phases = rng.uniform(0.0, 2.0 * np.pi, size=4)
    white = rng.standard_normal((3, n))
    accel_white = rng.standard_normal(n) if accel_channel else None
    return {"zero": zero, "drift": drift, "vib_hz": vib_hz, "phases": phases, "white": white,
            "accel_white": accel_white}


def _recorded_channels(
    t: np.ndarray,
    u: np.ndarray,
    a: np.ndarray,
    drag: np.ndarray,
    lift: np.ndarray,
    noise: Noise,
    draws: dict[str, Any],
    fs: float,
) -> pd.DataFrame:
    """The recorded channels: forces [N] plus zero, drift, vibration, hum and white noise;
    speed [m/s] plus white noise, quantised; the optional accel [m/s^2] plus white noise."""
    n = t.size
    scale = math.sqrt(fs / REFERENCE_FS)
    ramp = t / t[-1] if n > 1 else np.zeros_like(t)
    w_vib = 2.0 * np.pi * draws["vib_hz"] * t
    w_hum = 2.0 * np.pi * noise.hum_hz * t
    vib_amp = noise.vibration_per_speed * np.abs(u)
    zero, drift, phases, white = draws["zero"], draws["drift"], draws["phases"], draws["white"]

    def disturbance(k: int) -> np.ndarray:
        return (
            zero[k]
            + drift[k] * ramp
            + vib_amp * np.sin(w_vib + phases[k])
            + noise.hum_amplitude * np.sin(w_hum + phases[2 + k])
            + noise.balance_sigma * scale * white[k]
        )

    speed_rec = u + noise.speed_sigma * scale * white[2]
    if noise.speed_hum_amplitude:
        speed_rec = speed_rec + noise.speed_hum_amplitude * np.sin(w_hum + phases[2] + phases[3])
    if noise.speed_quantum > 0.0:
        speed_rec = np.round(speed_rec / noise.speed_quantum) * noise.speed_quantum
    columns: dict[str, np.ndarray] = {"time": t, "speed": speed_rec}
    if draws["accel_white"] is not None:
        columns["accel"] = a + noise.accel_sigma * scale * draws["accel_white"]
    columns["drag"] = drag + disturbance(0)
    columns["lift"] = lift + disturbance(1)
    return pd.DataFrame(columns)


def _plateau_truth(
    config: Config,
    angle_deg: float,
    plan: Any,
    *,
    hull: HullTruth | None,
    fin: FinTruth | None,
    tare: TareTruth,
    rho: float,
    nu: float,
    fs: float,
    t: np.ndarray,
    draws: dict[str, Any],
) -> dict[str, Any]:
    """The run's truth on its plateau, through the very same force functions as the samples
    (so it equals the plateau samples bit for bit), and the realised imperfections."""
    v_arr, zero_arr = np.array([plan.speed]), np.array([0.0])
    d_plat, l_plat = model_forces(
        config, angle_deg, v_arr, zero_arr, hull=hull, fin=fin, rho=rho, nu=nu
    )
    td_plat, tl_plat = tare_forces(v_arr, zero_arr, tare)
    q = 0.5 * rho * plan.speed**2
    truth: dict[str, Any] = {
        "config": config,
        "angle_deg": float(angle_deg),
        "speed": plan.speed,
        "accel": plan.accel,
        "decel": plan.decel,
        "jerk": plan.jerk_up,
        "jerk_decel": plan.jerk_down,
        "fs": float(fs),
        "n_samples": int(t.size),
        "duration_s": float(t[-1]),
        "distance_m": plan.distance,
        **plan.phases(),
        "rho": rho,
        "nu": nu,
        "drag_model": float(d_plat[0]),
        "lift_model": float(l_plat[0]),
        "tare_drag": float(td_plat[0]),
        "tare_lift": float(tl_plat[0]),
        "m_eff": 0.0,
        "cd": None,
        "cl": None,
        "reynolds": None,
        "zero_drag": float(draws["zero"][0]),
        "zero_lift": float(draws["zero"][1]),
        "drift_drag": float(draws["drift"][0]),
        "drift_lift": float(draws["drift"][1]),
        "vibration_hz": draws["vib_hz"],
    }
    if config == "hull":
        assert hull is not None
        truth["m_eff"] = float(hull.m_eff(angle_deg))
        truth["cd"] = float(d_plat[0] / (q * hull.frontal_area))
        truth["cl"] = float(l_plat[0] / (q * hull.frontal_area))
        truth["reynolds"] = plan.speed * hull.length / nu
        if abs(angle_deg) == 90.0:
            truth["cd_lateral"] = float(hull.cd90)
    elif config == "fin":
        assert fin is not None
        truth["m_eff"] = float(fin.m_fin)
        truth["cd"] = float(d_plat[0] / (q * fin.area))
        truth["cl"] = float(l_plat[0] / (q * fin.area))
        truth["reynolds"] = plan.speed * fin.chord / nu
    return truth


# =================================================================================== writers
_DECIMALS = {"time": 6, "speed": 6, "accel": 5, "drag": 6, "lift": 6}
_VOLT_DECIMALS = 8
_UNITS = {"time": "s", "speed": "m/s", "accel": "m/s^2", "drag": "N", "lift": "N"}


def _clean(x: np.ndarray, decimals: int) -> np.ndarray:
    return np.round(np.asarray(x, dtype=float), decimals) + 0.0  # + 0.0 turns -0.0 into 0.0


def to_file_frame(
    frame: pd.DataFrame,
    channel_style: ChannelStyle = "canonical",
    channels: LabChannels | None = None,
) -> pd.DataFrame:
    """The columns as written to a run file: renamed, converted to volts, rounded.

    Rounding: time and speed to 1e-6, accel to 1e-5, forces to 1e-6 N, volts to 1e-8 V (far
    below the noise).

    Parameters
    ----------
    frame : pandas.DataFrame
        Canonical channels from :func:`simulate_run` [SI].
    channel_style : {"canonical", "lab"}
        Canonical names and units, or the lab's names with forces in volts.
    channels : LabChannels, optional
        The lab's names and calibrations (default ``LabChannels()``).
    """
    if channel_style not in ("canonical", "lab"):
        raise ValueError(f"channel_style must be 'canonical' or 'lab', not {channel_style!r}.")
    out = {}
    lab = channels or LabChannels()
    for col in frame.columns:
        values = frame[col].to_numpy(dtype=float)
        if channel_style == "canonical":
            out[col] = _clean(values, _DECIMALS[col])
        elif col in ("drag", "lift"):
            gain = lab.drag_gain if col == "drag" else lab.lift_gain
            offset = lab.drag_offset if col == "drag" else lab.lift_offset
            out[getattr(lab, col)] = _clean(values / gain + offset, _VOLT_DECIMALS)
        else:
            out[getattr(lab, col)] = _clean(values, _DECIMALS[col])
    return pd.DataFrame(out)


#: zlib level of a generated ``.csv.gz``: the fastest, for a slightly larger file (the data
#: are the same at any level).
GZIP_LEVEL = 1


def csv_bytes(frame: pd.DataFrame) -> bytes:
    """The frame as a run file's CSV bytes: a header row, no index, ``\n`` line ends."""
    return csv_text(frame).encode("utf-8")


def write_run_file(
    frame: pd.DataFrame,
    path: str | Path,
    *,
    channel_style: ChannelStyle = "canonical",
    channels: LabChannels | None = None,
    tdms_dtype: Literal["float64", "float32"] = "float64",
    layout: str | None = None,
) -> Path:
    """Write one run file; the format follows the name: ``.csv``, ``.csv.gz`` or ``.tdms``,
    or ``layout`` (one of :data:`towtank.testing.layouts.LAYOUTS`: other labs' files).

    CSV has a header row; ``.csv.gz`` is gzip with a zero timestamp (same bytes for the same
    data); TDMS has one group ``data`` with one channel per column, time included (time always
    as float64, the other channels as ``tdms_dtype``).

    Parameters
    ----------
    frame : pandas.DataFrame
        Canonical channels from :func:`simulate_run` [SI].
    path : str or pathlib.Path
        Where to write.
    channel_style : {"canonical", "lab"}
    channels : LabChannels, optional
    tdms_dtype : {"float64", "float32"}, default "float64"
        Storage of the non-time TDMS channels; float32 (LabVIEW SGL) halves the file and keeps
        ~7 significant digits, far below the noise.
    layout : str, optional
        Write the file as another lab's software does (:mod:`towtank.testing.layouts`).

    Returns
    -------
    pathlib.Path
    """
    if tdms_dtype not in ("float64", "float32"):
        raise ValueError(f"tdms_dtype must be 'float64' or 'float32', not {tdms_dtype!r}.")
    path = Path(path)
    if layout is not None:
        lab = layout_channels(layout, channels or LabChannels()) or LabChannels()
        out = to_file_frame(frame, channel_style, lab)
        units = {}
        for canon in frame.columns:
            col = canon if channel_style == "canonical" else getattr(lab, canon)
            lab_force = channel_style == "lab" and canon in ("drag", "lift")
            units[col] = "V" if lab_force else _UNITS[canon]
        time_col = "time" if channel_style == "canonical" else lab.time
        if layout in ("two-cell", "matrix"):
            if channel_style != "lab":
                raise ValueError(f"the {layout} layout records load cells: channel_style='lab'")
            out = balance_frame(layout, out, lab)
        if layout == "zero-file":
            write_zero_file(out, path, time_col,
                            "speed" if channel_style == "canonical" else lab.speed)
        if layout == "no-speed":
            out = out.drop(columns=["speed" if channel_style == "canonical" else lab.speed])
        if layout in ("speed-log", "position-log"):
            speed_col = "speed" if channel_style == "canonical" else lab.speed
            write_carriage_log(layout, out, path, time_col, speed_col)
            out = out.drop(columns=[speed_col])
        return write_layout(layout, out, path, time_col, units)
    out = to_file_frame(frame, channel_style, channels)
    name = path.name.lower()
    path.parent.mkdir(parents=True, exist_ok=True)
    if name.endswith(".csv.gz"):
        path.write_bytes(gzip.compress(csv_bytes(out), compresslevel=GZIP_LEVEL, mtime=0))
    elif name.endswith(".csv"):
        path.write_bytes(csv_bytes(out))
    elif name.endswith(".tdms"):
        lab = channels or LabChannels()
        units = {}
        for canon in frame.columns:
            col = canon if channel_style == "canonical" else getattr(lab, canon)
            lab_force = channel_style == "lab" and canon in ("drag", "lift")
            units[col] = "V" if lab_force else _UNITS[canon]
        objects = [
            RootObject(properties={"name": path.stem, "generator": "towtank.testing.synthetic"}),
            GroupObject("data"),
        ]
        time_col = "time" if channel_style == "canonical" else lab.time
        for col in out.columns:
            dtype = np.float64 if col == time_col else np.dtype(tdms_dtype)
            objects.append(
                ChannelObject(
                    "data",
                    col,
                    out[col].to_numpy(dtype=np.float64).astype(dtype),
                    properties={"unit_string": units[col]},
                )
            )
        with TdmsWriter(str(path)) as writer:
            writer.write_segment(objects)
    else:
        raise ValueError(f"{path.name}: a run file must be .csv, .csv.gz or .tdms.")
    return path


#: The run's random draws and its recorded channels, for the other generators (captive days).
draw_imperfections = _draw_imperfections
recorded_channels = _recorded_channels
