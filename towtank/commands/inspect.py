"""``towtank inspect``: a quick look at one run file.

Reads the file (with the protocol's [channels] and [processing] when given, else canonical
channel names and default processing), reduces it exactly as the day's pipeline would but
without a sting tare, prints the phases, the steady means, the acceleration, zero and drift,
the sample rate and any notes, and writes a PNG of speed and forces with the phases shaded.
"""

from __future__ import annotations

import math
import re
import sys
import tomllib
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, TextIO

import numpy as np

from towtank.errors import ProtocolError, RunError
from towtank.ingest.describe import describe_file, protocol_block
from towtank.ingest.extensions import EXTENSIONS
from towtank.ingest.protocol import (
    ChannelMap,
    Processing,
    load_protocol,
    read_and_channels,
)
from towtank.ingest.protocol_types import CAPTIVE_TESTS, PMM_TESTS
from towtank.ingest.readers import name_list
from towtank.ingest.runfile import load_run
from towtank.ingest.speedlog import run_speed_log
from towtank.ingest.zerofile import run_zero_levels, with_zero_levels
from towtank.reduce.captive import (
    CaptiveRun,
    CycleVerdict,
    body_forces,
    cycle_verdicts,
    load_trace,
)
from towtank.reduce.captive_record import (
    CAPTIVE_LOADS,
    captive_channels,
    pmm_cycle_verdicts,
    reduce_captive_record,
)
from towtank.reduce.run import RunReduction, record_units, reduce_run, run_preview, sheet_segment
from towtank.report import style
from towtank.runtime.pathcheck import resolved

if TYPE_CHECKING:
    from towtank.report.captive_thumb import CaptiveTrace

EXIT_OK, EXIT_RUN_ERROR = 0, 1

PHASE_NAMES = {
    "still_pre": "zero (still)",
    "accel": "acceleration",
    "steady": "steady",
    "decel": "deceleration",
    "still_post": "still after",
}
RUN_EXTENSIONS = (".gz", *EXTENSIONS)


def plot_name(runfile: str | Path) -> str:
    """``run_020.csv.gz`` → ``run_020.png`` (the run file's name without its extensions)."""
    name = Path(runfile).name
    changed = True
    while changed:
        changed = False
        for ext in RUN_EXTENSIONS:
            if name.lower().endswith(ext) and len(name) > len(ext):
                name = name[: -len(ext)]
                changed = True
    return f"{name}.png"


def _fmt(x: float, unit: str, digits: int = 4) -> str:
    return "–" if x != x else f"{x:+.{digits}f} {unit}".replace("+", " ", 1)


#: Most channel names the summary line writes out (then the count of the rest).
COLUMNS_SHOWN = 24


def summary_lines(red: RunReduction, columns: tuple[str, ...] = (), t0: float = 0.0,
                  timing: str = "") -> list[str]:
    """The printed account of one reduced run (phases, means, acceleration, zero, drift).

    The phases are given in seconds from the file's first sample; a file whose time channel
    holds clock times (``t0`` [s], e.g. 1716280000.53, seconds since 1970) says so once.
    ``timing`` says where the time came from (``RawRun.time_source``). Forces are in N, or
    in their file's unit when ``red.units`` says the drag is raw (not calibrated)."""
    shift = t0 if abs(t0) > 1e5 else 0.0
    unit, source = red.units.get("drag", ("N", ""))
    force = unit if source == "raw" and unit != "unknown" else "(raw)" if source == "raw" \
        else "N"
    lines = [
        f"{red.file}: {red.n_samples} samples at {red.fs:g} Hz ({red.duration_s:.2f} s)"
        + (f"; columns: {name_list(columns, COLUMNS_SHOWN, quoted=False)}" if columns else ""),
        *([f"timing: {timing}"] if timing else []),
        *([f"units: {units_text(red.units)}"] if red.units else []),
        "phases [s]:" if not shift else
        f"phases [s from the first sample; its time stamp is {t0:.3f} s]:",
    ]
    for key, label in PHASE_NAMES.items():
        w = red.windows.get(key)
        text = (f"{w[0] - shift:7.2f} – {w[1] - shift:7.2f}" if w is not None
                else "    not found")
        extra = f"   ({red.window_source})" if key == "steady" else ""
        lines.append(f"  {label:<14s}{text}{extra}")
    lines += [
        "steady means (zero and drift removed, no tare):",
        f"  speed  {_fmt(red.speed_mean, 'm/s')}   (s.d. {red.speed_std:.4f} m/s)",
        f"  drag   {_fmt(red.drag_mean_raw, force)}   (s.d. {red.drag_std:.4f} {force})",
    ]
    if red.has_lift:
        lines.append(f"  lift   {_fmt(red.lift_mean_raw, force)}")
    lines.append(f"acceleration  {_fmt(red.accel_mean, 'm/s²', 3)}   "
                 "(mean over the constant-acceleration window)")
    zero = f"drag {_fmt(red.zero_drag, force)}"
    drift = f"drag {_fmt(red.drift_drag, force)}"
    if red.has_lift:
        zero += f", lift {_fmt(red.zero_lift, force)}"
        drift += f", lift {_fmt(red.drift_lift, force)}"
    lines += [f"zero          {zero}", f"drift         {drift}   (end minus start)"]
    if red.notes:
        lines.append("notes:")
        lines += [f"  - {n}" for n in red.notes]
    else:
        lines.append("notes: none")
    return lines


def _settings(protocol_path: str | Path | None):  # noqa: ANN202 - channels, Processing, Read
    if protocol_path is None:
        return {}, Processing(), None, None
    protocol = load_protocol(protocol_path, check_paths=False)
    return protocol.channels, protocol.processing, protocol.read, protocol


def _sheet_row(protocol, runfile: Path) -> dict:  # noqa: ANN001 - a Protocol
    """The run sheet's row of ``runfile`` (matched by path under the data folder, else by
    name), for a protocol whose speed comes from the sheet (``speed_source = "nominal"``)."""
    # loaded on use: the run sheet's reader loads pandas, which towtank inspect needs
    # only for a speed from the sheet
    from towtank.ingest.runsheet import read_run_sheet

    try:
        sheet = read_run_sheet(protocol.campaign.run_sheet, protocol.water.temperature_C,
                               protocol.sheet)
    except (ProtocolError, OSError) as exc:
        raise RunError(f"speed_source = \"nominal\" takes the speed from the run sheet, which "
                       f"cannot be read ({exc})") from None
    here = resolved(runfile)
    rows = sheet.to_dict("records")
    for match in (lambda r: isinstance(here, Path)
                  and resolved(protocol.campaign.data_dir / str(r["file"])) == here,
                  lambda r: Path(str(r["file"])).name == runfile.name):
        found = [r for r in rows if match(r)]
        if found:
            return found[0]
    raise RunError(f"{runfile.name} is not in the run sheet {protocol.campaign.run_sheet.name}, "
                   "and speed_source = \"nominal\" takes the run's speed from there")


def _sheet_segment(protocol, runfile: Path) -> int | None:  # noqa: ANN001 - a Protocol
    """The run sheet's ``segment`` of ``runfile`` (the run's acquisition in a file holding
    several), None when the sheet gives none, lists no such file or cannot be read (then
    ``[read] segment`` applies, and a file with several segments says so)."""
    try:
        return sheet_segment(_sheet_row(protocol, runfile))
    except RunError:
        return None


def _captive_row(protocol, runfile: Path) -> dict | None:  # noqa: ANN001 - Protocol | None
    """The run sheet's row of ``runfile`` when it is a captive run (its ``test`` one of
    :data:`CAPTIVE_TESTS`), else None (no protocol, no such row, a sheet that cannot be read).
    Only a protocol that can reduce captive runs ([captive], or a [model] with the balance's
    moment point or the yaw inertia) has its sheet read: a resistance day's inspect stays
    light (no pandas)."""
    if protocol is None or protocol.campaign.run_sheet is None:
        return None
    model = protocol.model
    if protocol.captive is None and (model is None or (
            model.balance_x_m is None and model.izz_kg_m2 is None)):
        return None
    try:
        row = _sheet_row(protocol, runfile)
    except RunError:
        return None
    return row if str(row.get("test", "")).strip().lower() in CAPTIVE_TESTS else None


def _run_number(runfile: Path) -> int:
    """The run number a file name holds (``run_004.csv`` → 4; 0 without one), for the
    ``{run}`` of a ``[zeros]`` pattern."""
    found = re.findall(r"\d+", plot_name(runfile))
    return int(found[-1]) if found else 0


def _describe(runfile: Path, read, out: TextIO):  # noqa: ANN001, ANN202 - ReadOptions | None
    """Print what the file holds and a ``[read]``/``[channels]`` block to paste into a
    protocol; return the block parsed as a protocol parses it (ReadOptions, channels) and each
    column's unit in the file, or None when the file cannot be described or the block names no
    channel."""
    try:
        desc = describe_file(runfile, read)
    except RunError:
        return None
    for line in desc.lines():
        print(line, file=out)
    print("a start for the protocol (check each line):", file=out)
    block = protocol_block(desc)
    print(block, file=out, end="")
    try:
        parsed = read_and_channels(tomllib.loads(block), "the proposed block")
    except (tomllib.TOMLDecodeError, ProtocolError):  # pragma: no cover - a bug of the block
        return None
    return (*parsed, {name: unit for name, unit, _ in desc.channels}) if parsed[1] else None


def _missing_channel(exc: RunError) -> bool:
    return exc.kind == "missing_channel"


def units_text(units: dict[str, tuple[str, str]]) -> str:
    """``time s (file), drag N (assumed: no unit label)``: each channel's unit in the file and
    where it came from."""
    how = {"assumed": "assumed: no unit label", "protocol": "from the protocol",
           "file": "from the file", "unknown": "from the file, not converted: taken as SI",
           "raw": "raw: not calibrated without a protocol"}
    return ", ".join(f"{c} {u} ({how.get(src, src)})" for c, (u, src) in units.items())


def raw_units(units: dict[str, tuple[str, str]], channels: dict[str, ChannelMap],
              file_units: dict[str, str]) -> dict[str, tuple[str, str]]:
    """The units of a run read without a protocol: a channel the proposed block gives a
    provisional gain is not calibrated, so it stays in its column's unit in the file (``V``),
    ``unknown`` when the file states none, with the source ``raw``."""
    out = {}
    for canon, (unit, source) in units.items():
        if source == "protocol":
            cm = channels.get(canon)
            cols = (cm.columns or (cm.column,)) if cm is not None else ()
            found = {file_units.get(c, "") for c in cols} - {""}
            unit, source = (found.pop() if len(found) == 1 else "unknown"), "raw"
        out[canon] = (unit, source)
    return out


def inspect_run(
    runfile: str | Path,
    protocol_path: str | Path | None = None,
    png: str | Path | None = None,
    *,
    out: TextIO | None = None,
    err: TextIO | None = None,
) -> int:
    """Print one run's phases and means and write its plot; the ``towtank inspect`` command.

    Parameters
    ----------
    runfile : path
        The run file, in any format the readers accept (docs/formats.md §3.1: .csv, .csv.gz,
        .txt/.dat/.asc/.tsv text, .tdms, .lvm, .mat, .h5/.hdf5).
    protocol_path : path, optional
        A protocol whose [read], [channels], [balance], [speed_log], [zeros] and [processing]
        apply as in ``process`` (``{run}`` in a file pattern: the last number of the run file's
        name); default canonical channel names and default processing. Without it, a file
        whose channels have other names is described, a ``[read]``/``[channels]`` block is
        proposed, and the run is reduced with that block (provisionally: a force in volts at
        gain 1.0 stays in volts).
    png : path, optional
        Where to write the plot; default ``<run file name without extensions>.png`` in the
        current folder (``-2``, ``-3`` … added when that name holds another run's plot). A
        file that is not inspect's plot of this run is never overwritten.
    out, err : text streams, optional
        Where to print (default stdout and stderr).

    Returns
    -------
    int
        0, or 1 when the run cannot be read or reduced (one sentence on ``err`` says why, and
        a run that was read is plotted as it is) or the plot would overwrite a file that is
        not inspect's plot of this run.
    """
    out = out or sys.stdout
    err = err or sys.stderr
    runfile = Path(runfile)
    channels, p, read, protocol = _settings(protocol_path)
    captive = _captive_row(protocol, runfile)
    raw = None
    proposed = False
    file_units: dict[str, str] = {}
    window: tuple[float, float] | None = None
    balance_test = ""  # the captive test a balance file read without a protocol is read as

    def load():  # noqa: ANN202 - RawRun
        nonlocal window
        balance = protocol.balance if protocol is not None else None
        zeros = log = nominal = segment = None
        if protocol is not None:  # as process: the run's zeros file and speed log
            number = _run_number(runfile) if captive is None else int(captive["run"])
            if captive is not None:  # as the day: the sheet's window, when it gives one
                ws, we = (captive.get("window_start_s", math.nan),
                          captive.get("window_end_s", math.nan))
                if math.isfinite(ws) and math.isfinite(we):
                    window = (float(ws), float(we))
            if p.speed_source == "nominal":  # the speed (and window) of the sheet's row
                row = _sheet_row(protocol, runfile)
                number = int(row["run"])
                nominal = float(row.get("speed_nominal", math.nan))
                if not (math.isfinite(nominal) and nominal > 0):
                    raise RunError(f"the run sheet gives {runfile.name} no speed_nominal, and "
                                   "speed_source = \"nominal\" takes the speed from there")
                ws, we = row.get("window_start_s", math.nan), row.get("window_end_s", math.nan)
                if math.isfinite(ws) and math.isfinite(we):
                    window = (float(ws), float(we))
            log = run_speed_log(protocol.speed_log, runfile.parent, runfile.name, number)

        def read_file(segment: int | None):  # noqa: ANN202 - RawRun
            return load_run(runfile, channels, max_nan_gap_s=p.max_nan_gap_s,
                            max_bad_row_fraction=p.max_bad_row_fraction, do_despike=p.despike,
                            options=read, balance=balance, speed_log=log,
                            speed_nominal=nominal, segment=segment,
                            test=balance_test if captive is None else str(captive["test"]))

        # the run sheet (pandas) is read for a segment only when the file holds several
        try:
            run = read_file(None)
            several = protocol is not None and any(
                n.startswith("segment ") and " acquisitions)" in n for n in run.notes)
        except RunError as exc:
            if protocol is None or " segment" not in exc.reason:
                raise
            run, several = None, True
        if several:
            segment = _sheet_segment(protocol, runfile)
            if segment is not None or run is None:
                run = read_file(segment)
        if protocol is not None:  # the zeros file at the run's rate, tapered as process does
            zeros = run_zero_levels(protocol.zeros, runfile.parent, runfile.name, number,
                                    channels, read, balance, fs=run.fs, taper_s=p.trim)
        return run if zeros is None else with_zero_levels(run, *zeros)

    try:
        try:
            raw = load()
        except RunError as exc:
            if protocol_path is not None or not _missing_channel(exc):
                raise
            proposal = _describe(runfile, read, out)
            if proposal is None:  # nothing recognised: the protocol must name the channels
                raise
            proposed = True
            read, channels, file_units = proposal
            try:
                raw = load()
            except RunError as again:  # no drag: is it a captive balance's file?
                if not _missing_channel(again):
                    raise
                for test in BALANCE_TESTS:  # read_file reads it as this test
                    balance_test = test
                    try:
                        raw = load()
                        break
                    except RunError:
                        continue
                else:
                    balance_test = ""
                    raise again from None
        red = reduce_run(raw, p, run=0, file=runfile.name, window_s=window)
        red = record_units(red, raw)
        if proposed:
            red = replace(red, units=raw_units(red.units, channels, file_units))
    except RunError as exc:
        reason = exc.reason.rstrip(".")
        head = "" if runfile.name in reason else f"{runfile.name}: "
        hint = ""
        if proposed:
            hint = " (read with the block proposed above)." + (
                " Complete the block, paste it into the campaign's protocol and give it with "
                "--protocol PROTOCOL.toml." if _missing_channel(exc) else "")
        elif _missing_channel(exc):
            hint = (" Give the campaign's protocol with --protocol PROTOCOL.toml, so that its "
                    "[channels] mapping names the lab's columns.")
        stop = "" if reason.endswith(("?", "!")) or hint.startswith(" (") else "."
        print(f"towtank: {head}{reason}{stop}{hint}", file=err)
        if raw is not None:  # read but not reduced: exactly when a look at it helps
            target = _target(runfile, png, err, out)
            if target is not None:
                _write_preview(raw, target, f"{head}{reason}{stop}", runfile)
                print(f"plot: {target} (the calibrated traces, no zero, no phases)", file=out)
        return EXIT_RUN_ERROR
    if proposed:
        print("reduced with the block above and default processing (provisional: check each "
              "line; a force at gain = 1.0 from volts is in volts, not newtons):", file=out)
    account: list[str] = []
    refused = None
    balance: CaptiveTrace | None = None
    if captive is not None:  # the day's captive reduction of the sheet's test
        red, account, refused = captive_account(protocol, raw, red, captive, runfile.name)
    elif balance_test:  # a balance file without its protocol: what it measured
        account, balance = balance_account(raw, red, p, balance_test)
    for line in [*summary_lines(red, raw.columns, t0=float(raw.time[0]),
                                timing=raw.time_source), *account]:
        print(line, file=out)
    if refused is not None:  # the day's one sentence for this run
        reason = refused.rstrip(".")
        head = "" if runfile.name in reason else f"{runfile.name}: "
        print(f"towtank: {head}{reason}.", file=err)
    target = _target(runfile, png, err, out)
    if target is None:  # refused to overwrite (an error), or not beside the raw data unasked
        return EXIT_RUN_ERROR if png is not None or refused is not None else EXIT_OK
    volts = any("with the stated gain 1.0" in n for n in red.notes)
    write_plot(red, target, protocol_path, runfile,
               settings=("proposed [channels]" + ("; forces in V" if volts else ""))
               if proposed else None, balance=balance)
    print(f"plot: {target}", file=out)
    return EXIT_OK if refused is None else EXIT_RUN_ERROR


def captive_account(protocol, raw, red: RunReduction, row: dict, file: str  # noqa: ANN001
                    ) -> tuple[RunReduction, list[str], str | None]:
    """A captive run reduced as the day reduces it
    (:func:`towtank.reduce.captive_record.reduce_captive_record` with the sheet's ``row``):
    the reduction with the captive notes, the printed account (:func:`captive_lines`), and
    the one sentence that rejects the run (None when the day keeps it)."""
    run = int(row["run"])
    cr: CaptiveRun | None = None
    refused = None
    try:
        arrays, notes, _ = reduce_captive_record(protocol, raw, red.windows, row, run=run,
                                                 file=file)
        cr = CaptiveRun.from_arrays(run, file, arrays)
        red = replace(red, notes=(*red.notes, *notes), captive=arrays)
    except RunError as exc:
        refused = exc.reason
    try:
        cycles = pmm_cycle_verdicts(protocol, raw, red.windows, row)
    except RunError:  # its sentence is the rejection's already
        cycles = []
    return red, captive_lines(row, cr, cycles, red.windows.get("steady")), refused


#: The captive tests a balance file read without a protocol is tried as, most channels first:
#: a yaw PMM's (sway and yaw), a sway PMM's (sway), a static run's (fx, fy, mz).
BALANCE_TESTS = ("yaw", "sway", "drift")
#: What a balance file read without its protocol cannot give, in one sentence.
BALANCE_NEEDS = ("a captive run's hydrodynamic loads need the campaign's protocol: the "
                 "model's mass_kg, izz_kg_m2 and xg_m to remove its inertia, balance_x_m to "
                 "refer the moment to O, and the run sheet's test and settings; give it with "
                 "--protocol PROTOCOL.toml")


def cycle_lines(cycles: list[CycleVerdict]) -> list[str]:
    """Every cycle of a PMM run's sway, its span [s], amplitude [m] and verdict (none: no
    lines)."""
    lines = ["  PMM cycles of the sway [s from the first sample]:"] if cycles else []
    for k, c in enumerate(cycles, 1):
        verdict = "kept" if c.kept else f"dropped: {c.reason}"
        lines.append(f"    {k:3d}  {c.start:8.2f} – {c.end:8.2f}  amplitude "
                     f"{c.amplitude:.4f} m  {verdict}")
    return lines


def balance_account(raw, red: RunReduction, p: Processing, test: str  # noqa: ANN001 - RawRun
                    ) -> tuple[list[str], CaptiveTrace | None]:
    """What a balance file read without its protocol shows: its loads zeroed as the day
    zeroes them (fx, fy [N], mz [N m] at the balance point, inertia not removed), their steady
    means, a PMM run's cycles of the sway, and the one sentence of what needs the protocol;
    with the trace its plot draws (None when the loads cannot be zeroed: no still window)."""
    # loaded on use: matplotlib only when a captive run is drawn
    from towtank.report.captive_thumb import CaptiveTrace

    found = [c for c in (*CAPTIVE_LOADS, "sway", "yaw") if c in raw.extra]
    lines = [f"balance file: {', '.join(found)} (a captive run, read without its protocol)"]
    try:
        chans = captive_channels(raw, red.windows, p, [])
        fx, fy, mz = body_forces(chans, 0.0)
    except RunError as exc:
        return [*lines, f"  loads not zeroed: {exc.reason}", f"note: {BALANCE_NEEDS}."], None
    steady = red.windows.get("steady")
    t = chans["t"]
    if steady is not None:
        m = (t >= steady[0]) & (t <= steady[1])
        lines.append("  steady means at the balance point (zero and drift removed, inertia "
                     "not removed):")
        lines.append(f"    fx {_fmt(float(np.mean(fx[m])), 'N')}   "
                     f"fy {_fmt(float(np.mean(fy[m])), 'N')}   "
                     f"mz {_fmt(float(np.mean(mz[m])), 'N m')}")
    trace = load_trace(t, raw.fs, fx, fy, mz, 0.0, chans.get("sway"), chans.get("yaw"))
    kept: list[tuple[float, float]] = []
    if "sway" in chans and steady is not None:
        i0, i1 = (int(np.searchsorted(t, steady[0])), int(np.searchsorted(t, steady[1],
                                                                          side="right")))
        verdicts = cycle_verdicts(t, chans["sway"], (i0, i1))
        lines += cycle_lines(verdicts)
        kept = [(c.start, c.end) for c in verdicts if c.kept]
    lines.append(f"note: {BALANCE_NEEDS}.")
    return lines, CaptiveTrace(trace, tuple(kept), test, about="the balance point")


def _sheet_value(row: dict, name: str) -> float:
    try:
        return float(row.get(name, math.nan))
    except (TypeError, ValueError):
        return math.nan


def _pm(value: float, se: float, unit: str) -> str:
    text = _fmt(value, unit)
    return text if se != se else f"{text} ± {se:.2g}"


#: The rows of a captive run's loads, as inspect names them.
COMPONENT_NAMES = {"mean": "mean", "sin": "in phase (sin)", "cos": "quadrature (cos)"}


def captive_lines(row: dict, cr: CaptiveRun | None, cycles: list[CycleVerdict],
                  steady: tuple[float, float] | None) -> list[str]:
    """The printed account of a captive run: the sheet's test and settings, the steady window
    [s], the hydrodynamic loads X, Y [N] and N [N m] about O with the inertia removed (each
    component ± its standard error), and for a PMM run every cycle kept or dropped with why,
    the measured frequency [Hz] and sway amplitude [m] against the sheet's and cycles_used.
    ``cr`` is None for a run the day rejects (its sentence is printed apart)."""
    test = str(row.get("test", "")).strip().lower()
    plane = str(row.get("plane") or "horizontal").strip().lower() or "horizontal"
    setting = [f"{name} {_sheet_value(row, key):g} {unit}" for name, key, unit in (
        ("drift", "drift_deg", "deg"), ("rudder", "rudder_deg", "deg"),
        ("radius", "radius_m", "m"), ("PMM amplitude", "pmm_amplitude_m", "m"),
        ("PMM frequency", "pmm_frequency_hz", "Hz")) if math.isfinite(_sheet_value(row, key))]
    lines = [f"captive run: {test} test, {plane} plane (run {row.get('run')} of the sheet)"
             + (f"; {', '.join(setting)}" if setting else "")]
    lines.append("  steady window  " + (f"{steady[0]:.2f} – {steady[1]:.2f} s" if steady
                                        else "not found"))
    if cr is not None:
        lines.append("  hydrodynamic loads about O, inertia removed (± standard error):")
        for r in cr.rows.to_dict("records"):
            lines.append(f"    {COMPONENT_NAMES.get(r['component'], r['component']):<17s}"
                         f"X {_pm(r['X'], r['X_se'], 'N')}   Y {_pm(r['Y'], r['Y_se'], 'N')}"
                         f"   N {_pm(r['N'], r['N_se'], 'N m')}")
    if test not in PMM_TESTS:
        return lines
    lines += cycle_lines(cycles)
    kept = sum(c.kept for c in cycles)
    lines.append(f"  cycles_used    {cr.cycles_used if cr is not None else kept} "
                 f"({len(cycles) - kept} dropped)")
    if cr is not None:
        for name, got, key, unit in (("frequency", cr.frequency_hz, "pmm_frequency_hz", "Hz"),
                                     ("amplitude", cr.amplitude_m, "pmm_amplitude_m", "m")):
            want = _sheet_value(row, key)
            lines.append(f"  {name:<14s} {got:.4f} {unit} measured, {want:g} {unit} in the "
                         f"sheet ({100 * (got / want - 1):+.1f} %)")
    return lines


#: The PNG text chunk that marks a plot as inspect's, with the run file it shows.
PNG_KEY = "towtank inspect"


def _png_source(path: Path) -> str | None:
    """The run file an existing inspect plot shows, or None for any other file."""
    try:
        # loaded on use: Pillow only when a PNG of that name exists
        from PIL import Image, PngImagePlugin

        with Image.open(path) as im:
            return (im.text.get(PNG_KEY) if isinstance(im, PngImagePlugin.PngImageFile)
                    else None)
    except Exception:  # noqa: BLE001 - not an image, or unreadable: not ours
        return None


def _target(runfile: Path, png: str | Path | None, err: TextIO, out: TextIO
            ) -> Path | None:
    """Where the plot goes: ``--png`` (wherever the user chooses), else ``<run>.png`` in the
    current folder (``<run>-2.png`` … when that name holds the plot of another run file), but
    not unasked into the raw data's folder. A file that is not an inspect plot of this run
    file is never overwritten (None, with a sentence on ``err``)."""
    source = str(runfile.resolve())
    if png is not None:
        target = Path(png)
        if target.exists() and _png_source(target) != source:
            print(f"towtank: the plot is not written: {target} exists and is not towtank "
                  "inspect's plot of this run file; give --png another name.", file=err)
            return None
        return target
    if Path.cwd().resolve() == runfile.resolve().parent:
        print(f"plot: not written: it would lie beside the raw data in {Path.cwd()}; give "
              "--png with a path (anywhere you choose) or run inspect from another folder.",
              file=out)
        return None
    stem = plot_name(runfile)[: -len(".png")]
    for k in range(1, 1000):
        target = Path.cwd() / (f"{stem}.png" if k == 1 else f"{stem}-{k}.png")
        if not target.exists() or _png_source(target) == source:
            return target
    print("towtank: the plot is not written: too many plots of that name here; give --png.",
          file=err)
    return None


def _save(fig, path: Path, runfile: str) -> None:  # noqa: ANN001 - a matplotlib Figure
    # loaded on use: matplotlib only when the plot is drawn
    import matplotlib as mpl

    path.parent.mkdir(parents=True, exist_ok=True)
    rc: Any = style.rc()  # matplotlib's stubs want its own key type
    with mpl.rc_context(rc):
        fig.savefig(path, dpi=style.PNG_DPI, facecolor="white",
                    metadata={"Software": None, PNG_KEY: runfile})


def _write_preview(raw, path: Path, reason: str, runfile: Path) -> None:  # noqa: ANN001
    # loaded on use: matplotlib only when the plot is drawn
    from towtank.report.figures import fig_preview

    fig = fig_preview(run_preview(raw),
                      f"{runfile.name}: calibrated traces (the run cannot be reduced)", reason)
    _save(fig, path, str(runfile.resolve()))


def write_plot(red: RunReduction, path: Path, protocol_path: str | Path | None = None,
               runfile: str | Path | None = None, settings: str | None = None,
               balance: CaptiveTrace | None = None) -> Path:
    """The run's thumbnail as a PNG (speed, drag, lift; phases shaded; means below); a
    captive run's (``red.captive``, or ``balance``: a balance file read without its protocol)
    its loads X, Y, N against time (:func:`towtank.report.figures.fig_captive_run`)."""
    # loaded on use: matplotlib only when the plot is drawn
    from towtank.report.captive_thumb import captive_trace
    from towtank.report.figures import fig_captive_run, fig_run

    ct = balance if balance is not None else captive_trace(red)
    if ct is not None:
        where = "O" if balance is None else "the balance point"
        title = (f"{red.file}: loads X, Y and N about {where} (zeroed, inertia not removed)")
        note = (f"{red.fs:g} Hz;  " + (f"settings of {Path(protocol_path).name}"
                                       if protocol_path else
                                       settings or "canonical channels, default processing"))
        fig = fig_captive_run(ct, red.windows, title, note)
        _save(fig, path, str(Path(runfile).resolve()) if runfile is not None else "")
        return path

    title = f"{red.file}: speed and forces (zero and drift removed, no tare)"
    note = (f"steady: U = {red.speed_mean:.4f} m/s, D = {red.drag_mean_raw:.4f} N"
            + (f", L = {red.lift_mean_raw:.4f} N" if red.has_lift else "")
            + (f";  acceleration {red.accel_mean:.3f} m/s²" if red.accel_mean == red.accel_mean
               else "")
            + f";  {red.fs:g} Hz"
            + (f";  settings of {Path(protocol_path).name}" if protocol_path else
               f";  {settings or 'canonical channels, default processing'}"))
    fig = fig_run(red, title, note)
    _save(fig, path, str(Path(runfile).resolve()) if runfile is not None else "")
    return path
