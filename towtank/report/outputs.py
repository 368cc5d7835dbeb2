"""Write the day's outputs atomically (FORMATS.md §5)."""

from __future__ import annotations

import json
import os
import platform
import shutil
import tempfile
from collections.abc import Callable
from dataclasses import asdict
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pandas as pd

from towtank import __version__

if TYPE_CHECKING:
    from towtank.pipeline import DayResult


def write_csv(df: pd.DataFrame, path: Path) -> None:
    """A deterministic CSV: full float precision, '\\n' line ends, no index."""
    df.to_csv(path, index=False, lineterminator="\n")


def provenance(day: DayResult, extra: dict[str, Any] | None = None) -> dict[str, Any]:
    """Inputs with their sha256, program and library versions, settings used."""
    import numpy
    import scipy

    p = day.protocol
    settings = {
        "processing": asdict(p.processing),
        "trim_s_used": p.processing.trim,
        "water": asdict(p.water),
        "channels": {k: asdict(v) for k, v in p.channels.items()},
        "reference": p.campaign.reference,
    }
    return {
        "program": "towtank",
        "version": __version__,
        "python": platform.python_version(),
        "libraries": {
            "numpy": numpy.__version__,
            "scipy": scipy.__version__,
            "pandas": pd.__version__,
        },
        "protocol": str(p.path),
        "campaign": p.campaign.name,
        "inputs": [{"path": k, "sha256": v} for k, v in day.inputs.items()],
        "settings": settings,
        "runs": {"total": int(len(day.sheet)), "rejected": day.n_rejected},
        **(extra or {}),
    }


def _swap_into_place(tmp: Path, out_dir: Path) -> None:
    """Replace ``out_dir`` by ``tmp`` with renames (atomic on one file system)."""
    if out_dir.exists():
        old = Path(tempfile.mkdtemp(prefix=f".{out_dir.name}.old-", dir=out_dir.parent))
        old.rmdir()
        os.rename(out_dir, old)
        try:
            os.rename(tmp, out_dir)
        except OSError:
            os.rename(old, out_dir)
            raise
        shutil.rmtree(old, ignore_errors=True)
    else:
        os.rename(tmp, out_dir)


Writer = Callable[["DayResult", Path], None]


def write_outputs(
    day: DayResult,
    out_dir: str | Path,
    *,
    report: bool = True,
    writers: list[Writer] | None = None,
    keep: tuple[str, ...] = (".cache",),
) -> Path:
    """Write every output of the day into ``out_dir``, replacing it as a whole.

    Parameters
    ----------
    day : DayResult
        The processed day.
    out_dir : path
        Output folder; created if needed. Its previous content is replaced only once the new
        set is complete (entries named in ``keep``, e.g. the cache, are carried over).
    report : bool
        Also write the workbook, the PDF and the figures.
    """
    out_dir = Path(out_dir).resolve()
    out_dir.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out_dir.name}.tmp-", dir=out_dir.parent))
    try:
        from towtank.report import tables

        tables.write_tables(day, tmp)
        if report:
            run_writers(writers or _report_writers(), day, tmp)
        (tmp / "provenance.json").write_text(
            json.dumps(provenance(day), indent=2, sort_keys=False, default=str) + "\n",
            encoding="utf-8",
        )
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
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return out_dir


def run_writers(writers: list[Writer], day: DayResult, folder: Path) -> None:
    """Run the report writers, the first in this process and the others beside it.

    Each writer writes its own files into ``folder`` and shares nothing with the others, so the
    later ones run in forked processes while this one draws the first (the PDF, the longest):
    the report takes about the time of its longest part. Where forking is not available or not
    safe (another thread is running) they run one after another. A writer that fails, here or
    in its process, fails the whole report (the caller then writes nothing).
    """
    import multiprocessing as mp
    import threading

    if len(writers) < 2 or "fork" not in mp.get_all_start_methods() or (
        threading.active_count() > 1
    ):
        for writer in writers:
            writer(day, folder)
        return
    ctx = mp.get_context("fork")
    children = []
    for writer in writers[1:]:
        recv, send = ctx.Pipe(duplex=False)
        proc = ctx.Process(target=_write_in_child, args=(writer, day, folder, send), daemon=True)
        proc.start()
        send.close()
        children.append((writer, proc, recv))
    failures: list[tuple[str, str]] = []
    try:
        writers[0](day, folder)
    finally:
        for writer, proc, recv in children:
            try:
                outcome = recv.recv()
            except EOFError:
                outcome = ("the process writing it stopped abruptly", "")
            proc.join()
            recv.close()
            if outcome is not None:
                failures.append((f"{_writer_name(writer)}: {outcome[0]}", outcome[1]))
    if failures:
        exc = RuntimeError("; ".join(f for f, _ in failures))
        for _, trace in failures:
            if trace:
                exc.add_note(trace)
        raise exc


def _writer_name(writer: Writer) -> str:
    return getattr(writer, "__name__", type(writer).__name__)


def _write_in_child(writer: Writer, day: DayResult, folder: Path, send: Any) -> None:
    """In a forked process: one writer; sends None, or (error, traceback)."""
    import traceback

    try:
        writer(day, folder)
        outcome = None
    except BaseException as exc:  # noqa: BLE001 - reported to the parent, which raises
        outcome = (f"{type(exc).__name__}: {exc}", traceback.format_exc())
    send.send(outcome)
    send.close()


def _report_writers() -> list[Writer]:
    """The report's writers: report.xlsx, report.pdf and figures/*.png.

    The protocol's [report] table may turn the PDF (``pdf = false``) or the PNG figures
    (``figures = false``) off; the workbook is always written.
    """
    from towtank.report.figures import write_figures
    from towtank.report.pdf import write_pdf
    from towtank.report.workbook import write_workbook

    def wanted(day: DayResult, option: str) -> bool:
        return bool(getattr(getattr(day.protocol, "report", None), option, True))

    def pdf(day: DayResult, folder: Path) -> None:
        if wanted(day, "pdf"):
            write_pdf(day, folder)

    def figures(day: DayResult, folder: Path) -> None:
        if wanted(day, "figures"):
            write_figures(day, folder)

    return [pdf, figures, write_workbook]  # the longest first: see run_writers
