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
    the report takes about the time of its longest part (:func:`towtank.parallel.run_beside`).
    A writer that fails, here or in its process, fails the whole report (the caller then
    writes nothing).
    """
    from functools import partial

    from towtank.parallel import run_beside

    run_beside([(_writer_name(w), partial(w, day, folder)) for w in writers])


def _writer_name(writer: Writer) -> str:
    return getattr(writer, "__name__", type(writer).__name__)


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
