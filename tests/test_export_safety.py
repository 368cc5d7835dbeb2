"""--export and the writers on a full disk and with odd text (issue 20, items 6, 7 and 11).

* item 6: the export writes run by run: the main process never holds every run's full-rate
  series at once (tracemalloc in this process; the peak resident memory of a process that
  exports a 5 kHz day);
* item 7: a full disk met by any writer (PDF, workbook, figures, tables, manifest, mat, hdf5,
  parquet) is exit 2 with one sentence and the output folder as it was, never a traceback, an
  exit 3 (``zlib.error``) or a segmentation fault (h5py); on a real full disk too (a small
  tmpfs, when this process may mount one);
* item 11: a NUL character in the run sheet's text is exported (U+2400), not exit 3.
"""

from __future__ import annotations

import contextlib
import dataclasses
import errno
import hashlib
import io
import itertools
import json
import os
import subprocess
import sys
import textwrap
import tracemalloc
import zlib
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from conftest import lab_environment

import towtank
from towtank.commands.cli import main
from towtank.report import export
from towtank.testing import synthetic as syn

ROOT = Path(towtank.__file__).resolve().parent.parent
ALL = ("mat", "hdf5", "parquet")
BYTES_PER_SAMPLE = 41  # t, U, a, drag, lift as float64 and phase as int8


def _make_day(root: Path, **kw) -> Path:
    kw.setdefault("seed", 5)
    kw.setdefault("file_format", "csv")
    syn.make_hull_day(root, sheet_format="csv", **kw)
    return syn.write_protocol(root / "p.toml",
                              **syn.hull_protocol_sections(".", "out", sheet_format="csv"))


def _series_bytes(day) -> tuple[int, int]:
    """(the largest run's, the whole day's) exported series [bytes]."""
    n = day.runs.set_index("run")["n_samples"].loc[sorted(day.reductions)].astype(int)
    return int(n.max()) * BYTES_PER_SAMPLE, int(n.sum()) * BYTES_PER_SAMPLE


def run_cli(*args: str) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = main(["process", *args])
    return rc, out.getvalue(), err.getvalue()


def fingerprint(folder: Path) -> dict[str, tuple[str, int]]:
    """sha256 and mtime of every file under ``folder``."""
    return {p.relative_to(folder).as_posix(): (hashlib.sha256(p.read_bytes()).hexdigest(),
                                               p.stat().st_mtime_ns)
            for p in sorted(folder.rglob("*")) if p.is_file()}


def leftovers(out: Path) -> list[str]:
    return sorted(p.name for p in out.parent.iterdir() if p.name.startswith(f".{out.name}."))


def assert_full_disk_reported(rc: int, stderr: str, out: Path, before: dict) -> None:
    """Exit 2, one sentence, the folder as it was, no temporary folder beside it."""
    lines = [line for line in stderr.splitlines() if line.strip()]
    assert rc == 2, stderr
    assert len(lines) == 1, stderr
    assert "No space left on device" in lines[0] and "the folder is as it was" in lines[0]
    assert "Traceback" not in stderr and "Exception ignored" not in stderr
    assert fingerprint(out) == before
    assert leftovers(out) == []


# ------------------------------------------------------------------ the day used below
@pytest.fixture(scope="session")
def written(tmp_path_factory):
    """A day (plain CSV files) written once with everything (report, its pages blank, and the
    three exports), and its result for the runs below (process_day is not what they test)."""
    from towtank.pipeline import process_day

    root = tmp_path_factory.mktemp("full_disk")
    protocol = _make_day(root)
    out = root / "out"
    with pytest.MonkeyPatch.context() as mp:
        _blank_pages_and_figures(mp)
        rc, _, err = run_cli(str(protocol), "--out", str(out), "-q", "-j", "1",
                             *[a for f in ALL for a in ("--export", f)])
    assert rc in (0, 1), err
    return protocol, out, process_day(protocol, jobs=1)


# ------------------------------------------------------------------ item 6: run by run

def _disk_fills_after(monkeypatch, nbytes: int) -> None:
    """runs.h5's writes fail with ENOSPC once ``nbytes`` have been written (HDF5 meets a
    full disk for real, through export's file object)."""
    left = [nbytes]
    real_pwrite = os.pwrite

    def pwrite(fd, data, offset):
        if left[0] <= 0:
            raise _enospc()
        n = real_pwrite(fd, bytes(data[:left[0]]), offset)
        left[0] -= n
        return n

    monkeypatch.setattr(export._NeverFailingFile, "_pwrite", staticmethod(pwrite))

@pytest.mark.heavy
def test_the_export_holds_one_run_at_a_time(written, tmp_path):
    """The Python and numpy memory live at once while the day is exported (all three
    formats) stays within a few runs' series, far below the day's (an export that reduced
    every run first and held them all would hold 8 MB for this day's 6.5 MB of series).

    Plain CSV run files: reading a .csv.gz asks Python's gzip for up to 1 GiB at once, which
    tracemalloc counts although the pages are never touched."""
    day = written[2]
    largest, total = _series_bytes(day)
    bound = 8 * largest + 512 * 1024
    assert total > 2 * bound  # the day is long enough to tell the two apart
    tracemalloc.start()
    try:
        tracemalloc.reset_peak()
        base, _ = tracemalloc.get_traced_memory()
        export.export_runs(day, tmp_path, ALL)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak - base < bound, (peak - base, largest, total)
    assert len(list((tmp_path / "export").glob("run_*.mat"))) == len(day.reductions)


_PEAK_SCRIPT = textwrap.dedent("""
    import dataclasses, gc, json, sys
    from pathlib import Path

    def status(key):
        with open("/proc/self/status") as fh:
            return next(int(l.split()[1]) * 1024 for l in fh if l.startswith(key))

    from towtank.pipeline import process_day
    from towtank.report.export import export_runs

    root = Path(sys.argv[1])
    day = process_day(root / "p.toml", jobs=1)
    first = min(day.reductions)  # the libraries' first use, not measured
    export_runs(dataclasses.replace(day, reductions={first: day.reductions[first]}),
                root / "warm", ("parquet",))
    gc.collect()
    with open("/proc/self/clear_refs", "w") as fh:
        fh.write("5")  # VmHWM := VmRSS
    before = status("VmRSS")
    export_runs(day, root / "exported", ("parquet",))
    n = day.runs.set_index("run")["n_samples"].loc[sorted(day.reductions)]
    print(json.dumps({"growth": status("VmHWM") - before, "largest": int(n.max()),
                      "total": int(n.sum())}))
""")


@pytest.mark.heavy
@pytest.mark.skipif(not Path("/proc/self/clear_refs").exists(), reason="Linux /proc only")
def test_the_peak_memory_of_an_export_is_one_runs_worth(tmp_path):
    """A process exporting a 5 kHz day (41 runs, 160 MB of series) grows its resident memory
    by a few runs' worth and the libraries' caches, not by the day (an export holding every
    run would grow it by more than the whole day, ~210 MB)."""
    _make_day(tmp_path, fs=5000.0, file_format="tdms")
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    done = subprocess.run([sys.executable, "-c", _PEAK_SCRIPT, str(tmp_path)], env=env,
                          capture_output=True, text=True, timeout=600, check=False)
    assert done.returncode == 0, done.stderr
    res = json.loads(done.stdout.strip().splitlines()[-1])
    largest, total = res["largest"] * BYTES_PER_SAMPLE, res["total"] * BYTES_PER_SAMPLE
    bound = 4 * largest + 48 * 2**20
    assert total > 2 * bound
    assert res["growth"] < bound, res


# ------------------------------------------------------------ item 7: a full disk, faked
def _fresh(day):
    """The processed day as process_day would give it again (write_outputs adds warnings)."""
    return dataclasses.replace(day, warnings=list(day.warnings))


def _enospc() -> OSError:
    return OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))


def _half_then_full(path: Path) -> None:
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    Path(path).write_bytes(b"half a file")
    raise _enospc()


def _zlib_after_full(path: Path) -> None:
    """What matplotlib's PdfPages does on a full disk: its write fails, and closing the file
    flushes the zlib stream again, which raises zlib.error on top of the OSError."""
    Path(path).write_bytes(b"%PDF-1.4 half")
    try:
        raise _enospc()
    except OSError:  # the OSError is the zlib.error's context, as in matplotlib
        raise zlib.error("Error -2 while flushing: inconsistent stream state")  # noqa: B904


def _blank_pages_and_figures(monkeypatch) -> None:
    """The report's drawing replaced by a blank page per PDF part and one small PNG: the
    writers still run as they do (the PDF's parts here and forked, joined; the figures
    forked), without the seconds of drawing that a full disk's handling does not depend on."""
    from pypdf import PdfWriter

    from towtank.report import figures, pdf

    def blank_part(day, plan, pages, path):
        writer = PdfWriter()
        writer.add_blank_page(width=595, height=842)
        with open(path, "wb") as fh:
            writer.write(fh)

    def one_figure(day, folder):
        (Path(folder) / "figures").mkdir(parents=True, exist_ok=True)
        (Path(folder) / "figures" / "tare.png").write_bytes(b"\x89PNG\r\n\x1a\n")

    monkeypatch.setattr(pdf, "_write_part", blank_part)
    monkeypatch.setattr(figures, "write_figures", one_figure)


def _inject(monkeypatch, where: str) -> None:
    from towtank.report import figures, outputs, pdf, tables, workbook
    from towtank.runtime import manifest

    _blank_pages_and_figures(monkeypatch)  # then the writer that meets the full disk
    if where == "pdf":  # every part, the first one in this process
        monkeypatch.setattr(pdf, "_write_part", lambda day, plan, pages, path:
                            _half_then_full(path))
    elif where in ("pdf-zlib-here", "pdf-zlib-forked"):
        # this process draws the first group of its first report: part 0 here, part 1 forked
        monkeypatch.setattr(pdf, "_REPORTS_DRAWN", itertools.count())
        part = ".report-part-0.pdf" if where == "pdf-zlib-here" else ".report-part-1.pdf"
        real = pdf._write_part

        def part_fails(day, plan, pages, path):
            if Path(path).name == part:
                _zlib_after_full(path)
            real(day, plan, pages, path)

        monkeypatch.setattr(pdf, "_write_part", part_fails)
    elif where == "workbook":  # a forked writer
        monkeypatch.setattr(workbook, "write_workbook",
                            lambda day, folder: _half_then_full(Path(folder) / "report.xlsx"))
    elif where == "figures":  # a forked writer
        monkeypatch.setattr(figures, "write_figures", lambda day, folder: _half_then_full(
            Path(folder) / "figures" / "tare.png"))
    elif where == "tables":
        monkeypatch.setattr(tables, "write_tables",
                            lambda day, folder: _half_then_full(Path(folder) / "runs.csv"))
    elif where == "manifest":
        real_manifest = manifest.write_manifest

        def manifest_fails(folder, files, **kw):
            if Path(folder).name != "out":
                _half_then_full(Path(folder) / manifest.MANIFEST)
            real_manifest(folder, files, **kw)

        monkeypatch.setattr(outputs.manifest, "write_manifest", manifest_fails)
    elif where in ("mat", "parquet"):
        calls = []

        def third_run_fails(path, series, meta):
            calls.append(path)
            if len(calls) == 3:
                _half_then_full(path)
            real(path, series, meta)

        real = getattr(export, f"_write_{where}")
        monkeypatch.setattr(export, f"_write_{where}", third_run_fails)
    elif where == "hdf5":  # the disk fills after 300 kB of runs.h5: HDF5 meets it for real
        _disk_fills_after(monkeypatch, 300_000)
    else:  # pragma: no cover
        raise AssertionError(where)


WRITERS = ["pdf", "pdf-zlib-here", "pdf-zlib-forked", "workbook", "figures", "tables",
           "manifest", "mat", "hdf5", "parquet"]


@pytest.mark.heavy
@pytest.mark.parametrize("where", WRITERS)
def test_a_full_disk_in_any_writer_is_exit_2_and_the_folder_stays(written, monkeypatch, where):
    protocol, out, day = written
    before = fingerprint(out)
    monkeypatch.setattr("towtank.pipeline.process_day", lambda *a, **k: _fresh(day))
    _inject(monkeypatch, where)
    report = where.startswith(("pdf", "workbook", "figures"))
    args = [str(protocol), "--out", str(out), "-q", "-j", "1", "--no-cache"]
    if not report:
        args.append("--no-report")
    if where in ("mat", "hdf5", "parquet"):
        args += ["--export", where]
    rc, _, err = run_cli(*args)
    assert_full_disk_reported(rc, err, out, before)


def _pdf_part_fails(monkeypatch) -> None:
    """The PDF's writer fails as matplotlib's does on a full disk: zlib.error, with no
    OSError behind it."""
    from towtank.report import pdf

    def broken(day, plan, pages, path):
        raise zlib.error("Error -2 while flushing: inconsistent stream state")

    _blank_pages_and_figures(monkeypatch)
    monkeypatch.setattr(pdf, "_write_part", broken)


@pytest.mark.heavy
def test_a_library_error_on_a_full_disk_is_the_full_disk(written, monkeypatch):
    """A writer's own error without the OSError behind it (as h5py's or a C library's can be)
    while the file system has no space left: exit 2, not 3."""
    from towtank.runtime import storage

    protocol, out, day = written
    before = fingerprint(out)
    monkeypatch.setattr("towtank.pipeline.process_day", lambda *a, **k: _fresh(day))

    _pdf_part_fails(monkeypatch)
    monkeypatch.setattr(storage, "free_bytes", lambda path: 4096)
    rc, _, err = run_cli(str(protocol), "--out", str(out), "-q", "-j", "1", "--no-cache")
    assert_full_disk_reported(rc, err, out, before)


@pytest.mark.heavy
def test_the_same_library_error_with_space_left_is_still_a_bug(written, monkeypatch):
    protocol, out, day = written
    before = fingerprint(out)
    monkeypatch.setattr("towtank.pipeline.process_day", lambda *a, **k: _fresh(day))

    _pdf_part_fails(monkeypatch)
    rc, _, err = run_cli(str(protocol), "--out", str(out), "-q", "-j", "1", "--no-cache")
    assert rc == 3 and "internal error (error: Error -2" in err
    assert fingerprint(out) == before and leftovers(out) == []


def test_hdf5_closes_its_file_cleanly_after_a_failed_write(tmp_path, monkeypatch):
    """The first failed write is kept for the end: HDF5 sees none, closes the file, and
    export_runs raises the OSError (ENOSPC) itself."""
    import h5py

    _disk_fills_after(monkeypatch, 50_000)
    open_before = h5py.h5f.get_obj_count(h5py.h5f.OBJ_ALL, h5py.h5f.OBJ_ALL)
    h5 = export._Hdf5Export(tmp_path / "runs.h5", "c")
    rng = np.random.default_rng(0)
    for k in range(20):
        h5.add(f"run_{k:03d}", {"t": rng.normal(size=5000)}, {"run": k})
        if h5.failed:
            break
    assert h5.failed and k < 19
    with pytest.raises(OSError) as info:
        h5.close()
    assert info.value.errno == errno.ENOSPC
    # nothing of the file is left open for the library's clean-up at exit
    assert h5py.h5f.get_obj_count(h5py.h5f.OBJ_ALL, h5py.h5f.OBJ_ALL) == open_before


# ------------------------------------------------------------- item 7: a real full disk
@pytest.fixture
def small_disk(tmp_path):
    """A folder on a tmpfs of its own (root only: skipped where mount is not permitted)."""
    def mount(size: str) -> Path:
        where = tmp_path / f"disk-{size}"
        where.mkdir()
        done = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs",
                               str(where)], capture_output=True, check=False)
        if done.returncode != 0:
            pytest.skip("a tmpfs cannot be mounted here")
        mounted.append(where)
        return where

    mounted: list[Path] = []
    if os.geteuid() != 0:
        pytest.skip("mounting a tmpfs needs root")
    yield mount
    for where in mounted:
        subprocess.run(["umount", "-l", str(where)], capture_output=True, check=False)


#: Run in the child before ``towtank process``: the report's PDF draws its text pages only
#: (the others blank, still written by matplotlib's PdfPages) and the figures are one small PNG,
#: so the PDF (200 kB) is what fills the small disk, without the seconds of drawing the fits.
_TEXT_PAGES_ONLY = textwrap.dedent("""
    from pathlib import Path
    from towtank.report import figures, pdf

    _render = pdf._render

    def render(day, page, plan, grids=None):
        text = page.kind in ("title", "summary", "runs", "quality")
        return _render(day, page, plan, grids) if text else pdf._page()

    def one_figure(day, folder):
        (Path(folder) / "figures").mkdir(parents=True, exist_ok=True)
        (Path(folder) / "figures" / "tare.png").write_bytes(b"\\x89PNG\\r\\n\\x1a\\n")

    pdf._render = render
    figures.write_figures = one_figure
""")


def _towtank(*args: str, prelude: str = "") -> subprocess.CompletedProcess:
    env = lab_environment(PYTHONPATH=str(ROOT))  # every core: the writers forked
    code = prelude + "\nfrom towtank.commands.cli import entry\nentry()\n"
    return subprocess.run([sys.executable, "-c", code, "process", *args], env=env,
                          capture_output=True, text=True, timeout=600, check=False)


@pytest.mark.heavy
@pytest.mark.parametrize("size, extra", [("2m", ("--no-report", "--export", "hdf5")),
                                         ("250k", ())], ids=["hdf5", "report"])
def test_a_real_full_disk_is_exit_2_and_the_folder_stays(tmp_path, small_disk, size, extra):
    """On a tmpfs too small for the new outputs, ``--export hdf5`` and the report end in exit 2
    with one sentence, the folder as it was: not a segmentation fault (exit 139) after h5py's
    tracebacks, not exit 3 from the PDF's zlib.error. A process of its own, since a segmentation
    fault would end the test run."""
    protocol = _make_day(tmp_path / "day")
    out = small_disk(size) / "out"
    rc, _, err = run_cli(str(protocol), "--out", str(out), "-q", "--no-report", "--no-cache",
                         "-j", "1")
    assert rc in (0, 1), err
    before = fingerprint(out)
    done = _towtank(str(protocol), "--out", str(out), "-q", "--no-cache", "-j", "2", *extra,
                    prelude="" if extra else _TEXT_PAGES_ONLY)
    assert_full_disk_reported(done.returncode, done.stderr, out, before)


# ------------------------------------------------------------------ item 11: NUL in text
@pytest.mark.heavy
def test_a_nul_in_the_run_sheet_is_exported_as_the_nul_symbol(tmp_path):
    """A NUL in a text cell that reaches ``meta`` (the tare group is free text; so is the
    campaign's name) and in a remark: exit 0 or 1 (not exit 3 from h5py's "VLEN strings do
    not support embedded NULLs"), and the three formats carry U+2400 in its place."""
    protocol = _make_day(tmp_path)
    sheet = pd.read_csv(tmp_path / "run_sheet.csv", dtype=str, keep_default_na=False)
    sheet["tare_group"] = sheet["tare_group"].replace({"A": "A\x00lab"})
    sheet.loc[0, "remarks"] = "cable\x00slack"
    sheet.to_csv(tmp_path / "run_sheet.csv", index=False)
    text = protocol.read_text(encoding="utf-8")
    assert 'name = "SUT-2 quarter-scale hull, synthetic day"' in text
    protocol.write_text(text.replace('name = "SUT-2 quarter-scale hull, synthetic day"',
                                     'name = "SUT-2\\u0000day"', 1), encoding="utf-8")
    rc, _, err = run_cli(str(protocol), "--no-report", "-q", "--no-cache",
                         *[a for f in ALL for a in ("--export", f)])
    assert rc in (0, 1), err
    import h5py
    import pyarrow.parquet as pq
    from scipy.io import loadmat

    runs = pd.read_csv(tmp_path / "out" / "runs.csv")
    run = int(runs[(runs["config"] == "hull") & (runs["status"] == "ok")]["run"].iloc[0])
    name = f"run_{run:03d}"
    folder = tmp_path / "out" / "export"
    with h5py.File(folder / "runs.h5", "r") as h5:
        assert h5.attrs["campaign"] == "SUT-2\u2400day"
        assert h5[name].attrs["tare_group"] == "A\u2400lab"
        assert h5[name].attrs["campaign"] == "SUT-2\u2400day"
    meta = json.loads(pq.read_table(folder / f"{name}.parquet").schema.metadata[b"towtank"])
    assert meta["meta"]["tare_group"] == "A\u2400lab"
    assert meta["meta"]["campaign"] == "SUT-2\u2400day"
    mat = loadmat(folder / f"{name}.mat", squeeze_me=True)
    assert mat["meta"]["tare_group"].item() == "A\u2400lab"
    assert export.safe_text("a\x00b\x00") == "a\u2400b\u2400"
