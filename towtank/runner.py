"""One day from its protocol to its written outputs: the steps ``towtank process``,
:func:`towtank.process_day` and every batch of ``towtank watch`` share.

1. :func:`prepare`: the outputs an interrupted run left aside are put back, the protocol is
   loaded, the output folder checked, the replay fingerprint taken
   (:class:`towtank.runtime.cache.DayStamp`) and the number of worker processes settled;
2. :func:`reduce_day`: the day (or the rows of a run sheet) reduced and analysed
   (:func:`towtank.pipeline.process_day`, :func:`~towtank.pipeline.process_sheet`), the
   report's date set, and every file the day opened, whatever named it, among the day's
   inputs (:mod:`towtank.runtime.reads`);
3. :func:`write_day`: no input allowed to be an output's target, the outputs written under
   the folder's lock, the summary, and the replay record.

:func:`run_day` does the three in order, or replays the last run when nothing changed since.
Nothing here prints: the caller gets a :class:`DayRun` (the day, the exit status, the
summary and the notes for the terminal), or :class:`DayStopped`, a
:class:`~towtank.errors.ProtocolError` (exit status 2) carrying the notes said before the day
stopped. Nothing given is changed: each step returns new values.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from types import MappingProxyType
from typing import TYPE_CHECKING, Any

from towtank.errors import ProtocolError
from towtank.report.safetext import clean_text
from towtank.runtime.manifest import MANIFEST, output_lock, recover_outputs
from towtank.runtime.pause import pause_at
from towtank.runtime.reads import Stamp, recording
from towtank.runtime.safefile import sha256_regular
from towtank.runtime.storage import STORAGE_ERRNOS

if TYPE_CHECKING:
    import pandas as pd

    from towtank.ingest.protocol import Protocol
    from towtank.report.outputs import Writer
    from towtank.results import DayResult, Notice
    from towtank.runtime.cache import DayStamp

__all__ = ["DayRun", "DayStopped", "Options", "OutputsNotWritten", "Plan", "Reduced",
           "prepare", "reduce_day", "run_day", "summary", "write_day"]

EXIT_OK, EXIT_REJECTED = 0, 1

#: Towtank's own bookkeeping in the output folder, never an input of the day.
BOOKKEEPING = (".cache", MANIFEST)

_NOTHING: Mapping[str, Stamp] = MappingProxyType({})


@dataclass(frozen=True)
class Options:
    """How a day is run.

    report : the workbook, the PDF and the figures too (else the CSV tables and provenance).
    export : formats of the reduced time series ("mat", "hdf5", "parquet") into export/.
    date : the report's test date (YYYY-MM-DD) instead of the protocol's or the sheet's.
    cache : keep and reuse reduced runs in the output folder's ``.cache``.
    replay : a day unchanged since its last complete run is not processed again; its exit
        status and summary are given back (with ``cache``).
    record : remember this run for the next one's replay (with ``cache``).
    jobs : worker processes (default: the protocol's ``[processing] jobs``, else
        ``TOWTANK_JOBS``, else every core).
    prestart : start the workers while this process reads the sheet.
    debug : a bug in a run's reduction raises instead of rejecting the run.
    quiet : no note about the number of jobs.
    progress : called with (runs done, runs in all) while the runs are reduced.
    """

    report: bool = True
    export: tuple[str, ...] = ()
    date: str | None = None
    cache: bool = True
    replay: bool = True
    record: bool = True
    jobs: int | None = None
    prestart: bool = True
    debug: bool = False
    quiet: bool = False
    progress: Callable[[int, int], None] | None = None

    def fingerprint(self) -> dict[str, Any]:
        """The options that change the outputs, as the replay fingerprint holds them."""
        return {"report": self.report, "date": self.date,
                "export": sorted(set(self.export))}


@dataclass(frozen=True)
class Plan:
    """A day ready to be reduced (:func:`prepare`)."""

    path: Path  # the protocol file
    protocol: Protocol  # loaded; a note about the output folder among its warnings
    out: Path | None  # the output folder, resolved; None: nothing is written
    options: Options
    jobs: int | None  # settled (:func:`settle_jobs`)
    cache_dir: Path | None = None  # the run cache's folder, or None without one
    stamp: DayStamp | None = None
    #: (exit status, summary) of the last complete run when nothing changed since
    replay: tuple[int, str] | None = None
    #: every file opened while preparing (the protocol and what it names), with its stat
    read: Mapping[str, Stamp] = field(default_factory=lambda: _NOTHING)
    notes: tuple[str, ...] = ()  # sentences for the terminal


@dataclass(frozen=True)
class Reduced:
    """A reduced day (:func:`reduce_day`) and every file it opened, with its stat as opened."""

    day: DayResult
    read: Mapping[str, Stamp] = field(default_factory=lambda: _NOTHING)


@dataclass(frozen=True)
class DayRun:
    """What running a day gave: the day (None when the last run was replayed), the exit
    status (0 every run usable, 1 some rejected), the summary for the terminal (empty when
    nothing was written) and the notes for the terminal's error stream, in order."""

    day: DayResult | None
    code: int
    summary: str
    notes: tuple[str, ...] = ()


class DayStopped(ProtocolError):
    """The day cannot be run or written (exit status 2): ``str()`` the sentence, ``notes``
    what was said before it stopped (e.g. outputs put back)."""

    def __init__(self, sentence: str, notes: Iterable[str] = ()) -> None:
        super().__init__(sentence)
        self.notes = tuple(notes)


class OutputsNotWritten(DayStopped):
    """The storage refused the outputs (a full disk, a quota, a read-only file system):
    ``errno`` says which; the output folder is as it was."""

    def __init__(self, out: Path, errno: int, notes: Iterable[str] = ()) -> None:
        # the system's own words for the errno: a library's strerror may be a paragraph
        # (h5py's names its driver, the time and the buffer's address)
        super().__init__(f"the outputs could not be written to {out} ({os.strerror(errno)}); "
                         "the folder is as it was before this run.", notes)
        self.out = out
        self.errno = errno


def settle_jobs(asked: int | None, protocol: Protocol) -> tuple[int | None, str | None]:
    """The worker processes: ``asked``, else the protocol's ``[processing] jobs``, else the
    ``TOWTANK_JOBS`` environment variable, else None (every core), at most the cores this
    machine gives towtank; and the note saying so when more were asked for, or when the
    variable is set to something that is not a number of processes (it is then left aside)."""
    # loaded on use: multiprocessing's pools only when a day is run
    from towtank.runtime import parallel

    jobs = asked if asked is not None else protocol.processing.jobs
    if jobs is None:
        jobs, text = parallel.jobs_setting()
        if jobs is None and text:
            return None, (f"note: {parallel.JOBS_VARIABLE}={text[:40]!r} is not a whole number "
                          f"of at least 1: it is left aside and every core is used.")
    cores = parallel.default_jobs()
    if jobs is not None and jobs > cores:
        return cores, (f"note: {jobs} jobs asked for, but this machine gives towtank {cores} "
                       f"cores: {cores} jobs are used.")
    return jobs, None


def bookkeeping(out: Path | None) -> list[str | Path]:
    """The paths of towtank's own bookkeeping in ``out`` (:data:`BOOKKEEPING`)."""
    return [] if out is None else [Path(out).resolve() / name for name in BOOKKEEPING]


def prepare(protocol: str | Path | Protocol, out: str | Path | None = None,
            options: Options = Options(), *, write: bool = True) -> Plan:
    """Step 1: the protocol loaded (or taken as loaded), the output folder checked, the
    replay fingerprint taken and the jobs settled.

    Parameters
    ----------
    protocol : str, Path or Protocol
        The protocol file, or a protocol already loaded (the files it read when it was
        loaded, e.g. a tare table, are then not among the day's recorded inputs).
    out : str or Path, optional
        The output folder; default the protocol's ``output_dir``. A set of outputs an
        interrupted run left beside it is put back first.
    options : Options
    write : bool
        False: nothing will be written (no output folder, no replay).

    Raises
    ------
    DayStopped
        The protocol or the output folder is unusable.
    """
    notes: list[str] = []
    if out is not None and write:
        recovered = recover_outputs(Path(out).resolve())
        if recovered:
            notes.append(recovered)
    try:
        with recording() as opened:
            if isinstance(protocol, str | Path):
                # loaded on use: the protocol's checks (numpy and the water properties)
                from towtank.ingest.protocol import load_protocol

                loaded = load_protocol(protocol)
            else:
                loaded = protocol
            if getattr(loaded, "vehicle", None) is not None:
                # loaded on use: the vehicle's hull only for a protocol that describes one
                from towtank.vehicle.stage import geometry_problem

                problem = geometry_problem(loaded.vehicle)
                if problem is not None:  # a slip (mm for m) stops the day, as predict does
                    raise ProtocolError(f"{Path(loaded.path).name}: {problem}")
            folder, stamp, replay = None, None, None
            if write:
                # loaded on use: the protocol's checks, as above
                from towtank.ingest.protocol import with_output_dir

                loaded, folder = with_output_dir(
                    loaded, out if out is not None else loaded.campaign.output_dir)
                opened.skip.extend(bookkeeping(folder))
            if folder is not None and options.cache and (options.replay or options.record):
                # loaded on use: the cache (numpy) only when a day is written
                from towtank.runtime.cache import DayStamp

                stamp = DayStamp(folder / ".cache", loaded, folder, options.fingerprint())
                found = stamp.replay()  # first: the fingerprint before the day is read
                replay = found if options.replay else None
    except ProtocolError as exc:
        raise DayStopped(str(exc), notes) from exc
    jobs, note = settle_jobs(options.jobs, loaded)
    if note is not None and not options.quiet and replay is None:
        notes.append(note)
    cache = folder / ".cache" if folder is not None and options.cache else None
    return Plan(path=Path(loaded.path), protocol=loaded, out=folder, options=options,
                jobs=jobs, cache_dir=cache, stamp=stamp if options.record else None,
                replay=replay,
                read=MappingProxyType(dict(opened.files)), notes=tuple(notes))


def reduce_day(plan: Plan, sheet: pd.DataFrame | None = None, *, jobs: int | None = None,
               unlisted: list[Notice] | None = None) -> Reduced:
    """Step 2: the day reduced and analysed, its report date set and its inputs completed
    with every file it opened.

    Parameters
    ----------
    plan : Plan
    sheet : DataFrame, optional
        The run sheet's rows to process (``towtank watch``: those whose files are complete);
        default the protocol's whole sheet, read here.
    jobs : int, optional
        Worker processes for this day; default the plan's.
    unlisted : list of Notice, optional
        With ``sheet``: the warnings of the data files no row names (default: all of them).

    Raises
    ------
    ProtocolError
        The run sheet is unusable.
    """
    # loaded on use: the pipeline loads every stage
    from towtank import pipeline

    options = plan.options
    jobs = plan.jobs if jobs is None else jobs
    with recording(bookkeeping(plan.out)) as opened:
        if sheet is None:
            day = pipeline.process_day(plan.path, protocol=plan.protocol, jobs=jobs,
                                       progress=options.progress, debug=options.debug,
                                       cache_dir=plan.cache_dir)
        else:
            day = pipeline.process_sheet(plan.protocol, sheet, jobs=jobs,
                                         progress=options.progress, debug=options.debug,
                                         cache_dir=plan.cache_dir, unlisted=unlisted)
    if options.date:
        day = replace(day, report_date=options.date)
    read = dict(plan.read)
    for path, stat in opened.files.items():
        read.setdefault(path, stat)
    return Reduced(with_opened(day, read, plan.out), MappingProxyType(read))


def with_opened(day: DayResult, opened: Iterable[str], out: Path | None) -> DayResult:
    """The day with every file it opened (tare table, hull table, ...) among its inputs,
    with its sha256, for provenance.json: the files in the output folder aside. A new
    DayResult; ``day`` is not changed."""
    root = str(Path(out).resolve()) + os.sep if out is not None else None
    more = {}
    for path in opened:
        if path not in day.inputs and not (root is not None and path.startswith(root)):
            sha = sha256_regular(path)
            if sha is not None:
                more[path] = sha
    return replace(day, inputs={**day.inputs, **more}) if more else day


def write_day(plan: Plan, reduced: Reduced, *, writers: list[Writer] | None = None,
              keep: tuple[str, ...] | None = None,
              provenance_extra: dict[str, Any] | None = None) -> DayRun:
    """Step 3: no input of the day may be an output's target (the sheet may name run files
    anywhere), then the outputs written (:func:`towtank.report.outputs.write_day_outputs`),
    the summary made and, with the plan's stamp, the run recorded for the next one's replay;
    the lock spans the write and its record, so that another writer can neither mix its files
    with these nor have its outputs recorded as this day's.

    ``writers``, ``keep`` and ``provenance_extra`` as for
    :func:`~towtank.report.outputs.write_outputs` (``towtank watch``'s batches).

    Raises
    ------
    OutputsNotWritten
        The storage refused the outputs.
    DayStopped
        An input of the day is an output's target, or the output folder holds a file with
        an output's name that towtank did not write.
    """
    # loaded on use: the writers (pandas, provenance)
    from towtank.ingest.protocol import with_output_dir
    from towtank.report.outputs import KEPT, write_day_outputs

    out, options = plan.out, plan.options
    if out is None:
        raise ValueError("write_day needs a plan with an output folder")
    code = EXIT_REJECTED if reduced.day.rejected else EXIT_OK
    notes = list(plan.notes)
    try:
        with_output_dir(plan.protocol, out, reduced.day.inputs)
        with output_lock(out):
            day = write_day_outputs(reduced.day, out, report=options.report,
                                    writers=writers, keep=KEPT if keep is None else keep,
                                    export=options.export,
                                    provenance_extra=provenance_extra, jobs=plan.jobs)
            text = summary(day, out)
            if plan.stamp is not None:
                changed = plan.stamp.record(code, text, {**reduced.read, **read_stamps(day)})
                if changed:
                    notes.append(f"warning: {changed}")
    except ProtocolError as exc:
        raise DayStopped(str(exc), notes) from exc
    except OSError as exc:
        if exc.errno is None or exc.errno not in STORAGE_ERRNOS:
            raise
        raise OutputsNotWritten(out, exc.errno, notes) from exc
    return DayRun(day, code, text, tuple(notes))


def run_day(protocol: str | Path | Protocol, out: str | Path | None = None,
            options: Options = Options(), *, write: bool = True) -> DayRun:
    """A day from its protocol to its written outputs (steps 1 to 3), or the last run's exit
    status and summary when nothing changed since (``options.replay``).

    Parameters
    ----------
    protocol : str, Path or Protocol
        See :func:`prepare`.
    out : str or Path, optional
        The output folder; default the protocol's ``output_dir``.
    options : Options
    write : bool
        False: the day is only reduced (``DayRun.summary`` empty).

    Raises
    ------
    DayStopped
        Exit status 2: the protocol, the run sheet or the output folder is unusable;
        nothing was written.
    """
    plan = prepare(protocol, out, options, write=write)
    if plan.replay is not None:  # nothing changed since the last run: its outputs stand
        code, text = plan.replay
        return DayRun(None, code, text, plan.notes)
    # loaded on use: multiprocessing's pools only when a day is run
    from towtank.runtime import parallel

    if options.prestart:
        # the workers load the reduction's libraries while this process reads the sheet
        parallel.prestart(plan.jobs)
    try:
        pause_at("preload")
        reduced = reduce_day(plan)
        if plan.out is None:
            day = reduced.day
            return DayRun(day, EXIT_REJECTED if day.rejected else EXIT_OK, "", plan.notes)
        return write_day(plan, reduced)
    except DayStopped:
        raise
    except ProtocolError as exc:
        raise DayStopped(str(exc), plan.notes) from exc
    except KeyboardInterrupt:  # the workers and the fork server ignore Ctrl-C: ended here
        parallel.discard_prestarted(interrupted=True)
        parallel.end_forkserver()
        raise
    finally:
        parallel.discard_prestarted()  # when the day stopped before any run was reduced


def read_stamps(day: DayResult) -> dict[str, Stamp | None]:
    """Every input file of the day with its (size, mtime_ns, ctime_ns, inode): the run files
    as their bytes were read, the other inputs as they are now."""
    out: dict[str, Stamp | None] = {}
    for path in day.inputs:
        try:
            st = os.stat(path)
            out[str(path)] = (st.st_size, st.st_mtime_ns, st.st_ctime_ns, st.st_ino)
        except OSError:
            continue  # a file that could not be read: its run was rejected
    data_dir = day.protocol.campaign.data_dir
    for red in day.reductions.values():
        path = str(data_dir / red.file)
        if path in out:
            out[path] = red.file_stamp
    return out


def summary(day: DayResult, out: Path) -> str:
    """The lines ``towtank process`` prints: the counts, the rejections grouped, the
    warnings and the output folder."""
    runs = day.runs
    counts = runs["status"].value_counts()
    lines = [
        f"{day.protocol.name}: {len(runs)} runs, {counts.get('ok', 0)} ok, "
        f"{counts.get('rejected', 0)} rejected, {counts.get('void', 0)} void{day.means_text}"
    ]
    # loaded on use: pandas only when runs were rejected
    from towtank.analysis.daywide import group_rejections

    lines += [f"  rejected: {g.sentence}" for g in group_rejections(runs, day.rejected)]
    lines += [f"  warning: {w}" for w in day.warnings]
    lines.append(f"outputs in {out}")
    # no escape sequence from a file reaches the terminal
    return "\n".join(clean_text(line) for line in lines) + "\n"
