"""The watch loop of ``towtank watch``: each run's verdict as its file completes, the day's
outputs kept up to date (docs/formats.md, "towtank watch").

:class:`WatchSession` holds the day: the last good run sheet, which run files are complete
(:class:`towtank.live.arrival.ArrivalTracker`), the verdicts given. :meth:`WatchSession.step`
looks once at the sheet and the files and processes what became complete as one batch;
:meth:`WatchSession.run` calls it whenever watchfiles reports a change (or every
:data:`POLL_MS`, so that settle times are checked when nothing happens). A test drives the
session in-process with :meth:`~WatchSession.step` or :meth:`~WatchSession.run` with a
condition; the command line adds the page server and Ctrl-C.

"The runs so far": the sheet's rows whose files are complete, the void rows, and the rows the
sheet alone rejects; a run whose file does not exist yet (or is still being written) is "to
do", not rejected. After every batch the output folder holds what ``towtank process`` writes
for those rows (through the same manifest, lock and atomic swap), except that the PDF and
figures are redrawn at most every ``[watch] pdf_interval_s`` (carried over unchanged in
between; provenance.json's ``watch`` entry says which runs they cover).

The process stays single-threaded: the report writers fork.
"""

from __future__ import annotations

import io
import json
import math
import os
import shutil
import signal
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pandas as pd
from watchfiles import watch

from towtank.analysis.next_run import rank_next_runs
from towtank.errors import ProtocolError
from towtank.ingest.inputs import day_sheet, unlisted_warnings
from towtank.ingest.protocol_types import CAPTIVE_TESTS
from towtank.live import arrival
from towtank.live.state import (
    LIVE_DIR,
    claim_live_dir,
    now_iso,
    remove_leftovers,
    save_figure,
    write_state,
)
from towtank.report import figures as rf
from towtank.report.figures import write_figures
from towtank.report.pdf import write_pdf
from towtank.report.safetext import clean_text
from towtank.report.workbook import write_workbook
from towtank.results import Notice
from towtank.runner import (
    DayStopped,
    Options,
    OutputsNotWritten,
    Plan,
    Reduced,
    prepare,
    reduce_day,
    write_day,
)
from towtank.runtime.parallel import fork_beside, leave_inherited_alone
from towtank.runtime.safefile import read_regular
from towtank.runtime.storage import STORAGE_ERRNOS, os_error, storage_error

if TYPE_CHECKING:
    from towtank.ingest.protocol import Protocol
    from towtank.results import DayResult

__all__ = ["POLL_MS", "Verdict", "WatchSession", "captive_verdict_line", "verdict_line"]

#: The longest the loop waits for a change before it looks at the files anyway [ms].
POLL_MS = 100

#: Niceness added to the processes drawing the report and the fit figures: on a machine of
#: two cores the watching process, which gives the verdicts, gets the processor first.
CHILD_NICE = 10

#: The live page's figures of the day's fits (state.json "figures" keys).
FIT_FIGURES = ("damping", "added_mass", "captive")

#: Files an output writer leaves in the report that watch carries over between two PDFs.
PDF_OUTPUTS = ("report.pdf", "figures")

#: What watch writes into the live folder, as its sentences name it when it cannot.
PAGE = "the live page's state"
FITS = "the live page's fit figures"
REPORT = "report.pdf and figures/"

#: A forked drawing that failed for the storage (a full disk...) exits with this plus the
#: errno, so that the watching process tells it as a storage failure.
STORAGE_EXIT = 100

#: Largest file a forked drawing leaves for the watching process (its listing, its error)
#: and largest coefficients.csv read back for the live state [bytes].
MAX_NOTE_BYTES = 1 << 20
MAX_TABLE_BYTES = 64 << 20


@dataclass(frozen=True)
class Verdict:
    """A run's verdict: one line on the terminal and one entry of state.json."""

    run: int
    file: str
    test: str
    angle_deg: float
    speed_m_s: float | None
    drag_N: float | None
    status: str  # ok | suspicious | rejected
    reason: str | None
    line: str
    time: str
    sha256: str = ""
    #: a captive run's loads about O (X_N, Y_N [N], N_Nm [N m]) and its PMM cycles_used
    #: (None where the run was not reduced); None for any other run
    captive: dict[str, float | None] | None = None

    def entry(self) -> dict[str, Any]:
        """The state.json entry."""
        return {"run": self.run, "file": self.file, "test": self.test,
                "angle_deg": self.angle_deg, "speed_m_s": self.speed_m_s,
                "drag_N": self.drag_N, "status": self.status, "reason": self.reason,
                "line": self.line, "time": self.time, "captive": self.captive}


def _num(value: Any) -> float | None:
    try:
        v = float(value)
    except (TypeError, ValueError):
        return None
    return v if math.isfinite(v) else None


def verdict_line(run: int, test: str, angle_deg: float | None, speed_m_s: float | None,
                 speed_set: bool, drag_N: float | None, status: str,
                 reason: str | None) -> str:
    """``run 17  steady  α 10.0°  U 1.20 m/s  drag 3.41 N  ok``, and for a rejected or
    suspicious run ``: <the reason in one sentence>``. ``speed_set``: U is the sheet's set
    speed (the run was not reduced)."""
    alpha = f"α {angle_deg:.1f}°" if angle_deg is not None else "α –"
    u = (f"U {speed_m_s:.2f} m/s" + (" (set)" if speed_set else "")
         if speed_m_s is not None else "U –")
    d = f"drag {drag_N:.2f} N" if drag_N is not None else "drag –"
    line = f"run {run}  {test}  {alpha}  {u}  {d}  {status}"
    if reason:
        line += ": " + reason.strip()
    return line


def captive_loads(row: dict[str, Any]) -> dict[str, float | None]:
    """A captive run's runs.csv loads as state.json gives them: X_N, Y_N [N], N_Nm [N m]
    about O, inertia removed, and the PMM cycles_used (None where not reduced)."""
    cycles = _num(row.get("pmm_cycles"))
    return {"X_N": _num(row.get("captive_X_N")), "Y_N": _num(row.get("captive_Y_N")),
            "N_Nm": _num(row.get("captive_N_Nm")),
            "cycles_used": int(cycles) if cycles is not None else None}


def captive_verdict_line(run: int, test: str, row: dict[str, Any], speed_m_s: float | None,
                         speed_set: bool, loads: dict[str, float | None], status: str,
                         reason: str | None) -> str:
    """``run 26  sway  PMM 0.10 m 0.35 Hz  U 1.50 m/s  X -3.66 N  Y 0.11 N  N -0.04 N m
    5 cycles  ok``: a captive run's test and the sheet's settings (drift β, rudder δ [deg],
    arm radius R [m], PMM amplitude [m] and frequency [Hz], those set), its loads about O
    (the steady or cycle mean) and, for a rejected or suspicious run, ``: <the reason>``."""
    setting = []
    for key, text in (("drift_deg", "β {:.1f}°"), ("rudder_deg", "δ {:.1f}°"),
                      ("radius_m", "R {:g} m")):
        value = _num(row.get(key))
        if value is not None and (value != 0.0 or key == "drift_deg"):
            setting.append(text.format(value))
    amp, freq = _num(row.get("pmm_amplitude_m")), _num(row.get("pmm_frequency_hz"))
    if amp is not None and freq is not None:
        setting.append(f"PMM {amp:.2f} m {freq:g} Hz")
    u = (f"U {speed_m_s:.2f} m/s" + (" (set)" if speed_set else "")
         if speed_m_s is not None else "U –")
    parts = [f"run {run}", test, *setting, u]
    for key, name, unit in (("X_N", "X", "N"), ("Y_N", "Y", "N"), ("N_Nm", "N", "N m")):
        value = loads.get(key)
        parts.append(f"{name} {value:.2f} {unit}" if value is not None else f"{name} –")
    if loads.get("cycles_used") is not None:
        parts.append(f"{loads['cycles_used']} cycles")
    line = "  ".join([*parts, status])
    return line + (": " + reason.strip() if reason else "")


@dataclass
class _Said:
    """Sentences said once (terminal and state.json messages)."""

    seen: set[str] = field(default_factory=set)
    messages: list[str] = field(default_factory=list)


class WatchSession:
    """A watched day (see the module's text).

    Every batch is run by :mod:`towtank.runner` as ``towtank process`` runs a day
    (:func:`~towtank.runner.reduce_day`, :func:`~towtank.runner.write_day`), on the rows of
    the runs so far, with watch's own writers and provenance entry.

    Parameters
    ----------
    protocol : Protocol or towtank.runner.Plan
        The day's protocol, or the runner's plan of the day (:func:`towtank.runner.prepare`:
        its output folder, jobs, report and date are then the plan's, and the files read
        when its protocol was loaded are among the day's inputs).
    out : path, optional
        The output folder (default the protocol's ``output_dir``); ``.cache/`` and
        ``.live/`` are kept in it.
    jobs : int, optional
        Worker processes for a batch of several runs (default: the protocol's, else
        ``TOWTANK_JOBS``, else all).
    report : bool
        Also write the workbook, the PDF and the figures (else the CSV tables only).
    date : str, optional
        The report's test date (``--date``).
    echo : callable
        Where the verdict lines and sentences go (default ``print``, flushed).
    live_figures : bool
        Draw the live page's figures into ``.live/``.
    clock : callable
        The time [s since the epoch] (a test may pass its own).
    """

    def __init__(self, protocol: Protocol | Plan, out: str | Path | None = None, *,
                 jobs: int | None = None, report: bool = True, date: str | None = None,
                 echo: Callable[[str], None] | None = None, live_figures: bool = True,
                 clock: Callable[[], float] = time.time) -> None:
        plan = protocol if isinstance(protocol, Plan) else prepare(
            protocol, out, watch_options(jobs=jobs, report=report, date=date))
        assert plan.out is not None
        self.plan = plan
        self.protocol = plan.protocol
        self.out = plan.out
        self.live_dir = self.out / LIVE_DIR
        self.jobs = plan.jobs
        self.report = plan.options.report
        self.echo = echo if echo is not None else _print
        self.live_figures = live_figures
        self.clock = clock
        w = self.protocol.watch
        self.tracker = arrival.ArrivalTracker(w.settle_s, w.never_stops_s)
        self.sheet_tracker = arrival.ArrivalTracker(w.settle_s, w.never_stops_s)
        self.sheet_path = Path(self.protocol.campaign.run_sheet)
        self.data_dir = Path(self.protocol.campaign.data_dir)
        self.sheet: pd.DataFrame | None = None  # the last good sheet
        self.batch: Reduced | None = None  # the last batch, reduced
        self.verdicts: list[Verdict] = []
        self.given: dict[int, tuple[str, str | None, str]] = {}
        self.said = _Said()
        self.version = 0
        self.batches = 0
        self.writes = 0  # output updates
        self.fits_stale = False  # the live page's fit figures are behind the outputs
        #: (run, file, sha256) of every reduction this session obtained: a run file is only
        #: ever reduced complete
        self.reduced: list[tuple[int, str, str]] = []
        self.pdf_at: float | None = None  # when the PDF was last drawn [s]
        self.pdf_runs: list[int] | None = None  # the runs it covers
        self.pdf_iso: str | None = None
        self.pdf_stale = False
        #: the report being drawn: (process id, folder, its runs, when it was started)
        self._job: tuple[int, Path, list[int], str] | None = None
        self._staged: Path | None = None  # the folder of the last report drawn
        self._fits_job: tuple[int, Path] | None = None  # (process id, its listing)
        claim_live_dir(self.live_dir)  # ProtocolError: a link, or a folder not towtank's
        remove_leftovers(self.live_dir)  # of an earlier watch that was killed
        self.latest: Verdict | None = None
        self.figures: dict[str, str] = {}
        self.timings: dict[str, float] = {}
        self._dirty = False
        self._unlisted: list[Notice] = []
        self.next_runs: list[dict[str, Any]] = []
        arrival.ignore_lease_breaks()

    @property
    def day(self) -> DayResult | None:
        """The day of the runs so far (the last batch), or None before the first."""
        return self.batch.day if self.batch is not None else None

    # ------------------------------------------------------------------ sentences
    def say(self, sentence: str, *, once: bool = True) -> None:
        """Print ``sentence`` (once per session when ``once``) and keep it for state.json."""
        if once and sentence in self.said.seen:
            return
        self.said.seen.add(sentence)
        self.said.messages.append(sentence)
        self.echo(sentence)

    # ------------------------------------------------------------------ the sheet
    def read_sheet(self) -> bool:
        """Read the run sheet; keep the last good one when it cannot be read (said once per
        fault). True when a sheet was read."""

        p = self.protocol
        try:
            sheet = day_sheet(p)
        except ProtocolError as exc:
            if self.sheet is None:
                raise
            self.say(f"{self.sheet_path.name} could not be read ({_strip_dot(str(exc))}); the "
                     "last good sheet is kept and the sheet is read again at its next change.")
            return False
        self.sheet = sheet
        self._unlisted = unlisted_warnings(p, sheet)
        self._dirty = True
        return True

    def names(self) -> dict[str, int]:
        """The run files the sheet's rows (void ones aside) name -> run."""
        if self.sheet is None:
            return {}
        out: dict[str, int] = {}
        for run, file, status in zip(self.sheet["run"], self.sheet["file"],
                                     self.sheet["status"], strict=True):
            if status != "void" and str(file).strip():
                out.setdefault(str(file), int(run))
        return out

    # ------------------------------------------------------------------ one look
    def scan(self, changed: set[str] | None = None) -> list[str]:
        """One look at the sheet and the run files; return the files that became complete.
        ``changed``: paths watchfiles reported (for the lock files and unlisted files)."""
        now = self.clock()
        event = self.sheet_tracker.update("sheet", arrival.observe(self.sheet_path, now))
        st = self.sheet_tracker.files["sheet"]
        if self.sheet is None:  # the first look: the sheet as it is
            self.read_sheet()
            self._sheet_sig = st.complete or st.signature
        elif event == "complete" and st.complete != self._sheet_sig:
            self._sheet_sig = st.complete
            self.read_sheet()
        for path in sorted(changed or ()):
            name = Path(path).name
            if name.startswith("~$"):
                self.say(f"{name} is Excel's lock file (the sheet is open in Excel); it is "
                         "ignored.")
        names = self.names()
        if changed and any(self._unnamed(path, names) for path in changed):
            self._tell_unlisted()  # a listing of the data folder: only for a new name
        for gone in [n for n in self.tracker.files if n not in names]:
            self.tracker.forget(gone)
            self._dirty = True
        done = []
        for name in names:
            file = self.data_dir / name
            complete = self.tracker.is_complete(name)
            obs = arrival.observe(file, now, probe=False)
            known = self.tracker.files.get(name)
            if not complete and obs.size is not None and known is not None \
                    and known.signature == (obs.size, obs.mtime_ns):
                obs = arrival.observe(file, now)  # unchanged since the last look: closed?
            event = self.tracker.update(name, obs)
            if event == "complete":
                done.append(name)
            elif event == "vanished":
                self.say(f"{name} appeared and disappeared before it was complete; run "
                         f"{names[name]} is still to do.", once=False)
            elif event == "removed":
                self.say(f"{name} was removed; run {names[name]} is to do again.", once=False)
                self.given.pop(names[name], None)
                self._dirty = True
            elif event == "never_stops":
                self.say(f"{name} is still being written after "
                         f"{self.tracker.never_stops_s:g} s ([watch] never_stops_s); run "
                         f"{names[name]} waits until it stops.")
        if done:
            self._dirty = True
        return done

    _sheet_sig: tuple[int, int] | None = None

    def _unnamed(self, path: str, names: dict[str, int]) -> bool:
        """Whether ``path`` (from watchfiles) is in the data folder but no sheet row's file."""
        try:
            rel = Path(path).resolve().relative_to(self.data_dir.resolve()).as_posix()
        except (ValueError, OSError):
            return False
        return rel not in names

    def _tell_unlisted(self) -> None:

        if self.sheet is None:
            return
        self._unlisted = unlisted_warnings(self.protocol, self.sheet)
        for notice in self._unlisted:
            if not _inside(self.out, self.data_dir, notice.file):
                self.say(str(notice))

    # ------------------------------------------------------------------ one batch
    def runs_so_far(self) -> pd.DataFrame:
        """The sheet restricted to the runs so far (see the module's text), sheet order."""
        assert self.sheet is not None
        sheet = self.sheet
        keep = []
        for status, file, error in zip(sheet["status"], sheet["file"], sheet["sheet_error"],
                                       strict=True):
            keep.append(status == "void" or bool(error)
                        or self.tracker.is_complete(str(file)))
        sub = sheet[keep].reset_index(drop=True)
        sub.attrs = dict(sheet.attrs)
        return sub

    def step(self, changed: set[str] | None = None) -> list[Verdict]:
        """One look; when something changed, process the runs so far as one batch, print a
        verdict line per new or changed run and bring the outputs up to date. Returns the
        verdicts given."""
        self.scan(changed)
        verdicts: list[Verdict] = []
        if self._dirty:
            self._dirty = False
            verdicts = self.process()
        self._collect_report()
        # slower work only while no run file is being written: its verdict comes first
        self._collect_fits()
        if self._report_due():
            self._start_report()  # forked processes: drawn beside the next verdicts
        if self.fits_stale and self._fits_job is None and self.live_figures:
            self._start_fits()
        return verdicts

    def _start_fits(self) -> None:
        """Draw the live page's fit figures in a forked process (:meth:`_collect_fits`)."""
        day = self.day
        listing = self.live_dir / f".fits-{self.version}.json"
        live_dir = self.live_dir
        self._fits_job = (_fork(lambda: _draw_fits_child(day, live_dir, listing)), listing)
        self.fits_stale = False

    def _collect_fits(self, *, wait: bool = False) -> bool:
        """When the fit figures are drawn: state.json names them (one more version)."""
        if self._fits_job is None:
            return False
        pid, listing = self._fits_job
        done, status = os.waitpid(pid, 0 if wait else os.WNOHANG)
        if done == 0:
            return False
        self._fits_job = None
        code = os.waitstatus_to_exitcode(status)
        raw = read_regular(listing, MAX_NOTE_BYTES)
        try:
            drawn = json.loads(raw.decode("utf-8")) if raw is not None else None
        except (ValueError, RecursionError):
            drawn = None
        if raw is not None:
            listing.unlink(missing_ok=True)
        if (number := _storage_errno(code)) is not None:
            self._failed(FITS, os_error(number))
            return True
        if code != 0 or not isinstance(drawn, dict):
            self.say("the live page's fit figures could not be drawn; the last ones stay.")
            return True
        figs = {k: v for k, v in self.figures.items() if k not in FIT_FIGURES}
        self.figures = {**figs, **{str(k): str(v) for k, v in drawn.items()}}
        self.publish()
        return True

    def process(self) -> list[Verdict]:
        """Reduce the runs so far (the cache makes the known ones free), give the verdicts,
        write the outputs and the live state."""

        t0 = time.perf_counter()
        sub = self.runs_so_far()
        new_rows = sum(1 for r in sub["run"] if int(r) not in self.given)
        jobs = 1 if new_rows <= 1 else self.jobs
        self.batch = reduce_day(self.plan, sub, jobs=jobs,
                                unlisted=[w for w in self._unlisted
                                          if not _inside(self.out, self.data_dir, w.file)])
        day = self.batch.day
        self.batches += 1
        verdicts = self._verdicts(day)
        self.timings["reduce_s"] = time.perf_counter() - t0
        for v in verdicts:
            self.echo(v.line)
        if verdicts:
            self.latest = verdicts[-1]
        self.verdicts.extend(verdicts)
        if verdicts:  # the page has the verdicts at once; the outputs and fits follow
            self.publish(latest=True)
        self.timings["verdict_state_s"] = time.perf_counter() - t0
        t1 = time.perf_counter()
        self.write()
        self.timings["write_s"] = time.perf_counter() - t1
        t2 = time.perf_counter()
        self.next_runs = self.rank_next(day)
        self.timings["next_s"] = time.perf_counter() - t2
        if verdicts:
            for line in next_run_lines(self.next_runs):
                self.echo(line)
        self.fits_stale = True
        self.publish(latest=not verdicts)  # the tables written: their coefficients
        self.timings["state_s"] = time.perf_counter() - t2
        return verdicts

    def _verdicts(self, day: DayResult) -> list[Verdict]:
        """The verdict of every run whose (status, reason, content) is new."""
        out = []
        stamp = now_iso()
        for row in day.runs.to_dict("records"):
            if row["status"] == "void":
                continue
            run = int(row["run"])
            red = day.reductions.get(run)
            sha = red.sha256 if red is not None else ""
            if red is not None and (run, str(row["file"]), sha) not in self.reduced:
                self.reduced.append((run, str(row["file"]), sha))
            status = str(row["status"])
            rejection = day.rejected.get(run)
            # a rejected run: its sentence without the run number the line starts with
            reason = rejection.detail if rejection is not None else None
            if status == "ok" and red is not None and red.warnings:
                status = "suspicious"
                reason = red.warnings[0] + (f" (and {len(red.warnings) - 1} more warnings)"
                                            if len(red.warnings) > 1 else "")
            if status != "rejected" and status != "suspicious":
                reason = None
            key = (status, reason, sha)
            if self.given.get(run) == key:
                continue
            self.given[run] = key
            u = _num(row["speed_mean"])
            speed_set = u is None
            if u is None:
                u = _num(row["speed_nominal"])
            angle = _num(row["angle_deg"])
            test = str(row["test"])
            drag = _num(row["drag_mean"])
            captive = None
            if test.strip().lower() in CAPTIVE_TESTS:  # its loads about O, not a drag
                captive, drag = captive_loads(row), None
                line = captive_verdict_line(run, test, row, u, speed_set, captive, status,
                                            reason)
            else:
                line = verdict_line(run, test, angle, u, speed_set, drag, status, reason)

            out.append(Verdict(run=run, file=str(row["file"]), test=test,
                               angle_deg=angle if angle is not None else math.nan,
                               speed_m_s=u, drag_N=drag, status=status, reason=reason,
                               line=clean_text(line), time=stamp, sha256=sha,
                               captive=captive))
        return out

    # ------------------------------------------------------------------ outputs
    def _waiting(self) -> bool:
        return any(self.tracker.is_waiting(n) for n in self.names())

    def _report_due(self) -> bool:
        """Whether to start drawing the PDF and figures: they are behind the runs so far, none
        is being drawn, no run file is being written, and the last was started more than
        pdf_interval_s ago (or there is none yet)."""
        if (not self.report or self.day is None or self._job is not None or not self.pdf_stale
                or not len(self.day.runs)):
            return False
        if self._waiting():
            return False
        return (self.pdf_at is None
                or self.clock() - self.pdf_at >= self.protocol.watch.pdf_interval_s)

    def write(self, *, pdf: bool = False) -> None:
        """The outputs of the runs so far (``towtank process``'s writers, manifest and swap);
        without ``pdf`` the last report.pdf and figures/ drawn (by :meth:`_start_report`, or
        already in the folder) are carried over unchanged."""
        if self.batch is None:
            return
        runs = [int(r) for r in self.batch.day.runs["run"]]
        pdf_iso: str | None
        pdf_runs: list[int] | None
        if pdf:
            writers: list[Any] | None = None  # process's writers
            pdf_runs, pdf_iso = runs, now_iso()
        else:
            writers = [write_workbook, self._carry]
            pdf_runs, pdf_iso = self.pdf_runs, self.pdf_iso
        extra = {"watch": {"pdf_runs": pdf_runs, "pdf_written": pdf_iso,
                           "pdf_current": pdf_runs == runs, "runs": runs}}
        try:
            write_day(self.plan, self.batch, writers=writers, provenance_extra=extra)
        except OutputsNotWritten as exc:
            self.say(f"the outputs could not be written to {self.out} "
                     f"({os.strerror(exc.errno)}); the folder holds the last complete set, "
                     "and they are written again at the next run.")
            return
        except DayStopped as exc:  # a file of the user's with an output's name
            self.say(f"{_strip_dot(str(exc))}; the verdicts go on, the outputs are written "
                     "again at the next run.")
            return
        self.writes += 1
        if self.report and pdf:
            self.pdf_at, self.pdf_runs, self.pdf_iso = self.clock(), runs, pdf_iso
            self._drop_staged()
        self.pdf_stale = self.report and self.pdf_runs != runs

    def _carry(self, day: DayResult, folder: Path) -> None:
        """A report writer: the last report.pdf and figures/ drawn into the new set as they
        are (from the folder they were drawn in, else from the output folder)."""
        source = self._staged if self._staged is not None else self.out
        for name in PDF_OUTPUTS:
            src = source / name
            if src.is_dir() and not src.is_symlink():
                # into what this write drew already (figures/predicted_vs_measured.png of a
                # day with a [vehicle]): the files drawn now stay, the others are carried
                shutil.copytree(src, folder / name, copy_function=_link_new,
                                dirs_exist_ok=True)
            elif src.is_file() and not src.is_symlink():
                _link_or_copy(str(src), str(folder / name))

    def _start_report(self) -> None:
        """Draw report.pdf and figures/ of the runs so far in a forked process, into a folder
        of ``.live/``; :meth:`_collect_report` puts them into the outputs when it is done."""
        day = self.day
        assert day is not None
        folder = self.live_dir / f".report-{self.writes}"
        shutil.rmtree(folder, ignore_errors=True)
        runs = [int(r) for r in day.runs["run"]]
        beside = fork_beside(self.jobs)  # one job: the PDF's page groups one by one
        pid = _fork(lambda: _draw_report(day, folder, beside=beside))
        self._job = (pid, folder, runs, now_iso())
        self.pdf_at = self.clock()

    def _collect_report(self, *, wait: bool = False) -> bool:
        """When the report being drawn is done: its PDF and figures into the outputs (one
        more write), or one sentence if it failed. True when a drawing ended."""
        if self._job is None:
            return False
        pid, folder, runs, iso = self._job
        done, status = os.waitpid(pid, 0 if wait else os.WNOHANG)
        if done == 0:
            return False
        self._job = None
        if os.waitstatus_to_exitcode(status) == 0 and (folder / "done").is_file():
            old, self._staged = self._staged, folder
            self.pdf_runs, self.pdf_iso = runs, iso
            self.write()
            if old is not None:
                shutil.rmtree(old, ignore_errors=True)
            self.publish()
        elif (number := _storage_errno(os.waitstatus_to_exitcode(status))) is not None:
            self._failed(REPORT, os_error(number))
            shutil.rmtree(folder, ignore_errors=True)
        else:
            error = read_regular(folder / "error.txt", MAX_NOTE_BYTES)
            reason = error.decode("utf-8", "replace").strip() if error is not None else \
                f"its process ended with status {os.waitstatus_to_exitcode(status)}"
            self.say(f"report.pdf and figures/ of runs {_span(runs)} could not be drawn "
                     f"({reason}); the previous ones are kept.", once=False)
            shutil.rmtree(folder, ignore_errors=True)
        return True

    def _drop_staged(self) -> None:
        if self._staged is not None:
            shutil.rmtree(self._staged, ignore_errors=True)
            self._staged = None

    def finish(self) -> None:
        """At the end: the PDF and figures of every run so far if they are behind (drawn
        here, waiting for one being drawn), and the live figures."""
        if self._job is not None:
            self._collect_report(wait=True)
        if self._fits_job is not None:
            self._collect_fits(wait=True)
        if self.day is not None and (self.pdf_stale or self.fits_stale):
            if self.pdf_stale:
                self.write(pdf=True)
            self.publish(fits=True)

    def close(self) -> None:
        """Stop a report or figures being drawn (Ctrl-C) and remove their files."""
        if self._fits_job is not None:
            pid, listing = self._fits_job
            self._fits_job = None
            _end(pid)
            listing.unlink(missing_ok=True)
        if self._job is not None:
            pid, folder, _runs, _iso = self._job
            self._job = None
            _end(pid)
            shutil.rmtree(folder, ignore_errors=True)
        self._drop_staged()  # the output folder has its own links to its files

    # ------------------------------------------------------------------ live state
    def sheet_states(self) -> list[dict[str, Any]]:
        """Every sheet row with its state: done | rejected | to do | void | waiting."""
        if self.sheet is None:
            return []
        status = {}
        if self.day is not None:
            status = dict(zip(self.day.runs["run"].astype(int), self.day.runs["status"],
                              strict=True))
        out = []
        for row in self.sheet.to_dict("records"):
            run, file = int(row["run"]), str(row["file"])
            if row["status"] == "void":
                state = "void"
            elif status.get(run) == "rejected":
                state = "rejected"
            elif status.get(run) == "ok":
                state = "done"
            elif self.tracker.is_waiting(file):
                state = "waiting"
            else:
                state = "to do"
            out.append({"run": run, "file": file, "test": row["test"],
                        "config": row["config"], "angle_deg": _num(row["angle_deg"]),
                        "speed_m_s": _num(row["speed_nominal"]), "state": state})
        return out

    def state(self) -> dict[str, Any]:
        """The live state (docs/formats.md, "towtank watch")."""
        coefficients: list[dict[str, Any]] = []
        columns: list[str] = []
        raw = read_regular(self.out / "coefficients.csv", MAX_TABLE_BYTES)
        if raw is not None:
            table = pd.read_csv(io.BytesIO(raw))
            columns = [str(c) for c in table.columns]
            coefficients = table.astype(object).where(table.notna(), None).to_dict("records")
        latest = None
        if self.latest is not None:
            latest = {"run": self.latest.run, "line": self.latest.line,
                      "status": self.latest.status}
        return {
            "version": self.version,
            "protocol": self.protocol.name,
            "updated": now_iso(),
            "output_dir": str(self.out),
            "latest": latest,
            "verdicts": [v.entry() for v in self.verdicts],
            "sheet": self.sheet_states(),
            "coefficients": coefficients,
            "coefficient_columns": columns,
            "next_runs": list(self.next_runs),
            "messages": list(self.said.messages),
            "figures": dict(self.figures),
            "pdf": ({"written": self.pdf_iso, "runs": len(self.pdf_runs)}
                    if self.pdf_runs is not None and self.report else None),
        }

    def rank_next(self, day: DayResult) -> list[dict[str, Any]]:
        """The top three of the sheet's runs still to tow (and up to three conditions not on
        the sheet), ranked by how much each would narrow the day's widest relative interval
        (:func:`towtank.analysis.next_run.rank_next_runs`), as state.json's ``next_runs``."""
        if self.sheet is None:
            return []
        states = {row["run"]: row["state"] for row in self.sheet_states()}
        todo = self.sheet[[states.get(int(r)) == "to do" for r in self.sheet["run"]]]
        ranked = rank_next_runs(day.hull, day.runs, todo, reductions=day.reductions,
                                alpha_max_deg=self.protocol.processing.damping_alpha_max_deg)
        out = []
        for row in ranked.to_dict("records"):
            run = row["run"]
            out.append({
                "rank": int(row["rank"]),
                "run": None if pd.isna(run) else int(run),
                "description": str(row["description"]), "target": str(row["target"]),
                **{k: _num(row[k]) for k in ("half_width_now", "half_width_after",
                                             "relative_now", "relative_after")},
            })
        return out

    def publish(self, *, latest: bool = False, fits: bool = False) -> None:
        """Write state.json (its version one up), after drawing the latest run's figure
        (``latest``) and the fits' figures (``fits``); the others stay as they were. A
        failure of the storage or a link in the live folder is one sentence
        (:meth:`_failed`), not the end of the watch."""
        try:
            self._publish(latest=latest, fits=fits)
        except ProtocolError as exc:
            self._failed(PAGE, exc)
        except Exception as exc:
            full = storage_error(exc, self.live_dir)
            if full is None:
                raise
            self._failed(PAGE, full)

    def _publish(self, *, latest: bool, fits: bool) -> None:
        if self.live_figures and self.day is not None:
            t0 = time.perf_counter()
            figs = dict(self.figures)
            if latest:
                figs.pop("latest_run", None)
                figs.update(self._draw_latest())
            if fits:
                for key in FIT_FIGURES:
                    figs.pop(key, None)
                figs.update(self._draw_fits())
                self.fits_stale = False
            self.figures = figs
            self.timings["figures_s"] = time.perf_counter() - t0
        self.version += 1
        write_state(self.live_dir, self.state())

    def _failed(self, what: str, exc: BaseException) -> None:
        """One sentence for ``what`` (:data:`PAGE`, :data:`FITS`, :data:`REPORT`) that could
        not be written into the live folder (a full disk, a link put there meanwhile), said
        once in the session (a disk that fills and empties would otherwise repeat it at every
        run); the verdicts go on and the files there stay whole (each is replaced whole or not
        at all)."""
        if isinstance(exc, ProtocolError):
            sentence = f"{_strip_dot(str(exc))}; the verdicts go on without {what}."
        else:
            code = exc.errno if isinstance(exc, OSError) and exc.errno else None
            sentence = (f"{what} could not be written in {self.live_dir} "
                        f"({os.strerror(code) if code else exc}); the verdicts go on, and it is "
                        "written again at the next run.")
        self.say(sentence)

    def _draw_latest(self) -> dict[str, str]:
        """The latest verdict's run: its traces and phases, or its raw traces when it could
        not be reduced."""
        day, v = self.day, self.latest
        if day is None or v is None:
            return {}
        red = day.reductions.get(v.run)
        fig = None
        if red is not None:
            fig = rf.fig_run(red, v.line)
        elif v.run in day.previews:
            fig = rf.fig_preview(day.previews[v.run], f"run {v.run}", v.reason or "")
        if fig is None:
            return {}
        return {"latest_run": save_figure(fig, self.live_dir, "latest_run.png")}

    def _draw_fits(self) -> dict[str, str]:
        """The C_D(α) fit and the added-mass plot, those the day has."""
        return _fit_figures(self.day, self.live_dir)

    # ------------------------------------------------------------------ the loop
    def watched_paths(self) -> list[Path]:
        """The folders watched: the data folder and the sheet's folder."""
        paths = [self.data_dir.resolve()]
        folder = self.sheet_path.resolve().parent
        if not any(folder == p or p in folder.parents for p in paths):
            paths.append(folder)
        return paths

    def run(self, until: Callable[[WatchSession], bool] | None = None, *,
            timeout_s: float | None = None) -> None:
        """Watch until ``until(self)`` is true or ``timeout_s`` [s] has passed (forever
        without either; Ctrl-C raises KeyboardInterrupt). One :meth:`step` per change
        reported by watchfiles, and at least every :data:`POLL_MS`."""

        start = time.monotonic()
        self.step()
        if until is not None and until(self):
            return
        for changes in watch(*self.watched_paths(), debounce=50, step=20,
                             rust_timeout=POLL_MS, yield_on_timeout=True):
            self.step({path for _change, path in changes})
            if until is not None and until(self):
                return
            if timeout_s is not None and time.monotonic() - start > timeout_s:
                return


def watch_options(*, jobs: int | None = None, report: bool = True,
                  date: str | None = None) -> Options:
    """The runner's options of a watched day: the run cache kept, no replay and no replay
    record (the outputs change run by run), the workers started per batch, nothing said
    about the jobs."""
    return Options(report=report, date=date, jobs=jobs, replay=False, record=False,
                   prestart=False, quiet=True)


def _print(line: str) -> None:
    print(line, flush=True)


def _strip_dot(text: str) -> str:
    return text.strip().rstrip(".")


def _inside(out: Path, data_dir: Path, file: str | None) -> bool:
    """Whether an unlisted file (its path relative to the data folder) is in the output
    folder (towtank's own outputs when the output folder is inside the data folder)."""
    if file is None:
        return False
    try:
        rel = out.resolve().relative_to(data_dir.resolve()).as_posix()
    except ValueError:
        return False
    return file.startswith(rel + "/") or file.startswith(f".{Path(rel).name}.")


def _fork(task: Callable[[], int]) -> int:
    """Run ``task`` in a forked process that ignores Ctrl-C (the parent's to handle), runs
    at a lower priority (:data:`CHILD_NICE`) and exits with what it returns; its id."""
    old = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        pid = os.fork()
        if pid == 0:  # the child: never returns
            code = 1
            try:
                signal.signal(signal.SIGINT, signal.SIG_IGN)
                signal.pthread_sigmask(signal.SIG_SETMASK, old)
                os.nice(CHILD_NICE)  # the next run's verdict comes first
                leave_inherited_alone()
                code = task()
            finally:
                os._exit(code)
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)
    return pid


def _end(pid: int) -> None:
    """Kill and reap a forked process."""
    try:
        os.kill(pid, signal.SIGKILL)
        os.waitpid(pid, 0)
    except (ProcessLookupError, ChildProcessError):
        pass


def _draw_fits_child(day: DayResult | None, live_dir: Path, listing: Path) -> int:
    """In the forked process: the fit figures into ``live_dir``, their names into
    ``listing`` (JSON); 0, or 1 when they could not be drawn."""
    try:
        drawn = _fit_figures(day, live_dir)
        listing.write_text(json.dumps(drawn), encoding="utf-8")
        return 0
    except BaseException as exc:  # noqa: BLE001 - the parent says it in one sentence
        return _failed_code(exc, live_dir)


def _fit_figures(day: DayResult | None, live_dir: Path) -> dict[str, str]:
    """The C_D(α) fit, the added-mass plot and the captive derivatives' figure (the horizontal
    plane's, else the vertical's: drift, arm, PMM and ω' against the fit) the day has, saved
    into ``live_dir``."""
    figs: dict[str, str] = {}
    if day is None:
        return figs
    captive = [draw for name, _, draw in rf.available_figures(day)
               if name in ("captive", "captive_vertical")]
    drawn = (("damping", rf.fig_damping(
                 day.hull, day.protocol.processing.damping_alpha_max_deg)),
             ("added_mass", rf.fig_added_mass(day.hull, day.reductions)),
             ("captive", captive[0](page=False) if captive else None))
    for key, fig in drawn:
        if fig is not None:
            figs[key] = save_figure(fig, live_dir, f"{key}.png")
    return figs


def next_run_lines(ranked: list[dict[str, Any]]) -> list[str]:
    """The terminal's lines of the next-run ranking: the sheet's top three, then the best
    condition not on the sheet (the page lists all), each with the targeted coefficient's
    half-width now and expected after."""
    lines = []
    sheet = [row for row in ranked if row["run"] is not None]
    new = [row for row in ranked if row["run"] is None]
    for row in sheet[:3] + new[:1]:
        now, after = row["half_width_now"], row["half_width_after"]
        widths = (f"{row['target']} ±{now:.3g} → ±{after:.3g}"
                  if now is not None and after is not None else str(row["target"]))
        kind = "next" if row["run"] is not None else "try "
        lines.append(f"  {kind} {row['rank']}. {row['description']}  ({widths})")
    return lines


def _span(runs: list[int]) -> str:
    return f"{runs[0]}–{runs[-1]}" if len(runs) > 1 else (str(runs[0]) if runs else "none")


def _draw_report(day: DayResult, folder: Path, *, beside: bool = True) -> int:
    """In the forked process: report.pdf (its page groups ``beside`` this process,
    :func:`~towtank.report.pdf.write_pdf`) and figures/ into ``folder`` (as the protocol's
    [report] asks), then the marker ``done``; 0, or 1 with the error in ``error.txt``."""
    try:
        folder.mkdir(parents=True)
        options = day.protocol.report
        if getattr(options, "pdf", True):
            write_pdf(day, folder, beside=beside)
        if getattr(options, "figures", True):
            write_figures(day, folder)
        (folder / "done").touch()
        return 0
    except BaseException as exc:  # noqa: BLE001 - told by the parent in one sentence
        try:
            (folder / "error.txt").write_text(f"{type(exc).__name__}: {exc}", encoding="utf-8")
        except OSError:
            pass
        return _failed_code(exc, folder)


def _failed_code(exc: BaseException, folder: Path) -> int:
    """The exit code of a forked drawing that failed with ``exc`` writing into ``folder``:
    :data:`STORAGE_EXIT` plus the errno for a failure of the storage, else 1."""
    full = storage_error(exc, folder)
    if full is not None and full.errno is not None and full.errno < 256 - STORAGE_EXIT:
        return STORAGE_EXIT + full.errno
    return 1


def _storage_errno(code: int) -> int | None:
    """The errno a forked drawing's exit code ``code`` carries (:func:`_failed_code`), or
    None."""
    number = code - STORAGE_EXIT
    return number if number in STORAGE_ERRNOS else None


def _link_new(src: str, dst: str) -> None:
    """:func:`_link_or_copy` where ``dst`` is not there yet (a file drawn by this write)."""
    if not os.path.lexists(dst):
        _link_or_copy(src, dst)


def _link_or_copy(src: str, dst: str) -> None:
    """A hard link (the file is never changed in place: towtank replaces, never rewrites),
    else a copy."""
    try:
        os.link(src, dst)
    except OSError:
        shutil.copy2(src, dst)
