"""Reading cost per file layout: ``python -m towtank.testing.bench_read [--repeat 5]``.

Separate from the unit tests. It writes the same synthetic hull day (41 runs at 1 kHz, lab
channels in volts) in every layout towtank reads (:mod:`towtank.testing.layouts`: plain CSV,
TDMS with and without a time channel, LVM, European text, MATLAB v5 and v7.3, HDF5) into a work
folder, warms the page cache, and times :func:`towtank.ingest.runfile.load_run` (read, map,
calibrate, check) of every run file of each layout in this one process, best of ``--repeat``.
Each layout's time is reported as a ratio to the plain CSV day's, measured in the same run.
The target: a TDMS or .mat run costs no more than 1.5 × the same run as CSV.

``--wide-columns N`` times instead one file of very many columns (N, and ``--wide-rows``
rows), as LVM and as the same table in CSV: reading it, loading it as a run (rejected: it has
none of the day's channels; the sentence's length is reported) and, with ``--wide-day``, the
LVM hull day (41 runs) with this file as one more run, processed in this process. Reading
time grows linearly with the columns; the target: the LVM costs no more than 2 × the CSV.
"""

from __future__ import annotations

import argparse
import functools
import io
import json
import shutil
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from towtank.errors import RunError
from towtank.ingest.protocol import load_protocol
from towtank.ingest.protocol_types import ChannelMap
from towtank.ingest.runfile import file_bytes, load_run, read_columns
from towtank.testing import synthetic as syn
from towtank.testing.layouts import layout_channels, protocol_sections

if TYPE_CHECKING:
    from towtank.testing.truth import FileFormat

LAYOUTS: tuple[FileFormat, ...] = ("csv", "tdms", "tdms-waveform", "mat", "mat73", "hdf5", "lvm",
                                   "txt-eu")
TARGET = 1.5  # largest time ratio to CSV for the TDMS and MATLAB layouts
WIDE_TARGET = 2.0  # largest time ratio to CSV of the wide LVM file


def _write(root: Path, layout: FileFormat, seed: int) -> Path:
    day = root / layout
    proto = day / "protocol.toml"
    if proto.is_file():
        return proto
    syn.make_hull_day(day, seed=seed, file_format=cast(Any, layout), sheet_format="csv",
                      channel_style="lab")
    channels = layout_channels(layout, syn.LabChannels())
    sections = syn.hull_protocol_sections(".", "out", sheet_format="csv", channels=channels,
                                          channel_style="lab")
    laid_out: dict[str, Any] = protocol_sections(layout, sections)
    return syn.write_protocol(proto, **laid_out)


def time_layout(protocol_path: Path, repeat: int) -> tuple[float, int, int]:
    """(best time to load every run file [s], files, bytes) of one day."""
    protocol = load_protocol(protocol_path)
    data_dir = protocol.campaign.data_dir
    files = sorted(p for p in data_dir.iterdir() if p.is_file())
    blobs = [(p, file_bytes(p)) for p in files]  # warm: every file read once
    p = protocol.processing
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        for path, _data in blobs:
            load_run(path, protocol.channels, max_nan_gap_s=p.max_nan_gap_s,
                     max_bad_row_fraction=p.max_bad_row_fraction, do_despike=p.despike,
                     data=file_bytes(path), options=protocol.read, balance=protocol.balance)
        best = min(best, time.perf_counter() - t0)
    return best, len(blobs), sum(len(d) for _, d in blobs)


def run_bench(workdir: Path, *, repeat: int = 5, seed: int = 3) -> dict[str, dict[str, float]]:
    workdir.mkdir(parents=True, exist_ok=True)
    protocols = {layout: _write(workdir, layout, seed) for layout in LAYOUTS}
    out: dict[str, dict[str, float]] = {}
    for layout, proto in protocols.items():
        seconds, n, size = time_layout(proto, repeat)
        out[layout] = {"seconds": seconds, "files": n, "mb": size / 1e6,
                       "ms_per_file": 1e3 * seconds / n}
    base = out["csv"]["seconds"]
    for res in out.values():
        res["over_csv"] = res["seconds"] / base
    return out


def wide_table(n_columns: int, n_rows: int, seed: int = 0) -> tuple[list[str], np.ndarray]:
    """(column names ``c1``…, values [n_rows × n_columns]) of a wide file; the first column
    is the time [s] at 1 kHz."""
    rng = np.random.default_rng(seed)
    values = np.round(rng.normal(size=(n_rows, n_columns)), 4)
    values[:, 0] = np.arange(n_rows) / 1000.0
    return [f"c{j + 1}" for j in range(n_columns)], values


def wide_lvm(n_columns: int, n_rows: int = 200, seed: int = 0) -> bytes:
    """A LabVIEW Measurement file of ``n_columns`` channels (one segment, tab separated, the
    comment column last), as LabVIEW writes it."""
    names, values = wide_table(n_columns, n_rows, seed)
    n = n_columns - 1
    head = ["LabVIEW Measurement\t", "Writer_Version\t2", "Reader_Version\t2",
            "Separator\tTab", "Decimal_Separator\t.", "Multi_Headings\tNo",
            "X_Columns\tOne", "Time_Pref\tRelative", "***End_of_Header***", "",
            f"Channels\t{n}\t", "Samples\t" + "\t".join([str(n_rows)] * n),
            "Y_Unit_Label\t" + "\t".join(["V"] * n), "X_Dimension\t" + "\t".join(["Time"] * n),
            "X0\t" + "\t".join(["0"] * n), "Delta_X\t" + "\t".join(["0.001"] * n),
            "***End_of_Header***\t", "X_Value\t" + "\t".join(names[1:]) + "\tComment"]
    out = io.StringIO()
    out.write("\n".join(head) + "\n")
    np.savetxt(out, values, fmt="%.4f", delimiter="\t", newline="\t\n")
    return out.getvalue().encode()


def wide_csv(n_columns: int, n_rows: int = 200, seed: int = 0) -> bytes:
    """The table of :func:`wide_lvm` as plain CSV (header ``time,c2,c3…``)."""
    names, values = wide_table(n_columns, n_rows, seed)
    out = io.StringIO()
    out.write(",".join(["time", *names[1:]]) + "\n")
    np.savetxt(out, values, fmt="%.4f", delimiter=",")
    return out.getvalue().encode()


def _best(func: Callable[[], Any], repeat: int) -> tuple[float, Any]:
    best, result = float("inf"), None
    for _ in range(repeat):
        t0 = time.perf_counter()
        result = func()
        best = min(best, time.perf_counter() - t0)
    return best, result


def _rejection(path: Path, data: bytes) -> str:
    """The sentence rejecting a wide file as a run of the hull day's channels."""
    channels = {k: ChannelMap(**v) for k, v in syn.LabChannels().protocol_section().items()}
    try:
        load_run(path, channels, data=data)
    except RunError as exc:
        return str(exc)
    return ""


def run_wide(workdir: Path, n_columns: int, n_rows: int = 200, *, repeat: int = 1,
             day: bool = False) -> dict[str, float]:
    """Times [s] of a file of ``n_columns`` columns as LVM and as CSV (read, load as a run),
    the rejection sentence's length [characters] and, with ``day``, the LVM hull day with the
    file as its run 42 (seconds, and the size of runs.csv [bytes])."""
    workdir.mkdir(parents=True, exist_ok=True)
    out: dict[str, float] = {"columns": n_columns, "rows": n_rows}
    for fmt, make in (("lvm", wide_lvm), ("csv", wide_csv)):
        path = workdir / f"wide.{fmt}"
        data = make(n_columns, n_rows)
        path.write_bytes(data)
        out[f"{fmt}_mb"] = len(data) / 1e6
        read_columns(path, data)  # warm: the readers' libraries imported
        out[f"{fmt}_read_s"], _ = _best(functools.partial(read_columns, path, data), repeat)
        out[f"{fmt}_load_s"], reason = _best(functools.partial(_rejection, path, data), repeat)
        out[f"{fmt}_reason_chars"] = len(reason)
    out["lvm_over_csv"] = out["lvm_read_s"] / out["csv_read_s"]
    if day:
        out.update(_wide_day(workdir / "wide-day", workdir / "wide.lvm"))
    return out


def _wide_day(root: Path, wide: Path) -> dict[str, float]:
    """The LVM hull day (41 runs) in ``root``, plus the wide file as run 42, processed in this
    process (one job): seconds, runs, and the size of runs.csv [bytes]."""
    # loaded on use: the command line (the whole pipeline) only for --wide-day
    from towtank.commands.cli import main

    proto = _write(root, "lvm", 3)
    sheet = proto.parent / "run_sheet.csv"
    lines = sheet.read_text(encoding="utf-8").splitlines()
    if not any(ln.startswith("42,") for ln in lines):
        row = lines[-1].split(",")
        row[0], row[1] = "42", "run_042.lvm"
        lines.append(",".join(row))
        sheet.write_text("\n".join(lines) + "\n", encoding="utf-8")
    shutil.copyfile(wide, proto.parent / "data" / "run_042.lvm")
    out = proto.parent / "out"
    shutil.rmtree(out, ignore_errors=True)
    t0 = time.perf_counter()
    main(["process", str(proto), "--out", str(out), "-q", "--jobs", "1", "--no-report"])
    return {"day_s": time.perf_counter() - t0, "day_runs": len(lines) - 1,
            "runs_csv_bytes": (out / "runs.csv").stat().st_size}


def format_table(res: dict[str, dict[str, float]]) -> str:
    lines = ["| layout | files | MB | ms per file | / CSV |", "|---|---:|---:|---:|---:|"]
    for layout, r in res.items():
        flag = ""
        if layout.startswith(("tdms", "mat")):
            flag = " ✓" if r["over_csv"] <= TARGET else f" (target {TARGET:g})"
        lines.append(f"| {layout} | {r['files']:.0f} | {r['mb']:.1f} | {r['ms_per_file']:.2f} | "
                     f"{r['over_csv']:.2f}{flag} |")
    return "\n".join(lines)


def format_wide(res: dict[str, float]) -> str:
    lines = [f"{res['columns']:,.0f} columns × {res['rows']:,.0f} rows",
             "| file | MB | read s | load as a run s | sentence chars |",
             "|---|---:|---:|---:|---:|"]
    for fmt in ("lvm", "csv"):
        lines.append(f"| {fmt} | {res[f'{fmt}_mb']:.1f} | {res[f'{fmt}_read_s']:.2f} | "
                     f"{res[f'{fmt}_load_s']:.2f} | {res[f'{fmt}_reason_chars']:.0f} |")
    met = "✓" if res["lvm_over_csv"] <= WIDE_TARGET else f"(target {WIDE_TARGET:g})"
    lines.append(f"LVM / CSV read time: {res['lvm_over_csv']:.2f} {met}")
    if "day_s" in res:
        lines.append(f"LVM day of {res['day_runs']:.0f} runs with this file as one: "
                     f"{res['day_s']:.1f} s, runs.csv {res['runs_csv_bytes'] / 1e3:.1f} kB")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m towtank.testing.bench_read",
                                 description="Time reading run files in every layout.")
    ap.add_argument("--workdir", type=Path, default=Path("/tmp/towtank-bench-read"))
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--seed", type=int, default=3)
    ap.add_argument("--wide-columns", type=int, default=0,
                    help="time one file of this many columns instead (LVM and CSV)")
    ap.add_argument("--wide-rows", type=int, default=200)
    ap.add_argument("--wide-day", action="store_true",
                    help="with --wide-columns: also process the LVM day holding that file")
    args = ap.parse_args(argv)
    if args.wide_columns:
        wide = run_wide(args.workdir, args.wide_columns, args.wide_rows,
                        repeat=max(1, args.repeat), day=args.wide_day)
        print(format_wide(wide))
        (args.workdir / "bench_read_wide.json").write_text(json.dumps(wide, indent=1))
        return 0
    res = run_bench(args.workdir, repeat=max(1, args.repeat), seed=args.seed)
    print(format_table(res))
    (args.workdir / "bench_read.json").write_text(json.dumps(res, indent=1))
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
