"""Whole synthetic days: run sheets, day plans, truth files, protocols and the shipped sample
days."""

from __future__ import annotations

import datetime as _dt
import io
import json
import math
import re
import shutil
import zipfile
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import asdict, dataclass, field, fields, replace
from pathlib import Path
from typing import Any, Literal

import numpy as np
import openpyxl
import pandas as pd

from towtank import __version__ as _TOWTANK_VERSION
from towtank.testing.instruments import (
    LabChannels,
    Noise,
    csv_bytes,
    medium_properties,
    simulate_run,
    write_run_file,
)
from towtank.testing.layouts import LAYOUTS
from towtank.testing.layouts import NO_SPEED_WINDOW_MARGIN_S as m
from towtank.testing.truth import (
    FIN_SAMPLE_DATE,
    FIN_SAMPLE_SEED,
    GENERATOR_VERSION,
    HULL_SAMPLE_DATE,
    HULL_SAMPLE_SEED,
    ChannelStyle,
    Config,
    FileFormat,
    FinTruth,
    HullTruth,
    SheetFormat,
    TareTruth,
    sut2_hull_truth,
)

SHEET_COLUMNS = (
    "run",
    "file",
    "config",
    "test",
    "angle_deg",
    "speed_nominal",
    "accel_nominal",
    "tare_group",
    "water_temp_C",
    "status",
    "remarks",
)

_FIXED_TIME = _dt.datetime(2024, 5, 21, 9, 0, 0)


def _xlsx_bytes(rows: Sequence[Mapping[str, Any]], columns: Sequence[str]) -> bytes:
    """An .xlsx workbook with one sheet ``runs``, byte-for-byte reproducible."""
    wb = openpyxl.Workbook()
    ws = wb.active
    ws.title = "runs"
    ws.append(list(columns))
    for row in rows:
        ws.append([None if row.get(c) in ("", None) else row.get(c) for c in columns])
    wb.properties.creator = "towtank.testing.synthetic"
    wb.properties.created = _FIXED_TIME
    buf = io.BytesIO()
    wb.save(buf)
    return pinned_xlsx(buf.getvalue())


def pinned_xlsx(data: bytes) -> bytes:
    """An .xlsx file's bytes with its save time and zip entries' dates pinned (reproducible)."""
    stamp = _FIXED_TIME.strftime("%Y-%m-%dT%H:%M:%SZ").encode()
    out = io.BytesIO()
    with zipfile.ZipFile(io.BytesIO(data)) as src, \
            zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as dst:
        for info in src.infolist():
            data = src.read(info.filename)
            if info.filename == "docProps/core.xml":
                data = re.sub(
                    rb"(<dcterms:(?:modified|created)[^>]*>)[^<]*(</dcterms:(?:modified|created)>)",
                    rb"\g<1>" + stamp + rb"\g<2>",
                    data,
                )
            zi = zipfile.ZipInfo(info.filename, date_time=(1980, 1, 1, 0, 0, 0))
            zi.compress_type = zipfile.ZIP_DEFLATED
            zi.external_attr = info.external_attr
            dst.writestr(zi, data)
    return out.getvalue()


def write_run_sheet(
    rows: Iterable[Mapping[str, Any]], path: str | Path, columns: Sequence[str] = SHEET_COLUMNS
) -> Path:
    """Write a run sheet (docs/formats.md §2) as ``.csv`` or ``.xlsx``, one row per run.

    Parameters
    ----------
    rows : iterable of mapping
        One mapping per run with (at least) the keys of ``columns``; missing ones are left blank.
    path : str or pathlib.Path
        ``.csv`` or ``.xlsx``.
    columns : sequence of str
        Column order; default the docs/formats.md §2 columns.

    Returns
    -------
    pathlib.Path
    """
    path = Path(path)
    table = [dict(r) for r in rows]
    path.parent.mkdir(parents=True, exist_ok=True)
    suffix = path.suffix.lower()
    if suffix == ".xlsx":
        path.write_bytes(_xlsx_bytes(table, columns))
    elif suffix == ".csv":
        frame = pd.DataFrame([{c: r.get(c, "") for c in columns} for r in table], columns=columns)
        path.write_bytes(csv_bytes(frame))
    else:
        raise ValueError(f"{path.name}: a run sheet must be .csv or .xlsx.")
    return path


# ============================================================================== day builders
@dataclass(frozen=True)
class RunSpec:
    """One planned run of a day.

    Parameters
    ----------
    config : {"hull", "fin", "sting"}
    angle_deg : float
        Angle to the tow [deg].
    speed : float
        Set speed [m/s].
    accel : float
        Set acceleration [m/s^2].
    test : {"steady", "accel"}, default "steady"
    tare_group : str, default "A"
    status : {"ok", "void"}, default "ok"
    remarks : str, default ""
    plateau_s : float, optional
        Plateau length [s]; default as long as the tank allows (at most 8 s).
    decel : float, optional
        Deceleration [m/s^2].
    water_temp_C : float, optional
        Water temperature of the run [degC]; default drawn around the day's temperature.
    run : int, optional
        Run number; default the position in the plan, from 1.
    """

    config: Config
    angle_deg: float
    speed: float
    accel: float
    test: str = "steady"
    tare_group: str = "A"
    status: str = "ok"
    remarks: str = ""
    plateau_s: float | None = None
    decel: float | None = None
    water_temp_C: float | None = None
    run: int | None = None


def hull_day_plan() -> list[RunSpec]:
    """The SUT-2-style hull day: sting tares, hull at 0-15 deg, accelerated and transverse runs.

    Run count per config: sting 12 (7 steady, 5 accelerated), hull 30 (19 steady at 0-15 deg
    including 3 repeats, 1 voided run, 3 accelerated at 0 deg, 5 steady and 2 accelerated
    transverse tows at 90 deg); 42 in all.
    """
    low = 0.15  # [m/s^2] set acceleration of the low-speed steady runs
    high = 0.5  # [m/s^2] set acceleration of the steady runs at 0.8 m/s and above
    plan: list[RunSpec] = []
    for v in (0.1, 0.2, 0.3):
        plan.append(RunSpec("sting", 0.0, v, low))
    for v in (0.8, 1.2, 1.6, 2.0):
        plan.append(RunSpec("sting", 0.0, v, high))
    for acc in (0.25, 0.5, 1.0):
        plan.append(RunSpec("sting", 0.0, 2.0, acc, test="accel"))
    for acc in (0.1, 0.2):
        plan.append(RunSpec("sting", 0.0, 0.3, acc, test="accel"))
    speeds = (0.8, 1.2, 1.6, 2.0)
    for v in speeds:
        plan.append(RunSpec("hull", 0.0, v, high))
    for acc in (0.25, 0.5, 1.0):
        plan.append(RunSpec("hull", 0.0, 2.0, acc, test="accel"))
    plan.append(
        RunSpec(
            "hull",
            5.0,
            1.6,
            high,
            status="void",
            remarks="carriage stopped early",
            plateau_s=0.6,
        )
    )
    for ang in (5.0, 10.0, 15.0):
        for v in speeds:
            plan.append(RunSpec("hull", ang, v, high))
    plan.append(RunSpec("hull", 0.0, 1.2, high, remarks="repeat"))
    plan.append(RunSpec("hull", 0.0, 2.0, high, remarks="repeat"))
    plan.append(RunSpec("hull", 10.0, 1.6, high, remarks="repeat"))
    for v in (0.10, 0.15, 0.20, 0.25, 0.30):
        plan.append(RunSpec("hull", 90.0, v, low, remarks="transverse tow"))
    for acc in (0.1, 0.2):
        plan.append(RunSpec("hull", 90.0, 0.3, acc, test="accel", remarks="transverse tow"))
    return plan


def fin_day_plan() -> list[RunSpec]:
    """The NACA 0015 fin day: post tares, then the fin at 0-35 deg at four speeds.

    Angles 0, 2.5, 5 and 7.5 deg (the zero-lift check and points in the linear range, so that
    every speed keeps three or more distinct angles below its stall, which is 7.5-10 deg at
    these Re, for a lift slope with an intercept and residual degrees of freedom), then 10-35
    deg in 5 deg steps into and past stall. Run count per config: sting (the fin's post) 5
    (4 steady, 1 accelerated), fin 40 (10 angles x 4 speeds, steady); 45 in all. All in tare
    group "post".
    """
    acc = 0.5
    plan = [RunSpec("sting", 0.0, v, acc, tare_group="post") for v in (0.8, 1.5, 2.0, 2.7)]
    plan.append(RunSpec("sting", 0.0, 2.0, 1.0, test="accel", tare_group="post"))
    for ang in (0.0, 2.5, 5.0, 7.5, 10.0, 15.0, 20.0, 25.0, 30.0, 35.0):
        for v in (1.0, 1.5, 2.0, 2.5):
            plan.append(RunSpec("fin", ang, v, acc, tare_group="post"))
    return plan


@dataclass
class DayTruth:
    """Everything a synthetic day was made from, as written to ``truth.json``.

    ``coefficients`` and ``primes`` are the hull's at the day's nominal water (``water``);
    ``runs`` maps run number to the per-run truth of :func:`simulate_run` plus sheet fields.
    """

    name: str
    seed: int
    generator_version: str
    fs: float
    file_format: str
    channel_style: str
    tdms_dtype: str | None
    water: dict[str, Any]
    noise: Noise
    tares: dict[str, TareTruth]
    hull: HullTruth | None = None
    fin: FinTruth | None = None
    channels: LabChannels | None = None
    coefficients: dict[str, float] | None = None
    primes: dict[str, float] | None = None
    runs: dict[int, dict[str, Any]] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dict (run numbers as string keys)."""
        out: dict[str, Any] = {}
        for f in fields(self):
            value = getattr(self, f.name)
            if f.name == "runs":
                value = {str(k): v for k, v in value.items()}
            elif f.name == "tares":
                value = {k: asdict(v) for k, v in value.items()}
            elif dataclass_instance(value):
                value = asdict(value)
            out[f.name] = value
        out["towtank_version"] = _TOWTANK_VERSION
        return out


def dataclass_instance(value: Any) -> bool:
    """True for a dataclass instance (not a class)."""
    return hasattr(value, "__dataclass_fields__") and not isinstance(value, type)


def _json_default(value: Any) -> Any:
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, Path):
        return str(value)
    raise TypeError(f"{type(value).__name__} is not JSON serialisable")


def write_truth(truth: DayTruth | Mapping[str, Any], path: str | Path) -> Path:
    """Write a day's truth as JSON (``truth.json``).

    Parameters
    ----------
    truth : DayTruth or mapping
    path : str or pathlib.Path
    """
    path = Path(path)
    data = truth.to_dict() if isinstance(truth, DayTruth) else dict(truth)
    text = json.dumps(data, indent=2, default=_json_default, allow_nan=False)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text + "\n", encoding="utf-8")
    return path


def load_truth(path: str | Path) -> dict[str, Any]:
    """Read ``truth.json`` back (a plain dict; run numbers are string keys of ``runs``).

    Parameters
    ----------
    path : str or pathlib.Path
        The file, or the day's directory holding it.
    """
    path = Path(path)
    if path.is_dir():
        path = path / "truth.json"
    return json.loads(path.read_text(encoding="utf-8"))


def _run_temperatures(
    plan: Sequence[RunSpec],
    temperature_C: float,
    spread_C: tuple[float, float] | None,
    rng: np.random.Generator,
) -> list[float]:
    """Water temperature per run [degC]: a slow warming across the day, to 0.1 degC."""
    n = len(plan)
    jitter = rng.normal(0.0, 0.03, size=n)
    if spread_C is None:
        drawn = np.full(n, float(temperature_C))
    else:
        lo, hi = spread_C
        frac = np.arange(n) / max(n - 1, 1)
        drawn = np.clip(
            temperature_C + lo + (hi - lo) * frac + jitter, temperature_C + lo, temperature_C + hi
        )
        drawn = np.round(drawn, 1)
    return [
        float(spec.water_temp_C) if spec.water_temp_C is not None else float(x)
        for spec, x in zip(plan, drawn, strict=True)
    ]


def _make_day(
    out_dir: str | Path,
    plan: Sequence[RunSpec],
    *,
    name: str,
    seed: int,
    fs: float,
    file_format: FileFormat,
    sheet_format: SheetFormat,
    channel_style: ChannelStyle,
    channels: LabChannels | None,
    noise: Noise,
    temperature_C: float,
    temperature_spread_C: tuple[float, float] | None,
    water_type: str,
    hull: HullTruth | None,
    fin: FinTruth | None,
    tares: Mapping[str, TareTruth],
    accel_channel: bool,
    tank_length_m: float,
    tdms_dtype: Literal["float64", "float32"] = "float64",
    date: str | _dt.date | None = None,
) -> DayTruth:
    if file_format not in ("csv", "csv.gz", "tdms", *LAYOUTS):
        raise ValueError(f"file_format must be 'csv', 'csv.gz', 'tdms' or one of "
                         f"{', '.join(LAYOUTS)}, not {file_format!r}.")
    if sheet_format not in ("csv", "xlsx"):
        raise ValueError(f"sheet_format must be 'csv' or 'xlsx', not {sheet_format!r}.")
    out_dir = Path(out_dir)
    data_dir = out_dir / "data"
    data_dir.mkdir(parents=True, exist_ok=True)
    if channel_style == "lab" and channels is None:
        channels = LabChannels()

    test_date = _iso_date(date)
    numbers = [spec.run if spec.run is not None else i + 1 for i, spec in enumerate(plan)]
    if len(set(numbers)) != len(numbers):
        raise ValueError("Run numbers of the plan must be unique.")

    streams = np.random.SeedSequence(seed).spawn(len(plan) + 1)
    day_rng = np.random.default_rng(streams[0])
    temps = _run_temperatures(plan, temperature_C, temperature_spread_C, day_rng)

    nominal = medium_properties(temperature_C, water_type)
    rho0, nu0 = float(nominal.rho), float(nominal.nu)
    water_cache: dict[float, Any] = {}
    truth = DayTruth(
        name=name,
        seed=int(seed),
        generator_version=GENERATOR_VERSION,
        fs=float(fs),
        file_format=file_format,
        channel_style=channel_style,
        tdms_dtype=tdms_dtype if file_format == "tdms" else None,
        water={"type": water_type, "temperature_C": float(temperature_C), "rho": rho0, "nu": nu0},
        noise=noise,
        tares=dict(tares),
        hull=hull,
        fin=fin,
        channels=channels if channel_style == "lab" else None,
    )
    if hull is not None:
        truth.coefficients = hull.coefficients(rho0)
        truth.primes = hull.primes(rho0)

    rows: list[dict[str, Any]] = []
    for spec, number, temp, stream in zip(plan, numbers, temps, streams[1:], strict=True):
        if temp not in water_cache:
            water_cache[temp] = medium_properties(temp, water_type)
        tare = tares.get(spec.tare_group, TareTruth.none())
        frame, run_truth = simulate_run(
            spec.config,
            spec.angle_deg,
            spec.speed,
            spec.accel,
            hull=hull,
            tare=tare,
            fin=fin,
            noise=noise,
            water=water_cache[temp],
            fs=fs,
            rng=np.random.default_rng(stream),
            decel=spec.decel,
            plateau_s=spec.plateau_s,
            tank_length_m=tank_length_m,
            accel_channel=accel_channel,
        )
        file_name = f"run_{number:03d}.{LAYOUTS.get(file_format, file_format)}"
        write_run_file(
            frame,
            data_dir / file_name,
            channel_style=channel_style,
            channels=channels,
            tdms_dtype=tdms_dtype,
            layout=file_format if file_format in LAYOUTS else None,
        )
        row = {
            "run": int(number),
            "file": file_name,
            "config": spec.config,
            "test": spec.test,
            "angle_deg": float(spec.angle_deg),
            "speed_nominal": float(spec.speed),
            "accel_nominal": float(spec.accel),
            "tare_group": spec.tare_group,
            "water_temp_C": temp,
            "status": spec.status,
            "remarks": spec.remarks,
        }
        rows.append(row)
        truth.runs[int(number)] = {**row, "water_temp_C": temp, **run_truth}

    columns: tuple[str, ...] = SHEET_COLUMNS
    if file_format == "no-speed":  # the lab's steady windows: the set speed has no trace
        columns += ("window_start_s", "window_end_s")
        rows = [{**row,
                 "window_start_s": round(truth.runs[row["run"]]["t_plateau_start"] + m, 3),
                 "window_end_s": round(truth.runs[row["run"]]["t_plateau_end"] - m, 3)}
                for row in rows]
    if file_format == "lvm-appended":  # the run is the file's second acquisition
        columns += ("segment",)
        rows = [{**row, "segment": 2} for row in rows]
    if test_date is not None:  # the sheet only: truth.json is the same with or without it
        columns += ("date",)
        rows = [{**row, "date": test_date} for row in rows]
    write_run_sheet(rows, out_dir / f"run_sheet.{sheet_format}", columns)
    write_truth(truth, out_dir / "truth.json")
    return truth


def _iso_date(date: str | _dt.date | None) -> str | None:
    """A test date as ISO text, YYYY-MM-DD (None stays None)."""
    if date is None:
        return None
    if isinstance(date, _dt.datetime):
        return date.date().isoformat()
    if isinstance(date, _dt.date):
        return date.isoformat()
    try:
        return _dt.date.fromisoformat(str(date).strip()).isoformat()
    except ValueError:
        raise ValueError(f"date must be an ISO date, YYYY-MM-DD, not {date!r}.") from None


def make_hull_day(
    out_dir: str | Path,
    *,
    seed: int = HULL_SAMPLE_SEED,
    fs: float = 200.0,
    file_format: FileFormat = "csv.gz",
    sheet_format: SheetFormat = "xlsx",
    channel_style: ChannelStyle = "lab",
    noise: Noise | None = None,
    temperature_C: float = 18.0,
    runs: Sequence[RunSpec] | None = None,
    hull: HullTruth | None = None,
    tares: Mapping[str, TareTruth] | None = None,
    channels: LabChannels | None = None,
    accel_channel: bool = False,
    temperature_spread_C: tuple[float, float] | None = (-0.2, 0.3),
    water_type: str = "fresh",
    tank_length_m: float = 100.0,
    date: str | _dt.date | None = None,
) -> DayTruth:
    """Write a synthetic SUT-2 hull day: ``data/run_NNN.*``, ``run_sheet.*``, ``truth.json``.

    Parameters
    ----------
    out_dir : str or pathlib.Path
        The day's directory (created).
    seed : int
        Seed of the day; each run gets its own stream from it.
    fs : float, default 200.0
        Sampling rate [Hz].
    file_format : {"csv", "csv.gz", "tdms"}, default "csv.gz"
    sheet_format : {"csv", "xlsx"}, default "xlsx"
    channel_style : {"canonical", "lab"}, default "lab"
        Lab style writes the load cells in volts under the names of :class:`LabChannels`.
    noise : Noise, optional
        Default ``Noise()``.
    temperature_C : float, default 18.0
        Nominal water temperature [degC]; the truth coefficients are at this density.
    runs : sequence of RunSpec, optional
        The run plan; default :func:`hull_day_plan`.
    hull : HullTruth, optional
        Default :func:`sut2_hull_truth` at the nominal density.
    tares : mapping of str to TareTruth, optional
        Mounting force per tare group; default ``{"A": TareTruth()}``. Groups not listed
        have no mounting force.
    channels : LabChannels, optional
        Lab names and calibrations (lab style).
    accel_channel : bool, default False
        Record an accel channel.
    temperature_spread_C : (float, float) or None, default (-0.2, 0.3)
        Run temperatures rise across the day from ``temperature_C + lo`` to ``+ hi`` [degC]
        (rounded to 0.1 degC); None keeps every run at ``temperature_C``.
    water_type : str, default "fresh"
        The medium: ``"fresh"``, ``"sea"`` or ``"air"`` (a rig in air at 101325 Pa and 50 %
        relative humidity: forces and truth coefficients at the air's density, the protocol
        ``[water] type = "air"``).
    tank_length_m : float, default 100.0
        Tank length [m].
    date : str or datetime.date, optional
        Test date; if given, the run sheet gets a ``date`` column (ISO ``YYYY-MM-DD``,
        docs/formats.md §2: other columns are kept), from which the report takes its test
        date. Default: no such column.

    Returns
    -------
    DayTruth
    """
    nominal = medium_properties(temperature_C, water_type)
    hull = sut2_hull_truth(float(nominal.rho)) if hull is None else hull
    return _make_day(
        out_dir,
        hull_day_plan() if runs is None else list(runs),
        name="SUT-2 quarter-scale hull, synthetic day",
        seed=seed,
        fs=fs,
        file_format=file_format,
        sheet_format=sheet_format,
        channel_style=channel_style,
        channels=channels,
        noise=Noise() if noise is None else noise,
        temperature_C=temperature_C,
        temperature_spread_C=temperature_spread_C,
        water_type=water_type,
        hull=hull,
        fin=None,
        tares={"A": TareTruth()} if tares is None else tares,
        accel_channel=accel_channel,
        tank_length_m=tank_length_m,
        date=date,
    )


POST_TARE = TareTruth(t2=0.12, t1=0.015, m_t=0.12, lift_t2=0.004, lift_t1=0.001, lift_m_t=0.003)
"""Default tare of the fin day's post (a stiffer, thicker mounting than the hull's sting)."""


def make_fin_day(
    out_dir: str | Path,
    *,
    seed: int = FIN_SAMPLE_SEED,
    fs: float = 200.0,
    file_format: FileFormat = "tdms",
    sheet_format: SheetFormat = "csv",
    channel_style: ChannelStyle = "canonical",
    noise: Noise | None = None,
    temperature_C: float = 18.0,
    runs: Sequence[RunSpec] | None = None,
    fin: FinTruth | None = None,
    tares: Mapping[str, TareTruth] | None = None,
    channels: LabChannels | None = None,
    accel_channel: bool = False,
    temperature_spread_C: tuple[float, float] | None = (-0.2, 0.3),
    water_type: str = "fresh",
    tank_length_m: float = 100.0,
    tdms_dtype: Literal["float64", "float32"] = "float32",
    date: str | _dt.date | None = None,
) -> DayTruth:
    """Write a synthetic NACA 0015 fin day: ``data/run_NNN.*``, ``run_sheet.*``, ``truth.json``.

    Parameters are those of :func:`make_hull_day`, except: ``fin`` (default ``FinTruth()``,
    chord 0.12 m, span 0.15 m), ``tares`` (default ``{"post": POST_TARE}``), ``runs`` (default
    :func:`fin_day_plan`), ``tdms_dtype`` (storage of the non-time TDMS channels, default
    float32 as LabVIEW's SGL, to keep the day small), and the defaults TDMS files, CSV sheet
    and canonical channel names. ``date`` as in :func:`make_hull_day` (a ``date`` column of the
    run sheet only if given).

    Returns
    -------
    DayTruth
    """
    return _make_day(
        out_dir,
        fin_day_plan() if runs is None else list(runs),
        name="NACA 0015 fin, synthetic day",
        seed=seed,
        fs=fs,
        file_format=file_format,
        sheet_format=sheet_format,
        channel_style=channel_style,
        channels=channels,
        noise=Noise() if noise is None else noise,
        temperature_C=temperature_C,
        temperature_spread_C=temperature_spread_C,
        water_type=water_type,
        hull=None,
        fin=FinTruth() if fin is None else fin,
        tares={"post": POST_TARE} if tares is None else tares,
        accel_channel=accel_channel,
        tank_length_m=tank_length_m,
        tdms_dtype=tdms_dtype,
        date=date,
    )


# ================================================================================= protocols
_BARE_KEY = set("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789_-")


def _toml_key(key: str) -> str:
    if key and set(key) <= _BARE_KEY:
        return key
    return _toml_value(key)


def _toml_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int | np.integer):
        return str(int(value))
    if isinstance(value, float | np.floating):
        x = float(value)
        if math.isnan(x):
            return "nan"
        if math.isinf(x):
            return "inf" if x > 0 else "-inf"
        return repr(x)
    if isinstance(value, str | Path):
        text = str(value)
        text = text.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n")
        text = text.replace("\t", "\\t")
        text = re.sub("[\x00-\x1f\x7f]", lambda m: f"\\u{ord(m.group()):04X}", text)
        return f'"{text}"'
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    if isinstance(value, Mapping):
        inner = ", ".join(f"{_toml_key(k)} = {_toml_value(v)}" for k, v in value.items())
        return "{ " + inner + " }" if inner else "{}"
    raise TypeError(f"{type(value).__name__} cannot be written to TOML")


def _toml_table(lines: list[str], dotted: str, table: Mapping[str, Any], inline: set[str]) -> None:
    lines.append(f"[{dotted}]")
    subtables = []
    for key, value in table.items():
        if isinstance(value, Mapping) and dotted not in inline:
            subtables.append((key, value))
        else:
            lines.append(f"{_toml_key(key)} = {_toml_value(value)}")
    for key, value in subtables:
        _toml_table(lines, f"{dotted}.{_toml_key(key)}", value, inline)


def write_protocol(
    path: str | Path,
    *,
    header: str | None = None,
    inline_tables: Iterable[str] = ("channels",),
    **sections: Mapping[str, Any],
) -> Path:
    """Write a protocol TOML (docs/formats.md §1) from nested dicts.

    Values may be str, float, int, bool, lists of those, and dicts. A dict inside a section is
    written as a sub-table (``[prototype.water]``), except in the sections named by
    ``inline_tables`` where it becomes an inline table (``drag = { column = "...", gain = 20.0 }``).

    Parameters
    ----------
    path : str or pathlib.Path
        The TOML file to write.
    header : str, optional
        Comment lines written at the top.
    inline_tables : iterable of str, default ("channels",)
    **sections : mapping
        One mapping per section, in order: ``campaign={...}, water={...}, ...``.

    Returns
    -------
    pathlib.Path
    """
    path = Path(path)
    lines: list[str] = []
    if header:
        lines.extend(f"# {line}".rstrip() for line in header.splitlines())
        lines.append("")
    inline = set(inline_tables)
    for name, table in sections.items():
        if not isinstance(table, Mapping):
            raise TypeError(f"section {name!r} must be a mapping")
        _toml_table(lines, _toml_key(name), table, inline)
        lines.append("")
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(lines).rstrip("\n") + "\n", encoding="utf-8")
    return path


def hull_protocol_sections(
    day_dir: str = "../sample_runs/sut2_hull",
    output_dir: str = "../reports/sut2_hull",
    *,
    sheet_format: SheetFormat = "xlsx",
    channel_style: ChannelStyle = "lab",
    channels: LabChannels | None = None,
    temperature_C: float = 18.0,
    water_type: str = "fresh",
) -> dict[str, dict[str, Any]]:
    """The sections of the SUT-2 hull day's protocol (paths relative to the protocol file).

    Parameters
    ----------
    day_dir, output_dir : str
        The day's directory and the output directory, relative to the protocol file.
    sheet_format : {"csv", "xlsx"}
    channel_style : {"canonical", "lab"}
        Lab style adds the ``[channels]`` mapping.
    channels : LabChannels, optional
    temperature_C : float, default 18.0
        Tank water temperature [degC].
    water_type : str, default "fresh"
        ``[water] type``: ``"fresh"``, ``"sea"`` or ``"air"``.
    """
    sections: dict[str, dict[str, Any]] = {
        "campaign": {
            "name": "SUT-2 quarter-scale hull, synthetic day",
            "run_sheet": f"{day_dir}/run_sheet.{sheet_format}",
            "data_dir": f"{day_dir}/data",
            "output_dir": output_dir,
            "reference": "remus",
        },
        "water": {"type": water_type, "temperature_C": float(temperature_C)},
        "model": {
            "name": "SUT-2 1/4 model",
            "length_m": 0.353,
            "diameter_m": 0.050,
            "mass_kg": 0.552,
            "lateral_area_m2": 0.0152,
            "wetted_area_m2": 0.0472,
            "scale": 4.0,
            "depth_m": 0.25,
            "myring": {
                "a": 0.05875,
                "b": 0.1765,
                "c": 0.11775,
                "n": 2.0,
                "theta_deg": 25.0,
                "d": 0.05,
            },
        },
        "prototype": {
            "length_m": 1.412,
            "speeds_m_s": [1.0, 1.5, 2.0, 2.5],
            "water": {"type": "sea", "temperature_C": 15.0},
        },
    }
    if channel_style == "lab":
        sections["channels"] = (channels or LabChannels()).protocol_section()
    sections["processing"] = {}
    return sections


def fin_protocol_sections(
    day_dir: str = "../sample_runs/naca0015_fin",
    output_dir: str = "../reports/naca0015_fin",
    *,
    sheet_format: SheetFormat = "csv",
    fin: FinTruth | None = None,
    temperature_C: float = 18.0,
) -> dict[str, dict[str, Any]]:
    """The sections of the NACA 0015 fin day's protocol (canonical channels, no [model]).

    Parameters
    ----------
    day_dir, output_dir : str
        Relative to the protocol file.
    sheet_format : {"csv", "xlsx"}
    fin : FinTruth, optional
    temperature_C : float, default 18.0
        Tank water temperature [degC].
    """
    fin = fin or FinTruth()
    return {
        "campaign": {
            "name": "NACA 0015 fin, synthetic day",
            "run_sheet": f"{day_dir}/run_sheet.{sheet_format}",
            "data_dir": f"{day_dir}/data",
            "output_dir": output_dir,
        },
        "water": {"type": "fresh", "temperature_C": float(temperature_C)},
        "fin": {
            "chord_m": fin.chord,
            "span_m": fin.span,
            "section": fin.section,
            "x_m": -0.61,
            "linear_max_deg": 10.0,
        },
        "processing": {},
    }


def write_sample_protocols(protocols_dir: str | Path) -> list[Path]:
    """Write ``sut2_hull.toml`` and ``naca0015_fin.toml`` for the sample days.

    Parameters
    ----------
    protocols_dir : str or pathlib.Path
        Directory of the protocols; the sample days are expected in ``../sample_runs``.
    """
    protocols_dir = Path(protocols_dir)
    note = "Generated by towtank.testing.synthetic.write_sample_protocols; data: write_sample_days."
    hull = hull_protocol_sections()
    # the tested model is the vehicle: predicted beside measured, model.json (docs/formats.md)
    hull["vehicle"] = {"name": "SUT-2 1/4 model", "hull": "myring", "speed_m_s": 1.0}
    return [
        write_protocol(
            protocols_dir / "sut2_hull.toml",
            header="Synthetic SUT-2 quarter-scale hull day (sample_runs/sut2_hull).\n" + note,
            **hull,
        ),
        write_protocol(
            protocols_dir / "naca0015_fin.toml",
            header="Synthetic NACA 0015 fin day (sample_runs/naca0015_fin).\n" + note,
            **fin_protocol_sections(),
        ),
    ]


_SAMPLE_README = """\
# Sample runs (synthetic)

Generated by `write_sample_days` of `towtank.testing.synthetic` (version {version}); do not edit by
hand, regenerate. Each day holds `data/` (one file per run), a run sheet (with the test date in its
`date` column) and `truth.json` with the exact truth the data were made from (coefficients, per-run
plateau forces, tares, phases).

- `sut2_hull/`: SUT-2 quarter-scale hull, {hull_n} runs at {hull_fs:g} Hz, gzipped CSV in the lab's
  channel names (load cells in volts), run sheet .xlsx; protocol `protocols/sut2_hull.toml`.
- `naca0015_fin/`: NACA 0015 fin (chord 0.12 m, span 0.15 m), {fin_n} runs at {fin_fs:g} Hz,
  TDMS with canonical channel names, run sheet .csv; protocol `protocols/naca0015_fin.toml`.
"""


def write_sample_days(
    root: str | Path, *, protocols_dir: str | Path | None = None
) -> dict[str, DayTruth]:
    """Regenerate the shipped sample days ``root/sut2_hull`` and ``root/naca0015_fin``.

    Both directories are replaced as a whole; seeds are fixed, so the files are reproducible.
    Each run sheet carries its day's test date in a ``date`` column (:data:`HULL_SAMPLE_DATE`,
    :data:`FIN_SAMPLE_DATE`), which the report prints.

    Parameters
    ----------
    root : str or pathlib.Path
        The ``sample_runs`` directory.
    protocols_dir : str or pathlib.Path, optional
        If given, also write the two protocols there.

    Returns
    -------
    dict
        ``{"sut2_hull": DayTruth, "naca0015_fin": DayTruth}``.
    """
    root = Path(root)
    root.mkdir(parents=True, exist_ok=True)
    for name in ("sut2_hull", "naca0015_fin"):
        if (root / name).exists():
            shutil.rmtree(root / name)
    hull = make_hull_day(root / "sut2_hull", date=HULL_SAMPLE_DATE)
    fin = make_fin_day(root / "naca0015_fin", date=FIN_SAMPLE_DATE)
    (root / "README.md").write_text(
        _SAMPLE_README.format(
            version=GENERATOR_VERSION,
            hull_n=len(hull.runs),
            hull_fs=hull.fs,
            fin_n=len(fin.runs),
            fin_fs=fin.fs,
        ),
        encoding="utf-8",
    )
    if protocols_dir is not None:
        write_sample_protocols(protocols_dir)
    return {"sut2_hull": hull, "naca0015_fin": fin}


#: The runs of :func:`reading_day_plan`, numbered as in :func:`hull_day_plan`.
READING_DAY_RUNS = (1, 4, 5, 6, 7, 13, 14, 15, 16, 21, 22)


def reading_day_plan() -> list[RunSpec]:
    """Eleven runs of :func:`hull_day_plan` with their numbers in the full day: five steady
    sting tares (0.1-2.0 m/s), the hull at 0 deg (0.8-2.0 m/s) and runs 21 and 22 at 5 deg.

    A day for the tests of how one run's file (or the sheet) is read: it processes in half
    the time of the full day and gives the hull's drag, but not every coefficient.
    """
    plan = hull_day_plan()
    return [replace(plan[n - 1], run=n) for n in READING_DAY_RUNS]
