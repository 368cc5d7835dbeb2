"""The day's inputs: which runs of the sheet are reduced, which data files it leaves out, and
the sha256 of every input (provenance.json).

:func:`runs_to_reduce` decides the rejections the sheet alone makes (a row's own error, a file
two rows name, a path that cannot be opened) as :class:`towtank.messages.Rejection` objects;
:func:`unlisted_warnings` warns of the data files no row names; :func:`day_inputs` hashes the
protocol, the sheet, a reference CSV, the run files and their side files (carriage logs, zeros
files: :func:`side_files`).
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import pandas as pd

from towtank.ingest import readers
from towtank.ingest.protocol_types import Protocol, SpeedLog, ZeroFile
from towtank.ingest.runsheet import NUMERIC, REQUIRED, read_run_sheet, unlisted_files
from towtank.ingest.sections import check_captive_runs
from towtank.ingest.speedlog import log_path, log_sha
from towtank.messages import Notice, Rejection
from towtank.reference.sets import BUILTIN_REFERENCES
from towtank.runtime.pathcheck import is_regular_file, resolved

__all__ = ["day_inputs", "file_sha", "runs_to_reduce", "side_files", "side_files_sha",
           "unlisted_warnings"]


def side_files(protocol: Protocol) -> list[SpeedLog | ZeroFile]:
    """The protocol's per-run side files: carriage log ([speed_log]), zeros file ([zeros])."""
    return [spec for spec in (protocol.speed_log, protocol.zeros) if spec is not None]


def side_files_sha(protocol: Protocol, file: str, run: int) -> str:
    """The sha256 of the run's side files one after the other ("" without any): part of its
    cache key, since its reduction depends on their bytes as on the run file's."""
    return "".join(log_sha(spec, protocol.campaign.data_dir, file, run)
                   for spec in side_files(protocol))


def unlisted_warnings(protocol: Protocol, sheet: pd.DataFrame) -> list[Notice]:
    """A warning per data file that no sheet row names (side files of the runs aside)."""
    logs = {log_path(spec, Path("."), str(f), int(r)).as_posix()
            for spec in side_files(protocol)
            for r, f in zip(sheet["run"], sheet["file"], strict=True)}
    return [Notice(f"{f} is in the data folder but not in the run sheet; it is ignored.",
                   "sheet", file=f)
            for f in unlisted_files(sheet, protocol.campaign.data_dir) if f not in logs]


def runs_to_reduce(protocol: Protocol, sheet: pd.DataFrame) -> tuple[
        list[dict[str, Any]], dict[int, Rejection]]:
    """The sheet rows to reduce, and the rejections the sheet alone decides (a row's own
    error, a file named by two rows, a path that cannot be opened); void rows are neither."""
    rejected: dict[int, Rejection] = {}
    todo = []
    first_run_of: dict[Path, int] = {}
    for rec in sheet.to_dict("records"):
        if rec["status"] == "void":  # listed, never used: a void row's faults do not matter
            continue
        run, file = int(rec["run"]), str(rec["file"])
        if rec["sheet_error"]:
            rejected[run] = Rejection(run, file, "sheet", str(rec["sheet_error"]), "sheet",
                                      file_prefix=False)
            continue
        path = resolved(protocol.campaign.data_dir / file)
        if isinstance(path, str):  # a loop of symbolic links; a name too long
            rejected[run] = Rejection(run, file, "sheet", f"{file} cannot be opened ({path}).",
                                      "unreadable", file_prefix=False)
            continue
        if path in first_run_of:  # one recording cannot be two runs: a copy-paste in the sheet
            rejected[run] = Rejection(
                run, file, "sheet",
                f"{file} is also the file of run {first_run_of[path]} in the sheet; a "
                "recording is one run (a copied cell?)", "duplicate_file", file_prefix=False)
            continue
        first_run_of[path] = run
        todo.append(rec)
    return todo, rejected


def day_inputs(protocol: Protocol, sheet: pd.DataFrame,
               known: Mapping[str, str]) -> dict[str, str]:
    """sha256 of every input of the day: protocol, sheet, a reference CSV, every file the
    sheet names (rejected runs' too) and the runs' side files. ``known``: the sha256 of run
    files already read (file as the sheet names it -> sha256), not read again."""
    inputs = {str(protocol.path): file_sha(protocol.path),
              str(protocol.campaign.run_sheet): file_sha(protocol.campaign.run_sheet)}
    if protocol.campaign.reference not in BUILTIN_REFERENCES:  # a user CSV is an input too
        inputs[str(protocol.campaign.reference)] = file_sha(Path(protocol.campaign.reference))
    for file in sheet["file"]:
        path = protocol.campaign.data_dir / str(file)
        if str(file) in known:
            inputs[str(path)] = known[str(file)]
        elif str(file) and is_regular_file(path):
            inputs[str(path)] = file_sha(path, readers.MAX_RUN_FILE_BYTES)
    for spec in side_files(protocol):  # the carriage logs and zeros files are inputs too
        for run, file in zip(sheet["run"], sheet["file"], strict=True):
            log = log_path(spec, protocol.campaign.data_dir, str(file), int(run))
            if is_regular_file(log):
                inputs[str(log)] = file_sha(log)
    return inputs


def file_sha(path: Path, max_bytes: int | None = None) -> str:
    """sha256 of a file read in blocks (a file of any size in little memory), or "" when it
    cannot be read or is larger than ``max_bytes`` [bytes] (a run file over
    :data:`towtank.ingest.readers.MAX_RUN_FILE_BYTES` is refused before it is read: it is not
    read to be hashed either; its run is rejected anyway)."""
    try:
        with open(path, "rb") as f:
            if max_bytes is not None and os.fstat(f.fileno()).st_size > max_bytes:
                return ""
            return hashlib.file_digest(f, "sha256").hexdigest()
    except OSError:
        return ""

#: The columns of a day's sheet that has no run (a protocol with ``[captive] means`` alone).
EMPTY_SHEET_COLUMNS = (*REQUIRED, "test", "speed_nominal", "accel_nominal", "tare_group",
                       "water_temp_C", "status", "remarks", "window_start_s", "window_end_s",
                       "sheet_row", "sheet_error")


def day_sheet(protocol: Protocol) -> pd.DataFrame:
    """The protocol's run sheet read (:func:`read_run_sheet`) and its captive runs checked
    against the [model] (:func:`towtank.ingest.sections.check_captive_runs`); a protocol with
    ``[captive] means`` and no run sheet has a sheet with no row.

    Raises ProtocolError for a sheet that cannot be used."""
    if not protocol.campaign.sheet_given:
        return pd.DataFrame({c: pd.Series(dtype=float if c in NUMERIC or c in (
            "run", "angle_deg", "sheet_row") else object) for c in EMPTY_SHEET_COLUMNS})
    sheet = read_run_sheet(protocol.campaign.run_sheet, protocol.water.temperature_C,
                           protocol.sheet, air=protocol.water.is_air)
    check_captive_runs(sheet, protocol.model, protocol.captive, protocol.path.name)
    return sheet
