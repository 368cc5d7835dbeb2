"""towtank as a library: the functions a notebook or a script calls.

These are the command line's own steps, callable one by one::

    import towtank

    day = towtank.process_day("protocols/sut2_hull.toml", out="reports/day1")
    day.coefficients          # coefficients.csv as a DataFrame
    day.runs, day.table("fins"), day.table("scaling"), day.warnings, day.rejected

    protocol = towtank.load_protocol("protocols/sut2_hull.toml")
    raw = towtank.read_run("sample_runs/sut2_hull/data/run_020.csv.gz", protocol)
    red = towtank.reduce_run(raw, protocol, run=20)
    red.drag_mean_raw, red.speed_mean, red.windows

Every function works from a plain script (with or without ``if __name__ == "__main__":``),
from ``python -c``, ``python -`` and in IPython or Jupyter: where worker processes cannot be
started safely for the calling program, the runs are reduced in this process (see
:func:`towtank.runtime.parallel.main_is_importable`). Nothing is printed; problems come back
as the DayResult's ``warnings`` and ``rejected``, or as :class:`towtank.errors.ProtocolError`
for an unusable protocol or run sheet (what the command line turns into exit status 2).
"""

from __future__ import annotations

import datetime as dt
import math
import numbers
import warnings
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pandas as pd

from towtank.errors import ProtocolError, RunError
from towtank.ingest.protocol import Protocol
from towtank.ingest.protocol import load_protocol as _load
from towtank.ingest.protocol_types import CAPTIVE_TESTS
from towtank.ingest.runfile import RawRun
from towtank.ingest.runsheet import read_run_sheet
from towtank.reduce.run import (
    RunReduction,
    load_record,
    reduce_read,
    sheet_segment,
    zeroed_record,
)

if TYPE_CHECKING:
    from towtank.results import DayResult


def load_protocol(path: str | Path) -> Protocol:
    """Read and check a protocol file (TOML).

    Parameters
    ----------
    path : str or Path
        The campaign's protocol; relative paths inside it are relative to its folder.

    Returns
    -------
    Protocol
        The validated settings: ``.campaign``, ``.model``, ``.water``, ``.channels``,
        ``.processing`` and the other sections of docs/formats.md.

    Raises
    ------
    ProtocolError
        A missing or misspelt key, a value out of range or a path that does not exist, in one
        sentence naming the key.
    """
    return _load(path)


def _protocol(protocol: str | Path | Protocol) -> Protocol:
    _check_protocol(protocol)
    return load_protocol(protocol) if isinstance(protocol, str | Path) else protocol


def _check_protocol(protocol: Any) -> None:
    """TypeError (one sentence) unless ``protocol`` is a protocol file's path or a Protocol."""
    if not isinstance(protocol, str | Path | Protocol):
        raise TypeError("protocol must be the path of a protocol file (str or Path) or a "
                        f"Protocol from towtank.load_protocol, not {type(protocol).__name__}")


def _check_whole(value: Any, name: str, least: int) -> None:
    """TypeError or ValueError (one sentence) unless ``value`` is None or a whole number of at
    least ``least``."""
    if value is None:
        return
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise TypeError(f"{name} must be a whole number (int) or None, not "
                        f"{type(value).__name__} {value!r}")
    if value < least:
        raise ValueError(f"{name} must be at least {least}, not {value}")


def _check_date(date: Any) -> str | None:
    """``date`` as YYYY-MM-DD text: TypeError or ValueError (one sentence) for anything but
    None, a date or such a text of a date that exists."""
    if date is None or isinstance(date, dt.datetime):
        return None if date is None else date.date().isoformat()
    if isinstance(date, dt.date):
        return date.isoformat()
    if not isinstance(date, str):
        raise TypeError(f"date must be a text YYYY-MM-DD or a datetime.date, not "
                        f"{type(date).__name__}")
    try:
        return dt.datetime.strptime(date.strip(), "%Y-%m-%d").date().isoformat()
    except ValueError:
        raise ValueError(f"date {date!r} is not a date that exists, written YYYY-MM-DD"
                         ) from None


def process_day(
    protocol: str | Path | Protocol,
    out: str | Path | None = None,
    jobs: int | None = None,
    report: bool = True,
    *,
    cache: bool = True,
    date: str | None = None,
) -> DayResult:
    """Reduce a test day and, with ``out``, write its tables and reports.

    Parameters
    ----------
    protocol : str, Path or Protocol
        The protocol file, or a protocol already loaded with :func:`load_protocol`.
    out : str or Path, optional
        Output folder. None (the default) writes nothing: the results are only returned.
        Give the protocol's ``output_dir`` explicitly to write where ``towtank process``
        writes.
    jobs : int, optional
        Worker processes; default the protocol's ``[processing] jobs``, else the
        ``TOWTANK_JOBS`` environment variable, else every core.
        ``jobs=1`` reduces in this process.
    report : bool, default True
        With ``out``: also write report.xlsx, report.pdf and figures/ (else the CSV tables and
        provenance.json only).
    cache : bool, default True
        With ``out``: keep and reuse reduced runs in ``out/.cache``.
    date : str or datetime.date, optional
        Test date printed in the report (YYYY-MM-DD, a date that exists), instead of the
        protocol's or the sheet's.

    Returns
    -------
    DayResult
        ``.runs`` (runs.csv), ``.coefficients`` (coefficients.csv), ``.table("fins")``
        (fins.csv), ``.table("scaling")`` (scaling.csv) as DataFrames; ``.hull``, ``.fins``,
        ``.scaling``, ``.vehicle`` the stages' results (None when not run); ``.warnings`` (tuple of
        :class:`~towtank.results.Notice`: ``str()`` the sentence, ``.stage``, ``.run``,
        ``.file``);
        ``.rejected`` (run number -> Rejection); ``.reductions`` (run number ->
        :class:`~towtank.reduce.run.RunReduction`); ``.tares``; ``.protocol``.

    Raises
    ------
    ProtocolError
        The protocol, the run sheet or the output folder is unusable; nothing was written.
    TypeError, ValueError
        An argument of the wrong kind (``jobs="2"``, a protocol that is neither a path nor a
        Protocol) or value (``jobs=0``, ``date="2024-13-40"``), in one sentence naming it;
        nothing was read or written.

    Notes
    -----
    The day runs as ``towtank process`` runs it (:func:`towtank.runner.run_day`), and with
    ``out`` writes the same files, byte for byte: every file the day opened (a tare table,
    a hull table, ...) is among ``.inputs`` and in provenance.json, and the run is recorded
    in ``out/.cache`` so that a later ``towtank process`` of the unchanged day replays it.
    A day is never replayed here: it is always processed (the cached runs are reused). What
    the command line says on its error stream (outputs of an interrupted run put back, an
    input changed while the day was processed) comes as a :class:`UserWarning`.
    """
    # loaded on use: the runner loads the pipeline's stages, which load_protocol, read_run
    # and reduce_run do not need
    from towtank.runner import Options, run_day

    _check_protocol(protocol)
    _check_whole(jobs, "jobs", 1)
    jobs = None if jobs is None else int(jobs)
    date = _check_date(date)
    options = Options(report=report, date=date, cache=cache, jobs=jobs, replay=False,
                      quiet=True)
    run = run_day(protocol, out, options, write=out is not None)
    for note in run.notes:  # outputs put back, an input changed while the day was processed
        warnings.warn(note, UserWarning, stacklevel=2)
    assert run.day is not None  # never replayed
    return run.day


def read_run(file: str | Path, protocol: str | Path | Protocol | None = None, *,
             speed_nominal: float | None = None, segment: int | None = None,
             run: int | None = None) -> RawRun:
    """Read one run file as the day reads it: calibrated channels in SI units, checked.

    Parameters
    ----------
    file : str or Path
        The run file (.csv, .csv.gz, .tdms and the other formats of docs/formats.md).
    protocol : str, Path or Protocol, optional
        Whose ``[channels]`` map the lab's columns, ``[processing]`` set the checks, and whose
        ``[speed_log]`` and ``[zeros]`` files go with the run; default the canonical channel
        names (time, speed, drag[, lift, accel]) in SI units.
    speed_nominal : float, optional
        The run's set speed [m/s], needed when the protocol's ``[processing] speed_source``
        is ``"nominal"`` (no measured speed; ``.speed_nominal`` of the result, ``.speed`` 0);
        default the run sheet's.
    segment : int, optional
        Which acquisition of a file holding several one after another is the run, counted
        from 1; default the run sheet's ``segment``, else the protocol's ``[read] segment``.
    run : int, optional
        The run number, which names the run's carriage log and zeros file; default the run
        of the protocol's run sheet that names this file (the row with ``segment`` when
        several do), else 0. Never taken from the file's name.

    Returns
    -------
    RawRun
        ``.time`` [s], ``.speed`` [m/s], ``.drag`` [N], ``.lift`` [N] or None, ``.accel``
        [m/s²] or None, ``.fs`` [Hz], ``.sha256`` of the bytes read, ``.notes``; for a run
        whose sheet row is a captive test, ``.extra``: its balance and PMM channels (fx, fy
        [N], mz [N m], sway [m], yaw [deg]).

    Raises
    ------
    towtank.errors.RunError
        The file cannot be used; ``.reason`` is one sentence saying why.
    """
    _check_whole(segment, "segment", 1)
    _check_whole(run, "run", 0)
    path = Path(file)
    loaded = None if protocol is None else _protocol(protocol)
    row = None if loaded is None else _sheet_row(loaded, path, run=run, segment=segment)
    folder, name = path.parent, path.name
    if loaded is not None and row is not None:
        if _names(loaded, row, path):  # found as the day finds it
            folder, name = Path(loaded.campaign.data_dir), str(row["file"])
        else:  # the sheet's run of that number is another file's
            row = None
    number = run if run is not None else int(row["run"]) if row is not None else 0
    if segment is None and row is not None:
        segment = sheet_segment(row)
    nominal = None
    if loaded is not None and loaded.processing.speed_source == "nominal":
        if speed_nominal is None and row is not None:
            speed_nominal = float(row.get("speed_nominal", math.nan))
        if not (speed_nominal is not None and speed_nominal > 0):
            raise RunError(f"{path.name}: the protocol's speed_source = \"nominal\" takes the "
                           "speed from the run sheet: give read_run(..., speed_nominal=U) "
                           "[m/s]")
        nominal = speed_nominal
    raw, _stamp = load_record(loaded, folder, name, number, speed_nominal=nominal,
                              segment=segment,
                              test=str(row.get("test", "")) if row is not None else "")
    return zeroed_record(loaded, raw, folder, name, number)


def _sheet_row(protocol: Protocol, path: Path | None = None, *, run: int | None = None,
               segment: int | None = None) -> dict[str, Any] | None:
    """The protocol's run sheet row of the run: the row ``run`` when given, else the row that
    names ``path`` (with ``segment`` when given); None when there is none, or the sheet
    cannot be read."""
    try:
        sheet = read_run_sheet(protocol.campaign.run_sheet, protocol.water.temperature_C,
                               protocol.sheet, air=protocol.water.is_air)
    except ProtocolError:
        return None
    for row in sheet.to_dict("records"):
        if run is not None:
            if int(row["run"]) == run:
                return row
            continue
        if path is not None and _names(protocol, row, path) and (
                segment is None or sheet_segment(row) == segment):
            return row
    return None


def _names(protocol: Protocol, row: dict[str, Any], path: Path) -> bool:
    """Whether the sheet's ``row`` names the file ``path``."""
    file = str(row["file"]).strip()
    return bool(file) and (Path(protocol.campaign.data_dir) / file).resolve() == path.resolve()


def reduce_run(
    raw: RawRun,
    protocol: str | Path | Protocol | None = None,
    *,
    run: int = 0,
    file: str = "",
    window_s: tuple[float, float] | None = None,
    speed_nominal: float | None = None,
    accel_nominal: float | None = None,
    test: str | None = None,
) -> RunReduction:
    """Reduce one run read by :func:`read_run` as the day reduces it (before the tare is
    subtracted).

    Parameters
    ----------
    raw : RawRun
        The run's channels.
    protocol : str, Path or Protocol, optional
        Whose ``[processing]`` settings apply (filter, trims, bands) and whose ``[channels]``
        say which force channels are used; default settings without.
    run : int
        Run number, for the sentences of its notes; with a protocol whose run sheet has this
        run, the defaults of the arguments below are that row's.
    file : str
        File name, for the same (default the sheet's, else "run").
    window_s : (float, float), optional
        A hand-set steady window [s] (default the sheet's window_start_s, window_end_s).
    speed_nominal : float, optional
        Set speed [m/s], cross-checked against the measured plateau (default the sheet's,
        else none).
    accel_nominal : float, optional
        Set acceleration [m/s²], cross-checked likewise.
    test : str, optional
        The sheet's test ("steady", "accel"): an accel run without a usable
        constant-acceleration stretch is warned of, a steady run not noted for it. A captive
        test (drift, rudder, arm, sway, yaw, yaw_drift) is reduced to its loads as the day
        does, with the settings of the sheet's row ``run`` (ValueError without it). The
        sheet's row of ``run`` also gives the run's config: a fin run whose lift column holds
        no numbers is rejected (RunError), as the day rejects it.

    Returns
    -------
    RunReduction
        ``.speed_mean`` [m/s], ``.drag_mean_raw`` [N] (steady mean, zero and drift removed,
        tare still in), ``.accel_mean`` [m/s²], ``.windows`` (still_pre, accel, steady, decel,
        still_post as (start, end) in seconds), ``.notes``, ``.warnings``, ``.units`` (per
        channel: its unit and where it came from, "file", "protocol", "assumed" or
        "unknown") and the decimated samples; for a captive run ``.captive``, the arrays of
        its loads (``towtank.reduce.captive.CaptiveRun.from_arrays(run, file, .captive)``).

    Raises
    ------
    towtank.errors.RunError
        The run cannot be reduced; ``.reason`` is one sentence saying why.
    """
    if not isinstance(raw, RawRun):
        raise TypeError(f"reduce_run takes the RawRun that towtank.read_run returns, not "
                        f"{type(raw).__name__}: towtank.reduce_run(towtank.read_run(file, "
                        "protocol), protocol)")
    _check_whole(run, "run", 0)
    if window_s is not None and not (
            isinstance(window_s, tuple | list) and len(window_s) == 2
            and all(isinstance(v, numbers.Real) and not isinstance(v, bool) for v in window_s)):
        raise TypeError(f"window_s must be a (start, end) pair of times [s], not {window_s!r}")
    loaded = None if protocol is None else _protocol(protocol)
    row = None if loaded is None else _sheet_row(loaded, run=run)
    sheet = row if row is not None else {}
    kind = test if test is not None else str(sheet.get("test", ""))
    if kind in CAPTIVE_TESTS and row is None:
        raise ValueError(f"a {kind} run is reduced with the settings of its run sheet's row: "
                         "give the protocol and run=N of the row that lists it")
    if window_s is None:
        ws, we = sheet.get("window_start_s", math.nan), sheet.get("window_end_s", math.nan)
        if math.isfinite(ws) and math.isfinite(we):
            window_s = (float(ws), float(we))
    return reduce_read(
        loaded, raw, run=run, file=file or str(sheet.get("file", "")) or "run",
        window_s=window_s,
        speed_nominal=_given(speed_nominal, sheet.get("speed_nominal", math.nan)),
        accel_nominal=_given(accel_nominal, sheet.get("accel_nominal", math.nan)),
        test=kind, row=row)


def _given(value: float | None, default: float) -> float:
    return float(default) if value is None else value


def identify(model: str | Path | dict, log: str | Path | Any, estimate: list[str] | str, *,
             method: str = "ukf", start: str = "model", **kwargs: Any) -> Any:
    """Identify coefficients of a model from a manoeuvre record (``towtank identify``).

    Parameters
    ----------
    model : path or dict
        model.json (read and checked) or the model as a dict
    log : path, DataFrame or ManoeuvreLog
        The record in simulate's columns (``t_s``, states, ``rudder_deg``, ``sternplane_deg``),
        or as read (:class:`towtank.vehicle.identify_log.ManoeuvreLog`)
    estimate : list of str, or str
        model.json symbols to identify (e.g. ``["N_ur", "N_rdot", "N_uudr"]``; one symbol may
        be given alone, ``"N_ur"``)
    method : {"ukf", "ekf", "ls"}
    start : {"model", "zero"}
    **kwargs
        ``noise``, ``prior_sd``, ``check``, ``progress``, ``adequacy``, ``validate`` (a
        second record: path, DataFrame or ManoeuvreLog) of
        :func:`towtank.vehicle.identify.identify`

    Returns
    -------
    towtank.results.IdentifyResult
        ``params``, ``bse``, ``conf_int(alpha)`` (columns ``lower``, ``upper``),
        ``summary()``, ``to_frame()`` / ``table()`` (identified.csv), ``verdicts()``,
        ``adequacy`` (fit.csv) and ``fits()``.
    """

    # loaded on use: the identification (filterpy, scipy.stats) loads
    # only for identify
    from towtank.results.identify import IdentifyResult
    from towtank.results.summary import from_fit
    from towtank.vehicle.identify import identify as _identify
    from towtank.vehicle.identify_log import ManoeuvreLog, log_from_frame, read_log
    from towtank.vehicle.model import read_model

    def record(item: Any, name: str) -> ManoeuvreLog:
        if isinstance(item, pd.DataFrame):
            return log_from_frame(item, name)
        return item if isinstance(item, ManoeuvreLog) else read_log(item)

    mdl = model if isinstance(model, dict) else read_model(model)
    rec = record(log, "log")
    if kwargs.get("validate") is not None:
        kwargs["validate"] = record(kwargs["validate"], "validate")
    symbols = [estimate] if isinstance(estimate, str) else list(estimate)
    fit = _identify(mdl, rec, symbols, method=method, start=start, **kwargs)
    return from_fit(IdentifyResult, fit)


__all__ = ["ProtocolError", "identify", "load_protocol", "process_day", "read_run",
           "reduce_run"]
