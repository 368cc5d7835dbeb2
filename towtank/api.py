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

import math
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pandas as pd

from towtank.errors import ProtocolError, RunError
from towtank.ingest.protocol import Processing, Protocol, channel_map, with_output_dir
from towtank.ingest.protocol import load_protocol as _load
from towtank.ingest.runfile import RawRun, file_bytes, load_run
from towtank.ingest.speedlog import run_speed_log
from towtank.ingest.zerofile import run_zero_levels, with_zero_levels
from towtank.reduce.run import RunReduction, record_units
from towtank.reduce.run import reduce_run as _reduce

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
    return load_protocol(protocol) if isinstance(protocol, str | Path) else protocol


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
        Worker processes; default the protocol's ``[processing] jobs``, else every core.
        ``jobs=1`` reduces in this process.
    report : bool, default True
        With ``out``: also write report.xlsx, report.pdf and figures/ (else the CSV tables and
        provenance.json only).
    cache : bool, default True
        With ``out``: keep and reuse reduced runs in ``out/.cache``.
    date : str, optional
        Test date printed in the report (YYYY-MM-DD), instead of the protocol's or the sheet's.

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
    """
    # loaded on use: the pipeline loads every stage, which
    # load_protocol, read_run and reduce_run do not need
    from towtank.pipeline import process_day as _process

    path = protocol if isinstance(protocol, str | Path) else protocol.path
    loaded = _protocol(protocol)
    out_dir = None
    if out is not None:
        # the folder's note (outputs put back after an interrupted run) joins day.warnings
        loaded, out_dir = with_output_dir(loaded, Path(out))
    day = _process(
        path, protocol=loaded, jobs=jobs,
        cache_dir=Path(out_dir) / ".cache" if out_dir is not None and cache else None,
    )
    if date is not None:
        day = replace(day, report_date=date)
    if out_dir is not None:
        # loaded on use: the writers (pandas, provenance) load only here
        from towtank.report import write_outputs

        with_output_dir(loaded, out_dir, day.inputs)
        write_outputs(day, out_dir, report=report)
    return day


def read_run(file: str | Path, protocol: str | Path | Protocol | None = None, *,
             speed_nominal: float | None = None, segment: int | None = None) -> RawRun:
    """Read one run file as the day would: calibrated channels in SI units, checked.

    Parameters
    ----------
    file : str or Path
        The run file (.csv, .csv.gz, .tdms and the other formats of docs/formats.md).
    protocol : str, Path or Protocol, optional
        Whose ``[channels]`` map the lab's columns and ``[processing]`` set the checks; default
        the canonical channel names (time, speed, drag[, lift, accel]) in SI units.
    speed_nominal : float, optional
        The run's set speed [m/s], required when the protocol's ``[processing] speed_source``
        is ``"nominal"`` (no measured speed; ``.speed_nominal`` of the result, ``.speed`` 0).
    segment : int, optional
        Which acquisition of a file holding several one after another is the run, counted
        from 1 (the run sheet's ``segment``); default the protocol's ``[read] segment``.

    Returns
    -------
    RawRun
        ``.time`` [s], ``.speed`` [m/s], ``.drag`` [N], ``.lift`` [N] or None, ``.accel``
        [m/s²] or None, ``.fs`` [Hz], ``.sha256`` of the bytes read, ``.notes``.

    Raises
    ------
    towtank.errors.RunError
        The file cannot be used; ``.reason`` is one sentence saying why.
    """
    read = None
    if protocol is None:
        channels, p = channel_map({}), Processing()
    else:
        loaded = _protocol(protocol)
        channels, p, read = loaded.channels, loaded.processing, loaded.read
    path = Path(file)
    log = None
    if protocol is not None and loaded.speed_log is not None:
        digits = "".join(c for c in path.name.split(".")[0] if c.isdigit())
        log = run_speed_log(loaded.speed_log, path.parent, path.name, int(digits or 0))
    if p.speed_source == "nominal" and not (speed_nominal is not None and speed_nominal > 0):
        raise RunError(f"{path.name}: the protocol's speed_source = \"nominal\" takes the speed "
                       "from the run sheet: give read_run(..., speed_nominal=U) [m/s]")
    raw = load_run(path, channels, max_nan_gap_s=p.max_nan_gap_s,
                   max_bad_row_fraction=p.max_bad_row_fraction, do_despike=p.despike,
                   data=file_bytes(path), options=read,
                   balance=None if protocol is None else loaded.balance, speed_log=log,
                   speed_nominal=speed_nominal if p.speed_source == "nominal" else None,
                   segment=segment)
    if protocol is not None and loaded.zeros is not None:
        digits = "".join(c for c in path.name.split(".")[0] if c.isdigit())
        zeros = run_zero_levels(loaded.zeros, path.parent, path.name, int(digits or 0),
                                channels, read, loaded.balance, fs=raw.fs, taper_s=p.trim)
        assert zeros is not None
        raw = with_zero_levels(raw, *zeros)
    return raw


def reduce_run(
    raw: RawRun,
    protocol: str | Path | Protocol | None = None,
    *,
    run: int = 0,
    file: str = "",
    window_s: tuple[float, float] | None = None,
    speed_nominal: float = math.nan,
    accel_nominal: float = math.nan,
) -> RunReduction:
    """Reduce one run read by :func:`read_run` (before the tare is subtracted).

    Parameters
    ----------
    raw : RawRun
        The run's channels.
    protocol : str, Path or Protocol, optional
        Whose ``[processing]`` settings apply (filter, trims, bands); default settings without.
    run : int
        Run number, for the sentences of its notes.
    file : str
        File name, for the same.
    window_s : (float, float), optional
        A hand-set steady window [s] (the run sheet's window_start_s, window_end_s).
    speed_nominal : float
        Set speed [m/s] of the run sheet, cross-checked against the measured plateau.
    accel_nominal : float
        Set acceleration [m/s²], cross-checked likewise.

    Returns
    -------
    RunReduction
        ``.speed_mean`` [m/s], ``.drag_mean_raw`` [N] (steady mean, zero and drift removed,
        tare still in), ``.accel_mean`` [m/s²], ``.windows`` (still_pre, accel, steady, decel,
        still_post as (start, end) in seconds), ``.notes``, ``.warnings``, ``.units`` (per
        channel: its unit and where it came from, "file", "protocol", "assumed" or
        "unknown") and the decimated samples.

    Raises
    ------
    towtank.errors.RunError
        The run cannot be reduced; ``.reason`` is one sentence saying why.
    """
    processing = Processing() if protocol is None else _protocol(protocol).processing
    red = _reduce(raw, processing, run=run, file=file or "run", window_s=window_s,
                  speed_nominal=speed_nominal, accel_nominal=accel_nominal)
    return record_units(red, raw)


def identify(model: str | Path | dict, log: str | Path | Any, estimate: list[str], *,
             method: str = "ukf", start: str = "model", **kwargs: Any) -> Any:
    """Identify coefficients of a model from a manoeuvre record (``towtank identify``).

    Parameters
    ----------
    model : path or dict
        model.json (read and checked) or the model as a dict
    log : path, DataFrame or ManoeuvreLog
        The record in simulate's columns (``t_s``, states, ``rudder_deg``, ``sternplane_deg``),
        or as read (:class:`towtank.vehicle.identify_log.ManoeuvreLog`)
    estimate : list of str
        model.json symbols to identify (e.g. ``["N_ur", "N_rdot", "N_uudr"]``)
    method : {"ukf", "ekf", "ls"}
    start : {"model", "zero"}
    **kwargs
        ``noise``, ``prior_sd``, ``check``, ``progress`` of
        :func:`towtank.vehicle.identify.identify`

    Returns
    -------
    towtank.results.IdentifyResult
        ``params``, ``bse``, ``conf_int(alpha)`` (columns ``lower``, ``upper``),
        ``summary()``, ``to_frame()`` / ``table()`` (identified.csv), ``verdicts()``.
    """

    # loaded on use: the identification (filterpy, scipy.stats) loads
    # only for identify
    from towtank.results.identify import IdentifyResult
    from towtank.results.summary import from_fit
    from towtank.vehicle.identify import identify as _identify
    from towtank.vehicle.identify_log import ManoeuvreLog, log_from_frame, read_log
    from towtank.vehicle.model import read_model

    mdl = model if isinstance(model, dict) else read_model(model)
    if isinstance(log, pd.DataFrame):
        rec = log_from_frame(log, "log")
    else:
        rec = log if isinstance(log, ManoeuvreLog) else read_log(log)
    fit = _identify(mdl, rec, list(estimate), method=method, start=start, **kwargs)
    return from_fit(IdentifyResult, fit)


__all__ = ["ProtocolError", "identify", "load_protocol", "process_day", "read_run",
           "reduce_run"]
