"""Issue 33, "Trust, third round": what a newcomer met on a first day with towtank.

- Every ``towtank synth`` day (``--day`` × ``--format`` × ``--sheet``) is one ``process``
  reduces to the plain day's results: a hand-typed sheet keeps its layout's own columns
  (``Segment``, the steady window), and a fin day in a lab's layout gets the protocol sections
  that layout needs.
- Runs rejected for one fault whose sentences quote each file's own numbers are one line.
- A file without a speed channel names ``[processing] speed_source = "nominal"``.
- ``[tare] columns`` maps a lab's own tare table (``run,tow_speed,tare_drag``).
- ``towtank inspect`` without a protocol keeps volts as raw volts, and reads the time's unit
  from the time column's name (``Time (ms)``, ``t [s]``, ``time_us``).
"""

from __future__ import annotations

import argparse
import contextlib
import io
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from test_daywide import rejections_of

import towtank
from towtank.analysis.daywide import group_rejections
from towtank.commands.cli import _parser, main
from towtank.commands.inspect import inspect_run
from towtank.errors import ProtocolError, RunError
from towtank.ingest.describe import describe_file
from towtank.ingest.protocol_types import ChannelMap
from towtank.ingest.runfile import load_run
from towtank.testing import synthetic as syn
from towtank.testing.agreement import layout_gaps

REPO = Path(__file__).resolve().parents[1]
REAL = Path(__file__).resolve().parents[2] / "shared" / "real"


def _synth_choices() -> dict[str, tuple[str, ...]]:
    """--day, --format and --sheet as `towtank synth` offers them."""
    action = next(a for a in _parser()._actions if isinstance(a, argparse._SubParsersAction))
    synth = action.choices["synth"]
    return {a.dest: tuple(a.choices) for a in synth._actions if a.choices}


CHOICES = _synth_choices()
DAYS = tuple(d for d in CHOICES["day"] if d != "samples")  # samples: the shipped days
#: The combinations a newcomer found broken, and one day of each kind in a lab's layout.
FAST = (("hull", "lvm-appended", "hand-csv"), ("hull", "lvm-appended", "hand-xlsx"),
        ("hull", "no-speed", "hand-csv"), ("fin", "two-cell", "csv"),
        ("fin", "speed-log", "hand-xlsx"), ("air", "zero-file", "hand-csv"))
MATRIX = [(d, f, s) for d in DAYS for f in CHOICES["file_format"] for s in CHOICES["sheet_format"]]


def _synth_day(root: Path, day: str, layout: str, sheet: str) -> towtank.DayResult:
    """`towtank synth` the day into ``root`` and process it (no report)."""
    with contextlib.redirect_stdout(io.StringIO()):
        code = main(["synth", str(root), "--day", day, "--format", layout, "--sheet", sheet])
    assert code == 0, (day, layout, sheet)
    return towtank.process_day(root / "protocol.toml", jobs=1, report=False)


@pytest.fixture(scope="session")
def plain_days(tmp_path_factory):
    """The plain day of each kind (CSV run files, CSV sheet), made when first needed."""
    made: dict[str, towtank.DayResult] = {}

    def get(day: str) -> towtank.DayResult:
        if day not in made:
            made[day] = _synth_day(tmp_path_factory.mktemp(f"plain_{day}"), day, "csv", "csv")
        return made[day]
    return get


def _check_matrix(plain_days, tmp_path, day: str, layout: str, sheet: str) -> None:
    got, ref = _synth_day(tmp_path / "day", day, layout, sheet), plain_days(day)
    assert not got.rejected, got.rejected
    assert list(got.runs["status"]) == list(ref.runs["status"])
    fins = day == "fin"
    gaps = layout_gaps(layout, got.table("fins") if fins else got.coefficients,
                       ref.table("fins") if fins else ref.coefficients, fins=fins)
    assert gaps and max(gaps.values()) <= 1.0, {k: v for k, v in gaps.items() if v > 1.0}


@pytest.mark.heavy
@pytest.mark.parametrize(("day", "layout", "sheet"), FAST, ids=["-".join(c) for c in FAST])
def test_synth_days_in_a_lab_layout_give_the_plain_days_results(plain_days, tmp_path, day,
                                                                 layout, sheet):
    _check_matrix(plain_days, tmp_path, day, layout, sheet)


@pytest.mark.slow
@pytest.mark.parametrize(("day", "layout", "sheet"), [c for c in MATRIX if c not in FAST],
                         ids=["-".join(c) for c in MATRIX if c not in FAST])
def test_every_synth_day_gives_the_plain_days_results(plain_days, tmp_path, day, layout,
                                                      sheet):
    """The whole matrix (3 days × 17 layouts × 4 sheets, about 1.5 s each)."""
    _check_matrix(plain_days, tmp_path, day, layout, sheet)


def test_a_fault_quoting_each_files_numbers_is_one_line(tmp_path, capsys):
    """A lab's sheet without the `segment` column on a day of appended LVM files: every run is
    rejected, each with its own counts and times; the terminal says it once, runs.csv keeps
    each run's sentence."""
    with contextlib.redirect_stdout(io.StringIO()):
        assert main(["synth", str(tmp_path), "--format", "lvm-appended", "--sheet", "csv"]) == 0
    sheet = pd.read_csv(tmp_path / "run_sheet.csv")
    sheet.drop(columns="segment").to_csv(tmp_path / "run_sheet.csv", index=False)
    assert main(["process", str(tmp_path / "protocol.toml"), "--no-report", "--no-cache"]) == 1
    out = capsys.readouterr().out
    lines = [ln for ln in out.splitlines() if ln.startswith("  rejected:")]
    assert len(lines) == 1, out
    assert "every run that is not void (runs 1–19, 21–42)" in lines[0]
    assert "run_001.lvm holds 2 segments" in lines[0]
    runs = pd.read_csv(tmp_path / "out" / "runs.csv")
    reasons = runs.loc[runs["status"] == "rejected", "reason"]
    assert len(reasons) == 41 and reasons.nunique() > 1  # each run's own numbers
    assert reasons.str.contains("holds 2 segments").all()


def test_numbers_do_not_split_a_fault_but_other_words_do():
    rows = [{"run": r, "file": f"run_{r:03d}.lvm", "status": "rejected",
             "reason": f"run {r}: run_{r:03d}.lvm holds 2 segments: rows 424–{3000 + 7 * r}, "
                       f"{2577 + 7 * r} samples, {12.9 + 0.035 * r:.4g} s"} for r in range(1, 7)]
    rows[5]["reason"] = "run 6: run_006.lvm: the channel 'Fx1' is missing"
    runs = pd.DataFrame(rows)
    groups = group_rejections(runs, rejections_of(runs))
    assert [g.runs for g in groups] == [[1, 2, 3, 4, 5], [6]]
    assert groups[0].day_wide and "runs 1–5" in groups[0].sentence
    assert "shown for run_001.lvm" in groups[0].sentence and "rows 424–3007" in \
        groups[0].sentence  # the first run's own sentence


def _run_file(path: Path, columns: dict[str, np.ndarray]) -> Path:
    pd.DataFrame(columns).to_csv(path, index=False)
    return path


def _tow(fs: float = 200.0, duration_s: float = 20.0
         ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A tow at 1 m/s: time [s], speed [m/s] and a drag of 0.05 U² [V or N]; at rest for
    2 s, steady from 4 s to 4 s before the end."""
    t = np.arange(0.0, duration_s, 1.0 / fs)
    u = np.clip(np.minimum(t - 2.0, duration_s - 4.0 - t) * 0.5, 0.0, 1.0)
    noise = 1e-3 * np.random.default_rng(1).standard_normal(t.size)
    return t, u, 0.05 * u**2 + noise


def test_a_file_without_speed_names_the_nominal_speed_source(tmp_path):
    t, _, drag = _tow()
    path = _run_file(tmp_path / "run_001.csv", {"time": t, "drag": drag})
    with pytest.raises(RunError) as err:
        load_run(path, {})
    assert "the speed channel is missing" in err.value.reason
    assert '[processing] speed_source = "nominal"' in err.value.reason


def _tare_protocol(root: Path, extra: str) -> Path:
    """A protocol of the day in ``root`` (:func:`tare_day`) with a [tare] table section."""
    sections = syn.hull_protocol_sections(".", "out", sheet_format="csv")
    path = syn.write_protocol(root / "p.toml", **sections)
    path.write_text(path.read_text() + '\n[tare]\nsource = "table"\n' + extra)
    return path


@pytest.fixture(scope="session")
def tare_day(tmp_path_factory):
    """A hull day (written once for the module's tests) and two tare tables beside it."""
    root = tmp_path_factory.mktemp("tare")
    syn.make_hull_day(root, seed=3, file_format="csv", sheet_format="csv")
    u = [0.2, 0.8, 1.4, 2.0]
    d = [0.01 * x * x + 0.002 * x for x in u]
    (root / "tare.csv").write_text("speed_m_s,drag_N\n" + "".join(
        f"{a},{b}\n" for a, b in zip(u, d, strict=True)))
    (root / "lab_tare.csv").write_text("run,tow_speed,tare_drag\n" + "".join(
        f"{i},{a},{b}\n" for i, (a, b) in enumerate(zip(u, d, strict=True), 1)))
    return root


def test_a_labs_tare_table_is_read_through_its_column_mapping(tare_day):
    plain = towtank.load_protocol(_tare_protocol(tare_day, 'table = "tare.csv"\n')).tare
    lab = towtank.load_protocol(_tare_protocol(
        tare_day, 'table = "lab_tare.csv"\ncolumns = { speed_m_s = "tow_speed", '
                  'drag_N = "Tare_Drag" }\n')).tare
    assert lab.speeds_m_s == plain.speeds_m_s and lab.drag_N == plain.drag_N
    assert lab.lift_N == ()


@pytest.mark.parametrize(("extra", "message"), [
    ('table = "lab_tare.csv"\n',
     r"needs the columns 'speed_m_s' and 'drag_N'.*it has run, tow_speed, tare_drag.*"
     r"\[tare\] columns = \{ speed_m_s"),
    ('table = "lab_tare.csv"\ncolumns = { speed_m_s = "speed", drag_N = "tare_drag" }\n',
     r"needs the columns 'speed' \(speed_m_s in \[tare\] columns\) and 'tare_drag'"),
    ('table = "lab_tare.csv"\ncolumns = { speed = "tow_speed" }\n',
     r"unknown key 'speed' in \[tare.columns\]; did you mean 'speed_m_s'\?"),
    ('table = "lab_tare.csv"\ncolumns = { speed_m_s = "tow_speed", drag_N = "tow_speed" }\n',
     "maps one column of the tare table twice"),
])
def test_a_tare_table_mapping_that_does_not_fit_stops_the_day(tare_day, extra, message):
    with pytest.raises(ProtocolError, match=message):
        towtank.load_protocol(_tare_protocol(tare_day, extra))


@pytest.mark.skipif(not (REAL / "unh_rm2" / "Tare-drag.csv").is_file(),
                    reason="../shared/real/unh_rm2 is not present (real recordings are not kept "
                    "in the repository)")
def test_a_real_labs_tare_table_is_read_as_it_is(tare_day):
    """UNH's RM2 tare table (run,tow_speed,tare_drag: 12 speeds 0.2-1.3 m/s), as the lab
    keeps it."""
    table = (REAL / "unh_rm2" / "Tare-drag.csv").resolve()
    tare = towtank.load_protocol(_tare_protocol(
        tare_day, f'table = "{table}"\ncolumns = {{ speed_m_s = "tow_speed", drag_N = '
                  '"tare_drag" }\n')).tare
    ref = pd.read_csv(table)
    assert tare.speeds_m_s == tuple(ref["tow_speed"]) and len(tare.speeds_m_s) == 12
    assert tare.drag_N == tuple(ref["tare_drag"])


def test_tare_columns_need_a_table(tare_day):
    path = _tare_protocol(tare_day, "")
    path.write_text(path.read_text().replace('source = "table"',
                                             'source = "sting"\ncolumns = { drag_N = "x" }'))
    with pytest.raises(ProtocolError, match=r"'columns' in \[tare\] needs source = \"table\""):
        towtank.load_protocol(path)


def _inspect(path: Path, tmp_path: Path) -> tuple[int, str]:
    out, err = io.StringIO(), io.StringIO()
    code = inspect_run(path, png=tmp_path / f"{path.stem}.png", out=out, err=err)
    return code, out.getvalue() + err.getvalue()


def test_inspect_without_a_protocol_keeps_volts_raw_and_the_time_in_ms(tmp_path):
    t, u, drag = _tow()
    path = _run_file(tmp_path / "ms.csv", {"Time (ms)": t * 1e3, "Carriage speed (m/s)": u,
                                          "Fx (V)": drag})
    code, text = _inspect(path, tmp_path)
    assert code == 0, text
    assert "timing: time column 'Time (ms)' (200 Hz)" in text
    units = next(ln for ln in text.splitlines() if ln.startswith("units:"))
    assert "from the protocol" not in units and "drag V (raw" in units
    assert "4000 samples at 200 Hz" in text
    assert "drag    0.05" in text and " V   (s.d." in text


@pytest.mark.parametrize("name", ["time_us", "t [s]", "Time_ms", "t (min)"])
def test_inspect_reads_the_time_unit_in_a_column_name(tmp_path, name):
    t, u, drag = _tow()
    scale = {"time_us": 1e6, "t [s]": 1.0, "Time_ms": 1e3, "t (min)": 1 / 60}[name]
    path = _run_file(tmp_path / "run.csv", {name: t * scale, "speed": u, "drag": drag})
    code, text = _inspect(path, tmp_path)
    assert code == 0, text
    assert "at 200 Hz" in text and "steady means" in text


@pytest.mark.skipif(not (REAL / "fdfit" / "TDMSSample.tdms").is_file(),
                    reason="../shared/real/fdfit is not present (real recordings are not kept "
                    "in the repository)")
def test_a_real_time_column_in_ms_gives_its_rate():
    """FDFIT's LabVIEW TDMS sample: an explicit 'Time (ms)' channel at 20 ms (0.05 Hz when
    its unit is ignored)."""
    desc = describe_file(REAL / "fdfit" / "TDMSSample.tdms")
    assert desc.time_column == "Time (ms)" and desc.fs == pytest.approx(50.0)
    assert "(50 Hz)" in desc.timing


@settings(max_examples=25)
@given(unit=st.sampled_from([("s", 1.0), ("ms", 1e-3), ("us", 1e-6), ("min", 60.0)]),
       style=st.sampled_from(["{base} ({u})", "{base} [{u}]", "{base}_{u}", "{base} {u}"]),
       base=st.sampled_from(["time", "Time", "t", "Zeit"]),
       fs=st.sampled_from([50.0, 200.0, 1000.0]))
def test_the_time_is_read_in_seconds_whatever_unit_its_name_gives(tmp_path_factory, unit,
                                                                   style, base, fs):
    u_name, factor = unit
    name = style.format(base=base, u=u_name)
    t, u, drag = _tow(fs, duration_s=10.0)  # the time's unit, not the tow, is read here
    path = _run_file(tmp_path_factory.mktemp("unit") / "run.csv",
                     {name: t / factor, "speed": u, "drag": drag})
    raw = load_run(path, {"time": ChannelMap(column=name)})
    np.testing.assert_allclose(raw.time, t, rtol=1e-9, atol=1e-9)
    assert math.isclose(raw.fs, fs, rel_tol=1e-6)


def test_no_stray_image_at_the_repository_root():
    assert not sorted(p.name for p in REPO.glob("*.png"))
