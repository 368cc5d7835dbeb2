"""Write the day's outputs atomically (docs/formats.md §5)."""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import tempfile
import time
from collections.abc import Callable
from dataclasses import replace
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, Any

import towtank.report.tables as tables
from towtank.ingest.protocol import OUTPUT_NAMES
from towtank.report.export import export_runs
from towtank.report.provenance import provenance
from towtank.runtime import interrupt, manifest
from towtank.runtime.parallel import fork_beside, run_beside
from towtank.runtime.storage import storage_error

if TYPE_CHECKING:
    from towtank.results import DayResult


def _swap_into_place(tmp: Path, out_dir: Path) -> None:
    """Replace ``out_dir`` by ``tmp`` with renames (atomic on one file system).

    The old folder is removed only if it holds nothing but towtank's outputs: an entry that
    appeared in it after the check (the user saving a file at that moment) is moved into the
    new folder, and if that cannot be done the old folder is left where it is, named.
    """
    if out_dir.exists():
        old = Path(tempfile.mkdtemp(prefix=f".{out_dir.name}.old-", dir=out_dir.parent))
        old.rmdir()
        os.rename(out_dir, old)
        try:
            os.rename(tmp, out_dir)
        except OSError:
            os.rename(old, out_dir)
            raise
        kept = []
        for name in foreign_entries(old, keep=()):
            try:
                if os.path.lexists(out_dir / name):
                    raise FileExistsError(name)
                os.rename(old / name, out_dir / name)
            except OSError:
                kept.append(name)
        if not kept:
            shutil.rmtree(old, ignore_errors=True)
    else:
        os.rename(tmp, out_dir)


INCOMPLETE_TEXT = (
    "towtank is replacing the outputs in this folder one by one (the folder also holds files "
    "towtank did not write, which it leaves alone). If this file is still here, that run was "
    "interrupted: the outputs are a mix of two runs. Process the day again.\n"
)


def _replace_entries(tmp: Path, out_dir: Path) -> None:
    """Put the entries of ``tmp`` into ``out_dir`` one by one, each by a rename.

    Used when ``out_dir`` holds files towtank did not write: those are left alone. While the
    entries are swapped, ``OUTPUTS-INCOMPLETE.txt`` says that the set is mixed and the manifest
    lists both sets; earlier towtank outputs the new set lacks (e.g. fins.csv of a fin day)
    are removed; provenance.json goes last, then the new manifest, then the marker goes.
    """
    new_files = manifest.describe(tmp, OUTPUT_NAMES)
    old = manifest.read_manifest(out_dir)
    both = {k: list(v) for k, v in (old["files"] if old else {}).items()}
    for key, entries in new_files.items():
        both.setdefault(key, []).extend(entries)
    marker = INCOMPLETE_TEXT.encode()
    both[manifest.INCOMPLETE] = [{"size": len(marker), "mtime_ns": -1,
                                  "sha256": hashlib.sha256(marker).hexdigest()}]
    manifest.write_manifest(out_dir, both, complete=False)
    manifest.atomic_write_text(out_dir / manifest.INCOMPLETE, INCOMPLETE_TEXT)
    names = sorted(p.name for p in tmp.iterdir() if p.name != manifest.MANIFEST)
    names.sort(key=lambda n: n == "provenance.json")
    for name in names:
        src, dst = tmp / name, out_dir / name
        if src.is_dir():
            old_dir = None
            if dst.exists():
                old_dir = Path(tempfile.mkdtemp(prefix=f".{name}.old-", dir=out_dir))
                old_dir.rmdir()
                os.rename(dst, old_dir)
            os.rename(src, dst)
            if old_dir is not None:
                shutil.rmtree(old_dir, ignore_errors=True)
        else:
            os.replace(src, dst)
    for name in OUTPUT_NAMES.difference(names):  # ours: foreign ones stopped the day before
        stale = out_dir / name
        if stale.is_dir() and not stale.is_symlink():
            shutil.rmtree(stale, ignore_errors=True)
        elif stale.is_file() and not stale.is_symlink():
            stale.unlink()
    others = {rel: entries for rel, entries in (old["files"] if old else {}).items()
              if rel.split("/")[0] not in OUTPUT_NAMES and rel != manifest.INCOMPLETE
              and manifest.known(out_dir / rel, entries)}  # e.g. simulate's files
    manifest.write_manifest(out_dir, {**others, **new_files}, complete=True)
    (out_dir / manifest.INCOMPLETE).unlink(missing_ok=True)
    shutil.rmtree(tmp, ignore_errors=True)


#: A temporary output folder older than this was left by a killed run [s].
STALE_TEMPORARY_S = 600.0


def sweep_stale_temporaries(out_dir: Path, max_age_s: float = STALE_TEMPORARY_S) -> list[Path]:
    """Remove the temporary folders a killed run left beside ``out_dir`` (older than
    ``max_age_s`` [s], so that a run writing at the same time keeps its own); return them."""
    now = time.time()
    gone = []
    for pattern in (f".{out_dir.name}.tmp-*", f".{out_dir.name}.old-*"):
        for path in out_dir.parent.glob(pattern):
            try:
                if path.is_dir() and now - path.stat().st_mtime > max_age_s:
                    shutil.rmtree(path)
                    gone.append(path)
            except OSError:
                pass
    return gone


#: Towtank's own folders kept across output swaps: the run cache and watch's live state.
KEPT = (".cache", ".live")


def foreign_entries(out_dir: Path, keep: tuple[str, ...] = KEPT) -> list[str]:
    """Names in ``out_dir`` that are not towtank's outputs (nor kept, e.g. the cache): the
    user's, and anything else, whatever its name (a leftover of a killed run too: it is left
    alone rather than risk deleting a file of the user's that looks like one)."""
    if not out_dir.is_dir():
        return []
    return sorted(
        p.name for p in out_dir.iterdir()
        if p.name not in OUTPUT_NAMES and p.name not in keep
        and p.name not in (manifest.MANIFEST, manifest.INCOMPLETE)
    )


def refuse_foreign_outputs(out_dir: Path) -> None:
    """Stop (ProtocolError) when ``out_dir`` holds an entry with an output's name that towtank
    did not write (:func:`towtank.runtime.manifest.refuse_foreign`)."""
    manifest.refuse_foreign(out_dir, OUTPUT_NAMES)


Writer = Callable[["DayResult", Path], object]  # what a writer returns is not used


def write_outputs(day: DayResult, out_dir: str | Path, **options: Any) -> Path:
    """Write every output of the day into ``out_dir``, replacing the previous outputs;
    ``options`` and the errors as for :func:`write_day_outputs`. Returns the folder, resolved.
    """
    write_day_outputs(day, out_dir, **options)
    return Path(out_dir).resolve()


def write_day_outputs(
    day: DayResult,
    out_dir: str | Path,
    *,
    report: bool = True,
    writers: list[Writer] | None = None,
    keep: tuple[str, ...] = KEPT,
    export: tuple[str, ...] | list[str] = (),
    provenance_extra: dict[str, Any] | None = None,
    jobs: int | None = None,
) -> DayResult:
    """Write every output of the day into ``out_dir``, replacing the previous outputs, and
    return the day as written.

    Parameters
    ----------
    day : DayResult
        The processed day; it is not changed.
    out_dir : path
        Output folder; created if needed. Nothing is written there before the new set is
        complete in a temporary folder beside it. A folder holding only towtank's outputs is
        then replaced as a whole by one rename (entries named in ``keep``, e.g. the cache, are
        carried over); in a folder that also holds other files, each output is replaced by its
        own rename and the other files are left untouched.
    report : bool
        Also write the workbook, the PDF and the figures.
    writers : list, optional
        The report's writers, each called with the day and the folder (default: the
        workbook, the PDF and the figures).
    keep : tuple of str
        Entries of ``out_dir`` carried over into the new set (default :data:`KEPT`).
    export : sequence of str
        Also write every usable run's reduced time series in these formats ("mat", "hdf5",
        "parquet") into ``export/`` (:mod:`towtank.report.export`).
    provenance_extra : dict, optional
        More entries for provenance.json (``towtank watch``: which runs the PDF covers).
    jobs : int, optional
        Processes the report may use (default: every core). With one (asked for, or the
        machine's only core) the writers and the PDF's page groups run in this process one
        after another; else beside each other (:func:`run_writers`). The files are the same.

    Returns
    -------
    DayResult
        ``day``, or with ``export`` a new DayResult whose warnings add the runs that could not
        be exported.

    Raises
    ------
    OSError
        When the storage fails (a full disk, a quota...), with its errno, whatever library met
        it (:func:`towtank.runtime.storage.storage_error`); ``out_dir`` is then as it was and
        the temporary folder is gone.
    """
    out_dir = Path(out_dir).resolve()
    out_dir.parent.mkdir(parents=True, exist_ok=True)
    with manifest.output_lock(out_dir):  # two writers never mix their files
        return _write_outputs(day, out_dir, report=report, writers=writers, keep=keep,
                              export=export, provenance_extra=provenance_extra,
                              beside=fork_beside(jobs))


def _write_outputs(day: DayResult, out_dir: Path, *, report: bool,
                   writers: list[Writer] | None, keep: tuple[str, ...],
                   export: tuple[str, ...] | list[str],
                   provenance_extra: dict[str, Any] | None = None,
                   beside: bool = True) -> DayResult:
    manifest.recover_outputs(out_dir)
    refuse_foreign_outputs(out_dir)
    sweep_stale_temporaries(out_dir)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out_dir.name}.tmp-", dir=out_dir.parent))
    manifest.folder_mode(tmp, out_dir if out_dir.is_dir() else None)
    try:
        if export:  # first: a run that cannot be exported is a warning of the report
            # loaded on use: towtank.results loads the analysis stages, which a day's
            # writing without an export never needs here
            from towtank.results import notices

            said = notices(export_runs(day, tmp, tuple(export)), "export")
            day = replace(day, warnings=(*day.warnings,
                                         *(n for n in said if n not in day.warnings)))
        tables.write_tables(day, tmp)
        if getattr(day, "vehicle", None) is not None:  # predicted.csv, model.json
            # loaded on use: report.vehicle loads matplotlib, which
            # a day written without its report (report=False) never needs
            from towtank.report.vehicle import write_vehicle

            write_vehicle(day, tmp, figure=report)
        if report:
            run_writers(writers or _report_writers(beside=beside), day, tmp, beside=beside)
        (tmp / "provenance.json").write_text(
            json.dumps(provenance(day, provenance_extra), indent=2, sort_keys=False,
                       default=str) + "\n",
            encoding="utf-8",
        )
        manifest.write_manifest(tmp, manifest.describe(tmp, OUTPUT_NAMES))  # marks it complete
        interrupt.check()  # a Ctrl-C that a library dropped still stops the day here
        refuse_foreign_outputs(out_dir)  # again: a file may have appeared while we worked
        if foreign_entries(out_dir, keep):
            # a folder with the user's own files in it: replace our entries one by one and
            # leave everything else (and the kept cache) where it is
            _replace_entries(tmp, out_dir)
            return day
        moved = []
        for name in keep:  # carried over by a rename, not a copy: the cache can be large
            src = out_dir / name
            if src.exists() and not (tmp / name).exists():
                os.rename(src, tmp / name)
                moved.append(name)
        try:
            _swap_into_place(tmp, out_dir)
        except BaseException:
            for name in moved:
                os.rename(tmp / name, out_dir / name)
            raise
    except BaseException as exc:
        # a full disk is told while the partial outputs still fill it, and is an OSError
        # whatever library met it (zlib.error from the PDF, a writer's forked process)
        full = storage_error(exc, tmp)
        shutil.rmtree(tmp, ignore_errors=True)
        if full is not None and full is not exc:
            raise full from exc
        raise
    return day


def run_writers(writers: list[Writer], day: DayResult, folder: Path, *,
                beside: bool = True) -> None:
    """Run the report writers, the first in this process and the others beside it.

    Each writer writes its own files into ``folder`` and shares nothing with the others, so the
    later ones run in forked processes while this one draws the first (the PDF, the longest):
    the report takes about the time of its longest part
    (:func:`towtank.runtime.parallel.run_beside`); without ``beside`` they run here one after
    another. A writer that fails, here or in its process, fails the whole report (the caller
    then writes nothing).
    """
    run_beside([(_writer_name(w), partial(w, day, folder)) for w in writers], fork=beside)


def _writer_name(writer: Writer) -> str:
    return getattr(writer, "__name__", type(writer).__name__)


def _report_writers(*, beside: bool = True) -> list[Writer]:
    """The report's writers: report.xlsx, report.pdf and figures/*.png (the PDF's page
    groups drawn ``beside`` this process, :func:`~towtank.report.pdf.write_pdf`).

    The protocol's [report] table may turn the PDF (``pdf = false``) or the PNG figures
    (``figures = false``) off; the workbook is always written.
    """
    # loaded on use: the report's writers load matplotlib and openpyxl, which a day written
    # without its report never needs
    from towtank.report.figures import write_figures
    from towtank.report.pdf import write_pdf
    from towtank.report.workbook import write_workbook

    def wanted(day: DayResult, option: str) -> bool:
        return bool(getattr(getattr(day.protocol, "report", None), option, True))

    def pdf(day: DayResult, folder: Path) -> None:
        if wanted(day, "pdf"):
            write_pdf(day, folder, beside=beside)

    def figures(day: DayResult, folder: Path) -> None:
        if wanted(day, "figures"):
            write_figures(day, folder)

    return [pdf, figures, write_workbook]  # the longest first: see run_writers
