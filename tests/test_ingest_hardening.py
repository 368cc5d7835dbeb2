"""Issue 20 (adversarial review), the ingest part: files built to mislead or to exhaust the
readers are either read as the lab meant them or refused in one sentence, through the real
pipeline (exit status, the sentence, the other runs still processed).

- item 8: which worksheet of a run-sheet workbook is read (never a hidden one unless named),
  and a formula whose saved value is the empty string;
- item 9: a text run file cut in the middle of a line (CSV, LVM, European text, whitespace
  text) is refused with the same sentence, never read with a value "interpolated";
- item 6: the declared size of .mat and HDF5 arrays is checked before anything is read (a
  compression bomb, an unwritten 2³¹-element dataset), under an address-space limit so that a
  regression fails instead of eating the machine; huge reference CSVs and tare tables;
- item 11: HDF5 sample-rate attributes that are text, zero, empty, and soft-link loops.
"""

from __future__ import annotations

import functools
import os
import re
import shutil
import struct
import subprocess
import textwrap
import zipfile
import zlib
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from towtank.commands.cli import main
from towtank.errors import RunError
from towtank.ingest.runsheet import read_run_sheet
from towtank.testing import synthetic as syn
from towtank.testing.child import run_in_child
from towtank.testing.days import reading_day_plan
from towtank.testing.hang import hang_bound
from towtank.testing.layouts import layout_channels, protocol_sections

SEED = 20
REPO = Path(__file__).resolve().parents[1]
#: The day of these tests: what they test is how one run's file or the sheet is read, never
#: the fit, so eleven runs carry it as well as 42 (run 21 among them); "the rest of the day"
#: is every other run, processed.
PLAN = reading_day_plan()


def _day(root: Path, file_format: str = "csv", sheet_format: str = "csv",
         **sections: dict) -> Path:
    """A synthetic hull day in ``root`` (run files in ``file_format``); its protocol."""
    syn.make_hull_day(root, seed=SEED, file_format=file_format, sheet_format=sheet_format,
                      runs=PLAN)
    channels = layout_channels(file_format, syn.LabChannels())
    sec = syn.hull_protocol_sections(".", "out", sheet_format=sheet_format, channels=channels)
    sec = protocol_sections(file_format, sec)
    for name, values in sections.items():
        sec.setdefault(name, {}).update(values)
    return syn.write_protocol(root / "protocol.toml", **sec)


def _process(protocol: Path) -> int:
    return main(["process", str(protocol), "--out", str(protocol.parent / "out"),
                 "--no-report", "-q"])


def _runs(protocol: Path) -> pd.DataFrame:
    return pd.read_csv(protocol.parent / "out" / "runs.csv").set_index("run")


def _only_rejected(protocol: Path, run: int) -> str:
    """The reason of ``run``, after checking that it is the day's only rejected run."""
    runs = _runs(protocol)
    rejected = runs.index[runs["status"] == "rejected"].tolist()
    assert rejected == [run], runs.loc[rejected, "reason"].to_dict()
    assert (runs["status"] == "ok").sum() == len(PLAN) - 1  # the rest of the day is processed
    return str(runs.loc[run, "reason"])


def _one_sentence(text: str) -> None:
    assert "\n" not in text.strip() and "Traceback" not in text
    assert "internal error" not in text and "please report" not in text


# =============================================================== item 8: which worksheet
def _xlsx_day(root: Path) -> tuple[Path, Path]:
    protocol = _day(root, sheet_format="xlsx")
    return protocol, root / "run_sheet.xlsx"


def _copy_sheet(wb, title: str, index: int, angle_21: float):  # noqa: ANN001, ANN202
    """A copy of the run table as worksheet ``title`` at ``index``, run 21's angle changed."""
    src = wb.worksheets[0]
    rows = [list(r) for r in src.iter_rows(values_only=True)]
    ws = wb.create_sheet(title, index)
    col = rows[0].index("angle_deg")
    for r in rows:
        if r[0] == 21:
            r[col] = angle_21
        ws.append(r)
    return ws


def test_a_hidden_first_worksheet_is_not_the_run_sheet(tmp_path, capsys):
    """An old copy of the table hidden in the first tab (run 21 at 0°): the visible sheet
    (run 21 at 5°) is read; named in [sheet] name, the hidden one is."""
    import openpyxl

    protocol, path = _xlsx_day(tmp_path)
    wb = openpyxl.load_workbook(path)
    hidden = _copy_sheet(wb, "old runs", 0, 0.0)
    hidden.sheet_state = "hidden"
    wb.active = 1
    wb.save(path)
    assert read_run_sheet(path, 18.0).set_index("run").loc[21, "angle_deg"] == 5.0
    assert _process(protocol) == 0
    assert _runs(protocol).loc[21, "angle_deg"] == 5.0

    named = read_run_sheet(path, 18.0, _sheet_options(name="old runs"))
    assert named.set_index("run").loc[21, "angle_deg"] == 0.0
    for state in ("hidden", "veryHidden"):
        wb = openpyxl.load_workbook(path)
        wb.worksheets[0].sheet_state = state
        wb.active = 1
        wb.save(path)
        assert read_run_sheet(path, 18.0).set_index("run").loc[21, "angle_deg"] == 5.0


def _sheet_options(**kw):  # noqa: ANN003, ANN202
    from towtank.ingest.sheetlayout import parse_sheet_options

    return parse_sheet_options(kw, "p.toml")


def test_the_sheet_name_key_picks_a_worksheet_through_the_pipeline(tmp_path, capsys):
    import openpyxl

    protocol, path = _xlsx_day(tmp_path)
    wb = openpyxl.load_workbook(path)
    _copy_sheet(wb, "old runs", 0, 0.0).sheet_state = "hidden"
    wb.active = 1
    wb.save(path)
    text = protocol.read_text(encoding="utf-8")
    protocol.write_text(text + '\n[sheet]\nname = "old runs"\n', encoding="utf-8")
    assert _process(protocol) == 0
    assert _runs(protocol).loc[21, "angle_deg"] == 0.0

    protocol.write_text(text + '\n[sheet]\nname = "Runs 2024"\n', encoding="utf-8")
    assert _process(protocol) == 2
    err = capsys.readouterr().err
    assert "[sheet] name = 'Runs 2024', but the workbook has no worksheet of that name" in err
    assert "'old runs' (hidden)" in err
    _one_sentence(err)


def test_only_a_hidden_worksheet_with_the_columns_stops_the_day(tmp_path, capsys):
    import openpyxl

    protocol, path = _xlsx_day(tmp_path)
    wb = openpyxl.load_workbook(path)
    notes = wb.create_sheet("notes", 0)
    notes["A1"] = "operator notes"
    wb.worksheets[1].sheet_state = "hidden"
    wb.active = 0
    wb.save(path)
    assert _process(protocol) == 2
    err = capsys.readouterr().err
    assert "no visible worksheet has the required columns" in err
    assert "the hidden worksheet 'Sheet' has them" in err or "hidden worksheet" in err
    assert "[sheet] name" in err
    _one_sentence(err)
    assert not (tmp_path / "out").exists()


def test_two_visible_worksheets_with_the_columns_give_one_warning(tmp_path, capsys):
    """The active worksheet is read (here the second tab), and the day says so."""
    import openpyxl

    protocol, path = _xlsx_day(tmp_path)
    wb = openpyxl.load_workbook(path)
    first = wb.worksheets[0].title
    _copy_sheet(wb, "copy", 1, 7.5)
    wb.active = 1
    wb.save(path)
    assert main(["process", str(protocol), "--out", str(tmp_path / "out"), "--no-report"]) == 0
    captured = capsys.readouterr()
    assert _runs(protocol).loc[21, "angle_deg"] == 7.5
    line = next(ln for ln in (captured.out + captured.err).splitlines()
                if "visible worksheets" in ln)
    assert f"('{first}', 'copy'); 'copy' is used (the active one)" in line
    assert "[sheet] name" in line

    wb = openpyxl.load_workbook(path)
    wb.active = 2  # past both: a third tab, without the columns
    wb.create_sheet("chart data")
    wb.active = 2
    wb.save(path)
    sheet = read_run_sheet(path, 18.0)
    assert sheet.set_index("run").loc[21, "angle_deg"] == 5.0  # the first of the two
    assert f"'{first}' is used (the first)" in sheet.attrs["warnings"][0]


def test_a_sheet_name_with_a_csv_sheet_stops_the_day(tmp_path, capsys):
    protocol = _day(tmp_path)
    protocol.write_text(protocol.read_text(encoding="utf-8") + '\n[sheet]\nname = "runs"\n',
                        encoding="utf-8")
    assert _process(protocol) == 2
    err = capsys.readouterr().err
    assert "names a worksheet, but the run sheet is a CSV file" in err


def _set_cell_xml(path: Path, coordinate: str, cell_xml: bytes) -> None:
    """Replace cell ``coordinate`` of the first worksheet by ``cell_xml`` (as Excel or a
    program writes it)."""
    with zipfile.ZipFile(path) as zin:
        parts = [(i, zin.read(i)) for i in zin.infolist()]
    pattern = re.compile(rb'<c r="' + coordinate.encode() + rb'"[^>]*?(/>|>.*?</c>)', re.S)
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as zout:
        for info, data in parts:
            if info.filename == "xl/worksheets/sheet1.xml":
                data, n = pattern.subn(cell_xml, data, count=1)
                assert n == 1, coordinate
            zout.writestr(info, data)


def _remarks_cell(path: Path, run: int) -> str:
    """The coordinate of run ``run``'s remarks cell, given a text for the XML to hold."""
    import openpyxl

    wb = openpyxl.load_workbook(path)
    ws = wb.worksheets[0]
    header = [c.value for c in ws[1]]
    col = header.index("remarks") + 1
    row = next(r for r in range(2, ws.max_row + 1) if ws.cell(r, 1).value == run)
    ws.cell(row, col).value = "placeholder"
    wb.save(path)
    return ws.cell(row, col).coordinate


@pytest.mark.parametrize("cell", [
    b'<c r="{ref}" t="str"><f>IF(A2&gt;0,"","repeat")</f><v></v></c>',  # Excel
    b'<c r="{ref}" s="0" t="str"><f>IF(A2&gt;0,"","repeat")</f><v/></c>',  # LibreOffice
])
def test_a_formula_whose_saved_value_is_empty_text_is_an_empty_cell(tmp_path, cell):
    protocol, path = _xlsx_day(tmp_path)
    ref = _remarks_cell(path, 21)
    _set_cell_xml(path, ref, cell.replace(b"{ref}", ref.encode()))
    assert read_run_sheet(path, 18.0).set_index("run").loc[21, "remarks"] == ""
    assert _process(protocol) == 0


@pytest.mark.parametrize("cell", [
    b'<c r="{ref}"><f>IF(A2&gt;0,"","repeat")</f><v/></c>',  # openpyxl: never computed
    b'<c r="{ref}"><f>IF(A2&gt;0,"","repeat")</f></c>',
    b'<c r="{ref}" t="n"><f>1+1</f><v></v></c>',
])
def test_a_formula_with_no_saved_value_still_stops_the_day(tmp_path, capsys, cell):
    protocol, path = _xlsx_day(tmp_path)
    ref = _remarks_cell(path, 21)
    _set_cell_xml(path, ref, cell.replace(b"{ref}", ref.encode()))
    assert _process(protocol) == 2
    err = capsys.readouterr().err
    assert f"the cell(s) {ref} hold formulas with no saved value" in err
    _one_sentence(err)


# ================================================================= item 9: truncated text
TRUNCATED = re.compile(
    r"^(run \d+: )?(?P<file>\S+) ends in the middle of a line \((row (?P<row>\d+) has "
    r"(?P<k>\d+) of (?P<n>\d+) values|row (?P<row2>\d+) ends in '[^']*', a number cut "
    r"short); a truncated file\): was it copied before the recording finished\?$")


def _cut_mid_line(data: bytes, fraction: float = 0.6, keep_fields: int = 2,
                  sep: bytes = b",") -> tuple[bytes, int]:
    """``data`` cut inside a data line after ``keep_fields`` fields and a part of the next
    value; the cut line's row (1-based)."""
    start = data.index(b"\n", int(len(data) * fraction)) + 1
    line = data[start : data.index(b"\n", start)]
    fields = re.split(rb"[ \t]+" if sep == b" " else re.escape(sep), line.strip())
    head = sep.join(fields[:keep_fields]) + sep + fields[keep_fields][:2]
    cut = data[: start + line.index(fields[0])] + head
    return cut, cut.count(b"\n") + 1


def _whitespace_day(root: Path) -> tuple[Path, str]:
    """A day of canonical CSV files with run 21 as whitespace-separated text (.dat)."""
    syn.make_hull_day(root, seed=SEED, file_format="csv", sheet_format="csv",
                      channel_style="canonical", runs=PLAN)
    sec = syn.hull_protocol_sections(".", "out", sheet_format="csv", channel_style="canonical")
    protocol = syn.write_protocol(root / "protocol.toml", **sec)
    frame = pd.read_csv(root / "data" / "run_021.csv")
    (root / "data" / "run_021.csv").unlink()
    text = frame.to_string(index=False, float_format=lambda v: f"{v:.7g}")
    (root / "data" / "run_021.dat").write_text(text + "\n", encoding="utf-8")
    sheet = root / "run_sheet.csv"
    sheet.write_text(sheet.read_text().replace("run_021.csv", "run_021.dat"))
    return protocol, "run_021.dat"


@pytest.mark.parametrize("layout, suffix, sep", [
    ("csv", "csv", b","), ("lvm", "lvm", b"\t"), ("txt-eu", "txt", b";"),
    ("whitespace", "dat", b" "),
])
def test_a_run_file_cut_mid_line_is_rejected_in_every_text_layout(tmp_path, capsys, layout,
                                                                   suffix, sep):
    """The same sentence for a cut CSV, LVM, European or whitespace text; the day goes on.
    (An LVM cut mid-line was read with the missing values interpolated; a European text gave
    "columns found: '8,835', …".)"""
    if layout == "whitespace":
        protocol, name = _whitespace_day(tmp_path)
    else:
        protocol = _day(tmp_path, file_format=layout)
        name = f"run_021.{suffix}"
    path = tmp_path / "data" / name
    cut, row = _cut_mid_line(path.read_bytes(), sep=sep)
    path.write_bytes(cut)
    assert _process(protocol) == 1
    reason = _only_rejected(protocol, 21)
    m = TRUNCATED.match(reason)
    assert m, reason
    assert m["file"] == name and int(m["row"] or m["row2"]) == row
    if m["k"]:
        assert int(m["k"]) < int(m["n"])
    err = capsys.readouterr().err
    assert "internal error" not in err


@pytest.mark.parametrize("tail", [b";", b";-", b";0,1e", b";1,5e-", b";8,"])
def test_european_text_cut_inside_its_last_value(tmp_path, tail):
    from towtank.ingest.runfile import read_columns

    protocol = _day(tmp_path, file_format="txt-eu")  # noqa: F841 - the files
    data = (tmp_path / "data" / "run_021.txt").read_bytes()
    lines = data.split(b"\n")
    k = len(lines) // 2
    cut = b"\n".join(lines[:k]) + b"\n" + lines[k][: lines[k].rfind(b";")] + tail
    if tail == b";8,":  # a complete number ("8," is 8): read as written
        cols, _ = read_columns(Path("run_021.txt"), cut)
        assert cols["Fy load cell (V)"][-1] == 8.0
        return
    with pytest.raises(RunError) as info:
        read_columns(Path("run_021.txt"), cut)
    assert TRUNCATED.match(str(info.value)), info.value
    assert f"row {k + 1} " in str(info.value)


# ------------------------------------------------ the rule as a property of every prefix
def _text_files(root: Path, n: int) -> dict[str, bytes]:
    """An ``n``-row run in each text layout: CSV, European text, LVM (two segments),
    whitespace."""
    from towtank.testing.layouts import write_layout

    rng = np.random.default_rng(3)
    frame = pd.DataFrame({
        "Time (s)": np.round(np.arange(n) * 0.005, 3),
        "Carriage speed (m/s)": np.round(rng.normal(0.5, 0.3, n), 4),
        "Fx load cell (V)": np.round(rng.normal(-0.01, 0.004, n), 8),
        "Fy load cell (V)": np.round(rng.normal(0.003, 0.002, n), 8),
    })
    units = {"Time (s)": "s", "Carriage speed (m/s)": "m/s", "Fx load cell (V)": "V",
             "Fy load cell (V)": "V"}
    out = {}
    for layout, name in (("two-cell", "run.csv"), ("txt-eu", "run.txt"), ("lvm", "run.lvm")):
        out[name] = write_layout(layout, frame, root / name, "Time (s)", units).read_bytes()
    plain = frame.rename(columns=lambda c: c.split(" ")[0] if c != "Fx load cell (V)" else
                         "Fx").rename(columns={"Fy": "Fy"})
    out["run.dat"] = (plain.to_string(index=False, float_format=lambda v: f"{v:.8g}") +
                      "\n").encode()
    return out


@functools.cache
def _data_line_ends(data: bytes) -> tuple[int, ...]:
    """Byte offsets just after each data line (a line starting with a digit or a sign);
    worked out once per file (every prefix of it asks)."""
    ends, pos = [], 0
    for line in data.split(b"\n")[:-1]:
        if line.lstrip()[:1] in (*(bytes([c]) for c in b"0123456789"), b"-", b"+", b"."):
            ends.append(pos + len(line) + 1)
        pos += len(line) + 1
    return tuple(ends)


def _as_float(text: bytes, decimal_comma: bool) -> float:
    text = text.strip()
    return float(text.replace(b",", b".") if decimal_comma else text) if text else np.nan


def _files_and_columns(root: Path, n: int) -> tuple[dict[str, bytes], dict[str, dict]]:
    from towtank.ingest.runfile import read_columns

    files = _text_files(root, n)
    full = {}
    for name, data in files.items():
        cols, _ = read_columns(Path(name), data)
        full[name] = {k: np.asarray(v, dtype=float) for k, v in cols.items()
                      if not k.startswith("__")}
        assert all(v.size == n for v in full[name].values()), name
    return files, full


@pytest.fixture(scope="session")
def small_files(tmp_path_factory):
    return _files_and_columns(tmp_path_factory.mktemp("small"), 30)


@pytest.fixture(scope="session")
def long_files(tmp_path_factory):
    return _files_and_columns(tmp_path_factory.mktemp("long"), 3000)


def _check_prefix(name: str, data: bytes, full: dict[str, np.ndarray], cut: int) -> None:
    from towtank.ingest.runfile import read_columns

    prefix = data[:cut]
    ends = _data_line_ends(data)
    k = sum(e <= cut for e in ends)
    try:
        cols, _ = read_columns(Path(name), prefix)
    except RunError as exc:
        text = str(exc)
        if TRUNCATED.match(text):
            assert not prefix.endswith(b"\n"), text  # only a cut line is named so
            return
        assert k == 0, f"{cut}: {k} complete rows, but: {text}"  # nothing to read yet
        return
    got = {c: np.asarray(cols[c], dtype=float) for c in full}
    sizes = {v.size for v in got.values()}
    assert len(sizes) == 1, sizes
    n = sizes.pop()
    assert n in (k, k + 1), (cut, n, k)
    for c, values in full.items():
        np.testing.assert_array_equal(got[c][:k], values[:k], err_msg=f"{name} {c} cut {cut}")
    if n == k + 1:  # the last line has every value, the last perhaps cut to a shorter number
        assert not prefix.endswith(b"\n")
        line = prefix[prefix.rfind(b"\n") + 1 :]
        sep = {"run.csv": b",", "run.txt": b";", "run.lvm": b"\t"}.get(name)
        fields = line.split(sep) if sep else line.split()
        fields = [f for f in fields if f.strip()] if name == "run.lvm" else fields
        written = [_as_float(f, name == "run.txt") for f in fields]
        row = [got[c][k] for c in full if c != "time"]  # LVM: time is X_Value again
        np.testing.assert_array_equal(row[: len(written)], written[: len(row)])


@pytest.mark.heavy
def test_every_prefix_of_a_short_file_in_each_layout(small_files):
    """Exhaustively: each of the ~5500 prefixes of a 30-row file in the four layouts (cuts in
    the header, the units row, an LVM segment header, a number, a separator)."""
    files, full = small_files
    for name, data in files.items():
        for cut in range(len(data) + 1):
            _check_prefix(name, data, full[name], cut)


@pytest.mark.heavy
@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(which=st.sampled_from(["run.csv", "run.txt", "run.lvm", "run.dat"]),
       where=st.floats(0.0, 1.0))
def test_any_prefix_is_read_as_its_complete_rows_or_refused_with_the_sentence(
        long_files, which, where):
    """A prefix of a 3000-row file is read as exactly its complete rows (and a last line
    with every value, read as written: a number cut to a shorter one cannot be told), or
    refused with the truncation sentence; before the first complete row, with a RunError.
    Never anything else."""
    files, full = long_files
    data = files[which]
    _check_prefix(which, data, full[which], int(round(where * len(data))))


# ====================================================== item 6: declared sizes, before reading
LIMIT_GIB = 2.0  # address space of the subprocesses below: a regression fails, never swaps

#: Run in the child before towtank is loaded: the address-space limit, and ``read PATH``.
_LIMIT = textwrap.dedent(f"""
    import resource
    limit = int({LIMIT_GIB} * 2**30)
    resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    from pathlib import Path
    from towtank.errors import RunError
    from towtank.ingest.runfile import read_columns

    def read(path):
        try:
            read_columns(Path(path))
        except RunError as exc:
            print("RunError:", exc)
            return 0
        print("read")
        return 0
""")


def _limited(commands: dict[str, list[str]], timeout: float = 300
             ) -> dict[str, subprocess.CompletedProcess]:
    """Each of ``commands`` (towtank's ``process ...``, or one file read: ``read PATH``) run
    one after the other in one subprocess (one start-up and import for all) whose address
    space is limited to LIMIT_GIB: each command's exit status, stdout and stderr."""
    env = dict(os.environ, PYTHONPATH=str(REPO), OPENBLAS_NUM_THREADS="1",
               OMP_NUM_THREADS="1", MKL_NUM_THREADS="1")
    done = run_in_child(list(commands.values()), timeout=timeout, prelude=_LIMIT, env=env,
                        call='read(args[1]) if args[0] == "read" else main(args)')
    return dict(zip(commands, done, strict=True))


def _process_args(protocol: Path) -> list[str]:
    return ["process", str(protocol), "--out", str(protocol.parent / "out"), "--no-report",
            "-q", "--jobs", "1"]


def _zlib_of_zeros(prefix: bytes, total: int, chunk: int = 1 << 24) -> bytes:
    """A zlib stream of ``prefix`` followed by zeros, ``total`` bytes in all, built in a
    fraction of a second: one compressed chunk of zeros repeated (after a full flush each
    chunk compresses to the same bytes) and the Adler-32 of the whole worked out."""
    assert total % chunk == 0 and len(prefix) < chunk
    c = zlib.compressobj(9)
    zeros = bytes(chunk)
    first = c.compress(prefix + zeros[len(prefix):]) + c.flush(zlib.Z_FULL_FLUSH)
    again = c.compress(zeros) + c.flush(zlib.Z_FULL_FLUSH)
    assert again == c.compress(zeros) + c.flush(zlib.Z_FULL_FLUSH)
    end = c.flush()[:-4]
    a = zlib.adler32(prefix)
    low, high = a & 0xFFFF, ((a >> 16) + (a & 0xFFFF) * (total - len(prefix))) % 65521
    return first + again * (total // chunk - 1) + end + struct.pack(">I", (high << 16) | low)


def _mat_bomb(name: bytes, chunks: int) -> bytes:
    """A compressed MAT v5 variable: a column of 2²¹·chunks − 7 zeros (doubles), ~3 MB of file
    for chunks = 192, 3 GiB once decompressed."""
    n = (1 << 21) * chunks - 7
    head = struct.pack("<II", 14, 48 + 8 * n)  # miMATRIX
    head += struct.pack("<IIII", 6, 8, 6, 0)  # array flags: double
    head += struct.pack("<IIii", 5, 8, n, 1)  # dimensions n × 1
    head += struct.pack("<HH", 1, len(name)) + name.ljust(4, b"\0")  # small element: name
    head += struct.pack("<II", 9, 8 * n)  # miDOUBLE
    stream = _zlib_of_zeros(head, len(head) + 8 * n)
    return struct.pack("<II", 15, len(stream)) + stream  # miCOMPRESSED


def _mat_bomb_day(root: Path) -> tuple[Path, list[str]]:
    """A .mat day whose run 21 holds 3 MB that decompress to 3 GiB; the command."""
    protocol = _day(root, file_format="mat")
    path = root / "data" / "run_021.mat"
    path.write_bytes(path.read_bytes() + _mat_bomb(b"big", 192))
    return path, _process_args(protocol)


def _nested_mat(root: Path) -> tuple[Path, list[str]]:
    """An uncompressed cell array inside a struct whose dimensions say 2³¹−1 elements."""
    import scipy.io

    root.mkdir()
    path = root / "run.mat"
    scipy.io.savemat(path, {"t": np.arange(100.0), "drag": np.zeros(100),
                            "s": {"cells": np.array([[1.0]], dtype=object)}}, format="5")
    data = bytearray(path.read_bytes())
    # the cell's dimensions: the last but one miINT32 [1, 1] pair in the file (the last is
    # the double inside the cell), rewritten 2^31-1 × 1
    dims = struct.pack("<IIii", 5, 8, 1, 1)
    at = bytes(data).rfind(dims, 0, bytes(data).rfind(dims))
    assert at > 0
    data[at + 8 : at + 12] = struct.pack("<i", 2**31 - 1)
    path.write_bytes(bytes(data))
    return path, ["read", str(path)]


def _unwritten_dataset_day(root: Path, layout: str, group: str) -> tuple[Path, list[str]]:
    """An HDF5 (or MATLAB v7.3) day whose run 21 holds a dataset of 2³¹ doubles never
    written."""
    import h5py

    protocol = _day(root, file_format=layout)
    path = root / "data" / f"run_021.{'h5' if layout == 'hdf5' else 'mat'}"
    with h5py.File(path, "a") as fh:
        fh[group].create_dataset("big", shape=(2**31,), dtype="f8", chunks=(1 << 20,))
    return path, _process_args(protocol)


@pytest.fixture(scope="session")
def limited(tmp_path_factory) -> dict[str, tuple[Path, subprocess.CompletedProcess]]:
    """The files of the tests below, each with what its command did in one subprocess under
    the address-space limit (:func:`_limited`)."""
    root = tmp_path_factory.mktemp("limited")
    made = {"mat-bomb": _mat_bomb_day(root / "mat"),
            "nested-mat": _nested_mat(root / "nested"),
            "hdf5": _unwritten_dataset_day(root / "hdf5", "hdf5", "data"),
            "mat73": _unwritten_dataset_day(root / "mat73", "mat73", "/")}
    done = _limited({key: args for key, (_, args) in made.items()})
    return {key: (path, done[key]) for key, (path, _) in made.items()}


@pytest.mark.heavy
def test_a_compressed_mat_variable_declaring_3_gib_is_refused_before_it_is_read(limited):
    """3 MB of .mat that decompresses to 3 GiB (a run file is capped at 1 GiB): rejected
    from the size its header declares, in well under a second and without the memory; the
    other runs of the day are processed."""
    path, done = limited["mat-bomb"]
    assert path.stat().st_size < 4 << 20
    assert done.returncode == 1, done.stderr
    reason = _only_rejected(path.parents[1] / "protocol.toml", 21)
    assert "is too large for one run: its compressed MATLAB variable 'big' (402653177×1) " \
           "declares 3.0 GiB of numbers" in reason, reason
    assert "checked before reading" in reason
    _one_sentence(done.stderr)


@pytest.mark.heavy
def test_a_nested_mat_array_declaring_huge_dimensions_is_refused(limited):
    """An uncompressed cell array inside a struct whose dimensions say 2³¹ elements (a
    reader would allocate 16 GiB of object pointers before reading one): refused from the
    dimensions, wherever the array is nested."""
    _, done = limited["nested-mat"]
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith("RunError: run.mat is too large for one run: its MATLAB "
                                  "variable 's.cells' (2147483647×1) declares 16.0 GiB"), \
        done.stdout


@pytest.mark.heavy
@pytest.mark.parametrize("layout", ["hdf5", "mat73"])
def test_an_unwritten_dataset_of_2_31_values_is_refused_before_it_is_read(limited, layout):
    """A 10 kB HDF5 file (or MATLAB v7.3) whose dataset of 2³¹ doubles was never written:
    reading it would fill 16 GiB; its shape rejects the run first."""
    path, done = limited[layout]
    assert path.stat().st_size < 1 << 20
    assert done.returncode == 1, done.stderr
    reason = _only_rejected(path.parents[1] / "protocol.toml", 21)
    assert "is too large for one run: its" in reason and "dataset '/big' (2147483648) " \
        "declares 16.0 GiB of numbers" in reason.replace("/data/big", "/big"), reason
    _one_sentence(done.stderr)


def test_a_compressed_mat_file_reads_as_the_uncompressed_one(tmp_path):
    """The inflation that checks the declared sizes gives scipy the same variables."""
    import scipy.io

    from towtank.ingest.arrayfiles import read_mat_columns

    rng = np.random.default_rng(1)
    run = {"t": np.arange(500) / 200.0, "U": rng.normal(size=500), "drag": rng.normal(size=500)}
    plain, packed = tmp_path / "a.mat", tmp_path / "b.mat"
    scipy.io.savemat(plain, {"run": run, "fs": 200.0, "note": "x"}, do_compression=False)
    scipy.io.savemat(packed, {"run": run, "fs": 200.0, "note": "x"}, do_compression=True)
    a, _ = read_mat_columns(plain.read_bytes(), "a.mat")
    b, _ = read_mat_columns(packed.read_bytes(), "b.mat")
    assert packed.stat().st_size < plain.stat().st_size
    assert sorted(a) == sorted(b)
    for key in ("t", "U", "drag", "__fs__"):
        np.testing.assert_array_equal(a[key], b[key])


@pytest.mark.parametrize("what", ["reference", "tare"])
def test_a_huge_reference_csv_or_tare_table_stops_the_day_before_it_is_read(tmp_path, capsys,
                                                                             what):
    """A 100 MiB file (sparse here) where a table of a few lines is expected: exit 2 in one
    sentence, nothing written."""
    table = tmp_path / f"{what}.csv"
    head = "symbol,prime\nX_udot,-0.01\n" if what == "reference" else \
        "speed_m_s,drag_N\n0.5,0.1\n1.0,0.4\n"
    table.write_text(head, encoding="utf-8")
    with open(table, "r+b") as fh:
        fh.truncate(100 << 20)
    if what == "reference":
        protocol = _day(tmp_path, campaign={"reference": f"{what}.csv"})
    else:
        protocol = _day(tmp_path, tare={"source": "table", "table": f"{what}.csv"})
    assert _process(protocol) == 2
    err = capsys.readouterr().err
    name = "reference CSV" if what == "reference" else "tare table"
    assert f"the {name} {what}.csv is 100 MiB, but towtank reads such tables up to 64 MiB" \
        in err, err
    _one_sentence(err)
    assert not (tmp_path / "out").exists()


def test_a_fifo_as_tare_table_stops_the_day(tmp_path, capsys):
    """Opened, a named pipe waits forever for a writer: refused before (within a hang bound,
    so that a regression fails rather than hanging the tests)."""
    os.mkfifo(tmp_path / "tare.csv")
    protocol = _day(tmp_path, tare={"source": "table", "table": "tare.csv"})
    with hang_bound(120):
        assert _process(protocol) == 2
    assert "the tare table tare.csv is not a regular file" in capsys.readouterr().err


# ============================================== item 11: HDF5 sample-rate attributes, links
@pytest.fixture(scope="session")
def hdf5_timing_template(tmp_path_factory) -> Path:
    """An HDF5 day whose time comes from the group's ``sample_rate`` attribute (the time
    column left unmapped and renamed away), made once; each test edits a copy."""
    import h5py

    root = tmp_path_factory.mktemp("hdf5_timing")
    protocol = _day(root, file_format="hdf5")
    text = protocol.read_text(encoding="utf-8")
    text = "\n".join(ln for ln in text.splitlines() if not ln.startswith("time = "))
    protocol.write_text(text + "\n", encoding="utf-8")
    for path in (root / "data").glob("*.h5"):
        with h5py.File(path, "a") as fh:
            fh["data"].move("Time (s)", "clock (s)")
    return root


@pytest.fixture
def hdf5_timing_day(hdf5_timing_template, tmp_path) -> Path:
    """A copy of :func:`hdf5_timing_template` in ``tmp_path``: its protocol."""
    shutil.copytree(hdf5_timing_template, tmp_path, dirs_exist_ok=True)
    return tmp_path / "protocol.toml"


def _edit_h5(path: Path, edit) -> None:  # noqa: ANN001
    import h5py

    with h5py.File(path, "a") as fh:
        edit(fh["data"])


@pytest.mark.parametrize("value", ["200 Hz", "0.2 kHz", b"200", "200"])
def test_a_sample_rate_written_as_text_with_its_unit_is_read(tmp_path, hdf5_timing_day,
                                                            value):
    protocol = hdf5_timing_day

    def text_rate(group):  # noqa: ANN001, ANN202
        group.attrs["sample_rate"] = value

    _edit_h5(tmp_path / "data" / "run_021.h5", text_rate)
    assert _process(protocol) == 0
    assert _runs(protocol).loc[21, "fs_hz"] == pytest.approx(200.0)


def _set(key: str, value):  # noqa: ANN001, ANN202
    def edit(group):  # noqa: ANN001, ANN202
        del group.attrs["sample_rate"]
        group.attrs[key] = value
    return edit


def _soft_link_loop(group) -> None:  # noqa: ANN001
    import h5py

    group["a"] = h5py.SoftLink("/data/b")
    group["b"] = h5py.SoftLink("/data/a")


@pytest.mark.parametrize("edit, words", [
    (_set("fs", "fast"), "has no time column, and its sample rate attribute fs = 'fast' is "
                         "not a number, so the time cannot be built from it"),
    (_set("fs", "200 parsecs"), "its sample rate attribute fs = '200 parsecs' is in a unit "
                                "towtank does not know (it reads Hz, kHz"),
    (_set("fs", ""), "its sample rate attribute fs is empty"),
    (_set("fs", np.array([], dtype=float)), "its sample rate attribute fs is empty"),
    (_set("dt", 0.0), "its sample interval attribute dt = 0 is not a positive number"),
    (_set("dt", -0.005), "its sample interval attribute dt = -0.005 is not a positive number"),
    (_set("fs", np.nan), "its sample rate attribute fs = nan is not a positive number"),
    (_set("fs", np.array([200.0, 100.0])), "its sample rate attribute fs holds 2 different "
                                           "values"),
    (_soft_link_loop, "the link '/data/a' points back into itself (through '/data/b', a loop "
                      "of soft links)"),
], ids=["text", "unit", "empty-text", "empty-array", "dt-zero", "dt-negative", "nan",
        "two-values", "link-loop"])
def test_a_bad_sample_rate_attribute_or_a_link_loop_rejects_the_run_in_one_sentence(
        tmp_path, capsys, hdf5_timing_day, edit, words):
    protocol = hdf5_timing_day
    _edit_h5(tmp_path / "data" / "run_021.h5", edit)
    assert _process(protocol) == 1
    reason = _only_rejected(protocol, 21)
    assert words in reason, reason
    assert reason.startswith("run 21: run_021.h5")
    _one_sentence(reason)


def test_a_bad_rate_attribute_is_only_a_note_when_the_file_has_its_time(tmp_path):
    from towtank.ingest.runfile import load_run

    protocol = _day(tmp_path, file_format="hdf5")
    path = tmp_path / "data" / "run_021.h5"
    _edit_h5(path, _set("fs", "fast"))
    assert _process(protocol) == 0
    from towtank.ingest.protocol import load_protocol

    p = load_protocol(protocol)
    raw = load_run(path, p.channels, options=p.read)
    assert any("fs = 'fast' is not a number: ignored (the time column gives the time)" in n
               for n in raw.notes), raw.notes


def test_external_and_dangling_links_are_not_followed(tmp_path):
    """A link to another file is never opened (it could name any file on the machine); a
    soft link to nothing is left out."""
    import h5py

    from towtank.ingest.arrayfiles import read_hdf5_columns

    other = tmp_path / "secret.h5"
    with h5py.File(other, "w") as fh:
        fh["x"] = np.arange(50.0)
    path = tmp_path / "run.h5"
    with h5py.File(path, "w") as fh:
        fh["time"] = np.arange(50) / 100.0
        fh["drag"] = np.zeros(50)
        fh["stolen"] = h5py.ExternalLink(str(other), "/x")
        fh["nothing"] = h5py.SoftLink("/nowhere")
    cols, _ = read_hdf5_columns(path.read_bytes(), "run.h5")
    assert "stolen" not in cols and "nothing" not in cols
    assert {"time", "drag"} <= set(cols)


def test_inspect_says_why_a_stated_rate_is_not_used(tmp_path):
    import h5py

    from towtank.ingest.describe import describe_file

    path = tmp_path / "run.h5"
    with h5py.File(path, "w") as fh:
        fh["drag"] = np.zeros(50)
        fh["speed"] = np.zeros(50)
        fh.attrs["fs"] = "fast"
    desc = describe_file(path)
    assert desc.timing.startswith("none usable: its sample rate attribute fs = 'fast' is not a "
                                  "number; give [read] sample_rate_hz")
