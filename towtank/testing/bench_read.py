"""Reading cost per file layout: ``python -m towtank.testing.bench_read [--repeat 5]``.

Separate from the unit tests. It writes the same synthetic hull day (41 runs at 1 kHz, lab
channels in volts) in every layout towtank reads (:mod:`towtank.testing.layouts`: plain CSV,
TDMS with and without a time channel, LVM, European text, MATLAB v5 and v7.3, HDF5) into a work
folder, warms the page cache, and times :func:`towtank.ingest.runfile.load_run` (read, map,
calibrate, check) of every run file of each layout in this one process, best of ``--repeat``.
Each layout's time is reported as a ratio to the plain CSV day's, measured in the same run.
The target: a TDMS or .mat run costs no more than 1.5 × the same run as CSV.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

from towtank.ingest.protocol import load_protocol
from towtank.ingest.runfile import file_bytes, load_run
from towtank.testing import synthetic as syn
from towtank.testing.layouts import layout_channels, protocol_sections

if TYPE_CHECKING:
    from towtank.testing.truth import FileFormat

LAYOUTS: tuple[FileFormat, ...] = ("csv", "tdms", "tdms-waveform", "mat", "mat73", "hdf5", "lvm",
                                   "txt-eu")
TARGET = 1.5  # largest time ratio to CSV for the TDMS and MATLAB layouts


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


def format_table(res: dict[str, dict[str, float]]) -> str:
    lines = ["| layout | files | MB | ms per file | / CSV |", "|---|---:|---:|---:|---:|"]
    for layout, r in res.items():
        flag = ""
        if layout.startswith(("tdms", "mat")):
            flag = " ✓" if r["over_csv"] <= TARGET else f" (target {TARGET:g})"
        lines.append(f"| {layout} | {r['files']:.0f} | {r['mb']:.1f} | {r['ms_per_file']:.2f} | "
                     f"{r['over_csv']:.2f}{flag} |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m towtank.testing.bench_read",
                                 description="Time reading run files in every layout.")
    ap.add_argument("--workdir", type=Path, default=Path("/tmp/towtank-bench-read"))
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--seed", type=int, default=3)
    args = ap.parse_args(argv)
    res = run_bench(args.workdir, repeat=max(1, args.repeat), seed=args.seed)
    print(format_table(res))
    (args.workdir / "bench_read.json").write_text(json.dumps(res, indent=1))
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
