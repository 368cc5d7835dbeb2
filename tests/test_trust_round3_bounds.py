"""Issue 33 ("Trust, third round"), items 5, 12 and 13: bounds on what reading may cost.

5. A small .csv.gz holding more rows than a run may (5 000 000) is rejected, in one sentence,
   while it is decompressed: ``process -j 1`` and ``inspect`` both stay within an address-space
   limit that reading the whole file needs many times over. The row and value caps are one
   check common to every reader.
12. A name the file system refuses to look up (too long, a symlink loop) in the run sheet, the
   protocol or a side-file pattern rejects its run or stops the protocol with one sentence.
13. An integer too large for a float in the protocol is exit 2 naming its key; in the run
   sheet it rejects its run; any TOML number in any numeric key is exit 0, 1 or 2.
"""

from __future__ import annotations

import gzip
import math
import os
import subprocess
import sys
import textwrap
import zipfile
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from towtank.commands.cli import main
from towtank.errors import RunError
from towtank.ingest import columns, readers
from towtank.ingest.schema import SCHEMA
from towtank.runtime.pathcheck import FILE, FOLDER, MISSING, OTHER, path_kind, resolved
from towtank.testing import layouts
from towtank.testing import synthetic as syn
from towtank.testing.child import run_in_child

ROOT = Path(__file__).resolve().parents[1]
PLAN = [syn.RunSpec("sting", 0.0, 0.8, 0.5), syn.RunSpec("sting", 0.0, 1.6, 0.5),
        syn.RunSpec("hull", 0.0, 0.8, 0.5), syn.RunSpec("hull", 0.0, 1.6, 0.5)]
LONG_NAME = "x" * 300 + ".csv"


def _day(root: Path, **sections: Any) -> Path:
    """A four-run hull day (two sting, two hull runs) in ``root``, its protocol returned."""
    syn.make_hull_day(root, seed=3, file_format="csv", sheet_format="csv", runs=PLAN)
    base = syn.hull_protocol_sections(".", "out", sheet_format="csv")
    for name, values in sections.items():
        base.setdefault(name, {}).update(values)
    return syn.write_protocol(root / "protocol.toml", **base)


def _add_run(root: Path, file: str, **cells: Any) -> int:
    """A hull row naming ``file`` appended to the day's sheet; its run number."""
    sheet = pd.read_csv(root / "run_sheet.csv", dtype=str, keep_default_na=False)
    row = sheet.iloc[-1].copy()
    row["run"], row["file"] = str(len(sheet) + 1), file
    for key, value in cells.items():
        row[key] = value
    sheet.loc[len(sheet)] = row
    sheet.to_csv(root / "run_sheet.csv", index=False)
    return len(sheet)


def _runs(root: Path) -> pd.DataFrame:
    return pd.read_csv(root / "out" / "runs.csv").set_index("run")


def _one_sentence(text: str) -> bool:
    return text.count("\n") == 0 and ". " not in text.rstrip(".")


# ------------------------------------------------------------ 5. a run's rows are bounded
#: Rows of the bomb: past the row cap and the lines a text file may hold beyond it.
BOMB_ROWS = readers.MAX_RUN_ROWS + readers.TEXT_LINE_SLACK + 300_000


@pytest.fixture(scope="session")
def bomb_day(tmp_path_factory) -> tuple[Path, int]:
    """The four-run day and a fifth run, ``big.csv.gz``: 2 MB of gzip holding 5.3 M valid rows
    (200 MB), written by streaming a block of the day's rows into gzip.open."""
    root = tmp_path_factory.mktemp("bomb")
    protocol = _day(root)
    lines = (root / "data" / "run_003.csv").read_bytes().splitlines(keepends=True)
    header, block = lines[0], b"".join(lines[1:301])
    with gzip.open(root / "data" / "big.csv.gz", "wb", compresslevel=6) as fh:
        fh.write(header)
        for _ in range(BOMB_ROWS // 300):
            fh.write(block)
    assert (root / "data" / "big.csv.gz").stat().st_size < 4 << 20
    return protocol, _add_run(root, "big.csv.gz")


#: Run before each command in one new interpreter (:func:`run_in_child`): the command under an
#: address-space limit of the memory mapped at its start (the libraries loaded first, and
#: what an earlier command left) plus HEADROOM; reading the whole file needs more.
_LIMITED = textwrap.dedent("""
    import os, resource
    import numpy, pandas, pyarrow, pyarrow.csv, scipy.signal  # the libraries, loaded first
    from towtank.commands.cli import main as _main

    os.chdir({cwd!r})

    def limited(args):
        with open("/proc/self/status") as fh:
            mapped = next(int(l.split()[1]) * 1024 for l in fh if l.startswith("VmSize:"))
        resource.setrlimit(resource.RLIMIT_AS, (mapped + {headroom}, resource.RLIM_INFINITY))
        try:
            return _main(args)
        finally:
            resource.setrlimit(resource.RLIMIT_AS, (resource.RLIM_INFINITY,
                                                    resource.RLIM_INFINITY))
""")
HEADROOM = 768 << 20  # [bytes]: the 5.3 M rows as text are 200 MB, parsed several GB


@pytest.fixture(scope="module")
def bomb_commands(bomb_day) -> dict[str, subprocess.CompletedProcess]:
    """``process`` of the bomb day and ``inspect`` of its big file, each under its own
    address-space limit, in one child process (one start-up): command -> what it did."""
    protocol, _ = bomb_day
    big = protocol.parent / "data" / "big.csv.gz"
    env = {**os.environ, "MALLOC_ARENA_MAX": "2", "OMP_NUM_THREADS": "1",
           "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
    process, inspect = run_in_child(
        [["process", str(protocol), "-q", "--jobs", "1", "--no-report"],
         ["inspect", str(big), "--protocol", str(protocol)]],
        timeout=600, prelude=_LIMITED.format(cwd=str(protocol.parent), headroom=HEADROOM),
        call="limited(args)", env=env)
    return {"process": process, "inspect": inspect}


@pytest.mark.heavy
@pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="needs /proc (Linux)")
def test_process_rejects_a_small_gzip_of_too_many_rows_within_bounded_memory(bomb_day,
                                                                           bomb_commands):
    protocol, run = bomb_day
    done = bomb_commands["process"]
    assert done.returncode == 1, done.stderr
    runs = _runs(protocol.parent)
    reason = runs.loc[run, "reason"]
    assert runs.loc[run, "status"] == "rejected"
    assert reason.startswith(f"run {run}: big.csv.gz is too long for one run: it holds more "
                             "than 5,000,000 rows, and towtank reads at most 5,000,000 rows"), \
        reason
    assert _one_sentence(reason), reason
    assert (runs.drop(index=run)["status"] == "ok").all()


@pytest.mark.heavy
@pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="needs /proc (Linux)")
def test_inspect_rejects_a_small_gzip_of_too_many_rows_within_bounded_memory(bomb_commands):
    done = bomb_commands["inspect"]
    assert done.returncode == 1, done.stderr
    said = done.stderr.strip()
    assert said.startswith("towtank: big.csv.gz is too long for one run: it holds more than "
                           "5,000,000 rows"), said
    assert _one_sentence(said.removeprefix("towtank: ")), said


def test_the_caps_and_the_sentence():
    """The default caps: 5 M rows (83 min at 1 kHz), 40 M values (8 columns at 5 M rows),
    stated in docs/formats.md."""
    assert (readers.MAX_RUN_ROWS, readers.MAX_RUN_VALUES) == (5_000_000, 40_000_000)
    readers.check_run_size("a.csv", 5_000_000, 8)  # at both caps: read
    with pytest.raises(RunError, match=r"a.csv is too long for one run: it holds 5,000,001 "
                                       r"rows, and towtank reads at most 5,000,000 rows"):
        readers.check_run_size("a.csv", 5_000_001, 1)
    with pytest.raises(RunError, match=r"it holds 40,000,040 values \(1,000,001 rows of 40 "
                                       r"columns\)"):
        readers.check_run_size("a.csv", 1_000_001, 40)
    docs = (ROOT / "docs" / "formats.md").read_text(encoding="utf-8")
    assert "5 000 000 rows" in docs and "40 000 000 values" in docs


RUN_FRAME_ROWS = 600  # rows of the frame each format is written with: over the lowered cap


@pytest.fixture(scope="session")
def frame() -> pd.DataFrame:
    t = np.arange(RUN_FRAME_ROWS) / 100.0
    return pd.DataFrame({"Time (s)": t, "Carriage speed (m/s)": np.sin(t),
                         "Fx load cell (V)": np.cos(t), "Fy load cell (V)": t / 10.0})


@pytest.mark.parametrize("layout", ["two-cell", "txt-eu", "lvm", "tdms-waveform", "mat",
                                    "mat73", "hdf5", "hdf5-rate-name", "csv.gz", "txt.gz"])
def test_every_reader_applies_the_row_cap(layout, frame, tmp_path, monkeypatch):
    """One row cap for every format (here lowered to 500 rows: the file holds 600)."""
    units = {c: ("s" if c.startswith("Time") else "m/s" if "speed" in c else "V")
             for c in frame.columns}
    base = {"csv.gz": "two-cell", "txt.gz": "txt-eu"}.get(layout, layout)
    path = tmp_path / f"run_001.{layouts.LAYOUTS[base]}"
    layouts.write_layout(base, frame, path, "Time (s)", units)
    if layout.endswith(".gz"):
        gz = path.with_name(path.name + ".gz")
        gz.write_bytes(gzip.compress(path.read_bytes()))
        path = gz
    columns.read_columns(path)  # readable as it is
    monkeypatch.setattr(readers, "MAX_RUN_ROWS", 500)
    with pytest.raises(RunError, match=rf"{path.name} is too long for one run: it holds "
                                       r"(600|more than 500) rows"):
        columns.read_columns(path)


def test_a_text_file_of_too_many_lines_is_refused_before_it_is_parsed(tmp_path, monkeypatch):
    """Lines beyond the cap and its slack are counted on the bytes: no reader sees them."""
    monkeypatch.setattr(readers, "MAX_RUN_ROWS", 100)
    monkeypatch.setattr(readers, "TEXT_LINE_SLACK", 10)
    path = tmp_path / "run.txt"
    path.write_bytes(b"title\n" + b"1;2\n" * 200)

    def never(*_: Any, **__: Any) -> None:
        raise AssertionError("parsed")

    monkeypatch.setattr(columns, "read_text_columns", never)
    with pytest.raises(RunError, match="it holds more than 100 rows"):
        columns.read_columns(path)


@settings(max_examples=60, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(text=st.binary(max_size=3000), lines_cap=st.integers(0, 40),
       members=st.integers(1, 3))
def test_gunzip_gives_the_text_or_the_size_sentence(text, lines_cap, members, monkeypatch):
    """Any gzip (one member or several): the whole text when it has few enough lines, else the
    one sentence of the row cap; never another error."""
    monkeypatch.setattr(readers, "MAX_RUN_ROWS", lines_cap)
    monkeypatch.setattr(readers, "TEXT_LINE_SLACK", 0)
    data = b"".join(gzip.compress(text) for _ in range(members))
    whole = text * members
    if whole.count(b"\n") <= lines_cap and whole:
        assert columns.gunzip(data, "r.csv.gz") == whole
    elif not whole:
        assert columns.gunzip(data, "r.csv.gz") == b""
    else:
        with pytest.raises(RunError, match=r"r.csv.gz is too long for one run: it holds more "
                                           rf"than {lines_cap:,} rows"):
            columns.gunzip(data, "r.csv.gz")


# ------------------------------------------------------- 12. names the system refuses
def test_path_kind_answers_for_any_name(tmp_path):
    os.symlink(tmp_path / "loop", tmp_path / "loop")
    os.mkfifo(tmp_path / "pipe")
    (tmp_path / "f.csv").write_text("x")
    assert path_kind(tmp_path / "f.csv") == FILE
    assert path_kind(tmp_path) == FOLDER
    assert path_kind(tmp_path / "pipe") == OTHER
    assert path_kind(tmp_path / "nothing") == MISSING
    assert path_kind(tmp_path / "f.csv" / "below") == MISSING
    assert path_kind(tmp_path / LONG_NAME) == os.strerror(36)  # ENAMETOOLONG
    assert path_kind(tmp_path / "loop") == os.strerror(40)  # ELOOP
    assert path_kind("a\x00b") != FILE
    assert resolved(tmp_path / "loop") == "a symlink loop"
    assert resolved(tmp_path / "f.csv") == (tmp_path / "f.csv").resolve()


def test_a_name_too_long_or_a_link_loop_in_the_sheet_rejects_only_its_run(tmp_path):
    protocol = _day(tmp_path)
    long_run = _add_run(tmp_path, LONG_NAME)
    os.symlink(tmp_path / "data" / "loop.csv", tmp_path / "data" / "loop.csv")
    loop_run = _add_run(tmp_path, "loop.csv")
    assert main(["process", str(protocol), "-q", "--jobs", "1", "--no-report"]) == 1
    runs = _runs(tmp_path)
    assert runs.loc[long_run, "reason"].endswith(" cannot be read (File name too long).") or \
        "File name too long" in runs.loc[long_run, "reason"]
    assert runs.loc[loop_run, "reason"] == f"run {loop_run}: loop.csv cannot be opened (a " \
                                           "symlink loop)."
    for run in (long_run, loop_run):
        assert runs.loc[run, "status"] == "rejected"
        assert runs.loc[run, "reason"].startswith(f"run {run}: ")
        assert _one_sentence(runs.loc[run, "reason"])
    assert (runs.drop(index=[long_run, loop_run])["status"] == "ok").all()


def test_a_zeros_file_name_too_long_rejects_each_run_in_one_sentence(tmp_path):
    """The [zeros] pattern makes a 300-character name for every run."""
    protocol = _day(tmp_path, zeros={"file": "x" * 300 + "{stem}.csv"})
    assert main(["process", str(protocol), "-q", "--jobs", "1", "--no-report"]) == 1
    runs = _runs(tmp_path)
    assert (runs["status"] == "rejected").all()
    assert all("File name too long" in r and _one_sentence(r) for r in runs["reason"])


@pytest.mark.parametrize("where", ["data_dir", "run_sheet", "tare"])
def test_a_protocol_path_in_a_link_loop_stops_before_anything_is_written(where, tmp_path,
                                                                          capsys):
    loop = tmp_path / "loop"
    os.symlink(loop, loop)
    protocol = _day(tmp_path, **({"tare": {"source": "table", "table": "loop"}} if where == "tare"
                                 else {"campaign": {where: "loop"}}))
    assert main(["process", str(protocol), "-q", "--no-report"]) == 2
    said = capsys.readouterr().err.strip()
    assert said.startswith("towtank: protocol.toml: "), said
    assert ("symlink loop" in said or "symbolic links" in said) and "\n" not in said, said
    assert not (tmp_path / "out").exists()


# ------------------------------------------------- 13. numbers too large for a float
HUGE = 10**310 - 1


@pytest.mark.parametrize(("section", "key", "value"), [
    ("model", "mass_kg", HUGE), ("water", "temperature_C", -HUGE),
    ("channels", "drag", {"column": "Fx load cell (V)", "gain": HUGE}),
    ("prototype", "speeds_m_s", [1.0, HUGE])])
def test_an_integer_too_large_for_a_float_in_the_protocol_is_exit_2(section, key, value,
                                                                     tmp_path, capsys):
    protocol = _day(tmp_path, **{section: {key: value}})
    assert main(["process", str(protocol), "-q", "--no-report"]) == 2
    said = capsys.readouterr().err.strip()
    assert said.startswith("towtank: protocol.toml: '") and said.count("\n") == 0, said
    assert f"'{'gain' if section == 'channels' else key}'" in said, said
    assert "an integer of 310 digits" in said, said
    assert not (tmp_path / "out").exists()


def test_an_integer_past_pythons_digit_bound_names_its_key(tmp_path, capsys):
    protocol = _day(tmp_path)
    text = protocol.read_text(encoding="utf-8")
    protocol.write_text(text.replace("mass_kg = 0.552", "mass_kg = " + "9" * 5000),
                        encoding="utf-8")
    assert main(["process", str(protocol), "-q", "--no-report"]) == 2
    said = capsys.readouterr().err.strip()
    assert said == ("towtank: protocol.toml: 'mass_kg' is an integer of more than "
                    f"{sys.get_int_max_str_digits()} digits, not a number a protocol can hold.")
    assert not (tmp_path / "out").exists()


def _xlsx_with_huge_cell(csv_sheet: Path, out: Path, run: int, column: str) -> None:
    """The CSV sheet as an .xlsx whose cell of ``run`` in ``column`` holds a 310-digit number,
    as a hand-edited workbook can (openpyxl itself cannot write one)."""
    frame = pd.read_csv(csv_sheet)
    frame.loc[frame["run"] == run, column] = 7777777
    frame.to_excel(out, index=False)
    with zipfile.ZipFile(out) as zin:
        parts = [(info, zin.read(info.filename)) for info in zin.infolist()]
    with zipfile.ZipFile(out, "w") as zout:
        for info, body in parts:
            if info.filename.startswith("xl/worksheets/"):
                assert b">7777777<" in body
                body = body.replace(b">7777777<", b">" + str(HUGE).encode() + b"<")
            zout.writestr(info, body)


@pytest.mark.parametrize("sheet", ["csv", "xlsx"])
def test_a_number_too_large_for_a_float_in_the_sheet_rejects_its_run(sheet, tmp_path):
    protocol = _day(tmp_path)
    data = tmp_path / "data"
    (data / "run_005.csv").write_bytes((data / "run_004.csv").read_bytes())
    if sheet == "csv":
        run = _add_run(tmp_path, "run_005.csv", speed_nominal=str(HUGE))
    else:
        run = _add_run(tmp_path, "run_005.csv")
        _xlsx_with_huge_cell(tmp_path / "run_sheet.csv", tmp_path / "run_sheet.xlsx", run,
                             "angle_deg")
        text = protocol.read_text(encoding="utf-8").replace("run_sheet.csv", "run_sheet.xlsx")
        protocol.write_text(text, encoding="utf-8")
    assert main(["process", str(protocol), "-q", "--jobs", "1", "--no-report"]) == 1
    runs = _runs(tmp_path)
    reason = runs.loc[run, "reason"]
    assert runs.loc[run, "status"] == "rejected"
    assert reason.startswith(f"run {run}: row {run + 1} of run_sheet.{sheet}: "), reason
    assert "is not a number" in reason and _one_sentence(reason), reason
    assert (runs.drop(index=run)["status"] == "ok").all()


@pytest.mark.parametrize(("section", "key", "value", "said"), [
    ("model", "wetted_area_m2", 1.1235582092889474e307, "beyond the 1e+12 in magnitude"),
    ("prototype", "water", {"type": "sea", "temperature_C": 15.0, "salinity_g_kg": 1000.0},
     "grams of salt in a kilogram of sea water, below 1000"),
    ("model", "myring", {**syn.hull_protocol_sections()["model"]["myring"], "c": 1e-300},
     "[model.myring] does not describe a hull (float division by zero)")])
def test_numbers_that_overflowed_downstream_are_exit_2(section, key, value, said, tmp_path,
                                                       capsys):
    """Numbers that overflow or divide by zero downstream (in the scaling, IAPWS-08 or the
    Myring geometry; found by the property below) are exit 2 with one sentence, not exit 3."""
    protocol = _day(tmp_path, **{section: {key: value}})
    assert main(["process", str(protocol), "-q", "--no-report"]) == 2
    err = capsys.readouterr().err.strip()
    assert said in err and err.count("\n") == 0, err
    assert not (tmp_path / "out").exists()


#: Every numeric key of the sections the day's protocol has, as (section path, key).
NUMERIC_KEYS = sorted(
    (section, key)
    for section in ("water", "model", "model.myring", "prototype", "prototype.water",
                    "processing", "read", "watch")
    for key, (kind, _) in SCHEMA[section].items() if kind in ("float", "int", "floats")
) + [("channels.drag", "gain"), ("channels.drag", "offset"), ("speed_log", "offset_s")]

TOML_NUMBERS = st.one_of(
    st.integers(),
    st.integers(min_value=-(10**400), max_value=10**400),
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([HUGE, -HUGE, 10**4000, math.inf, -math.inf, math.nan, 0, -1, 1e308]),
)


@pytest.fixture(scope="session")
def number_day(tmp_path_factory) -> tuple[Path, dict[str, Any]]:
    root = tmp_path_factory.mktemp("numbers")
    _day(root)
    return root, syn.hull_protocol_sections(".", "out", sheet_format="csv")


@settings(max_examples=40, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(where=st.sampled_from(NUMERIC_KEYS), value=TOML_NUMBERS)
def test_any_toml_number_in_any_numeric_key_is_never_an_internal_error(where, value,
                                                                       number_day):
    root, base = number_day
    section, key = where
    sections = {k: (dict(v) if isinstance(v, dict) else v) for k, v in base.items()}
    parts = section.split(".")
    if parts[0] == "speed_log":
        sections["speed_log"] = {"file": "{stem}.csv", "speed": {"column": "Carriage speed "
                                                                 "(m/s)"}}
    table = sections.setdefault(parts[0], {})
    for part in parts[1:]:
        table[part] = dict(table.get(part, {}))
        table = table[part]
    table[key] = [1.0, value] if SCHEMA.get(section, {}).get(key, ("",))[0] == "floats" \
        else value
    protocol = syn.write_protocol(root / "protocol.toml", **sections)
    code = main(["process", str(protocol), "-q", "--jobs", "1", "--no-report"])
    assert code in (0, 1, 2), (where, value, code)
