"""Tests of the report stage: report.xlsx, report.pdf and figures/*.png.

A synthetic hull day (with one run damaged, so one is rejected beside the voided one) and a
synthetic fin day are generated once per session (per xdist worker), processed by the pipeline
and written by :func:`towtank.report.write_outputs`; the tests read the files back.
"""

from __future__ import annotations

import copy
import functools
import math
import os
import re
from dataclasses import replace
from pathlib import Path

import numpy as np
import openpyxl
import pandas as pd
import pytest
from conftest import built_once
from hypothesis import given, settings
from hypothesis import strategies as st
from pypdf import PdfReader

from towtank.pipeline import process_day
from towtank.report import (
    figure_base,
    figures,
    pdf,
    provenance,
    quality,
    style,
    workbook,
    write_outputs,
)
from towtank.testing import synthetic

REPORT_DATE = "2024-05-21"
NUMERIC = re.compile(r"^[+-]?\d+(\.\d*)?([eE][+-]?\d+)?$")
DAMAGED_RUN = 33  # a repeat run at 0 deg, 1.2 m/s: the day stays complete without it


@pytest.fixture(scope="session")
def days(tmp_path_factory: pytest.TempPathFactory) -> dict[str, tuple]:
    """(DayResult, output folder) of the hull and the fin day, written once per test run
    (:func:`conftest.built_once`: shared by the xdist workers; the tests only read them)."""
    value, _ = built_once(tmp_path_factory, "test_report_days", _write_days)
    return value


def page_texts(path: Path) -> tuple[str, ...]:
    """The text of each page of the PDF ``path`` (pypdf's), read once per version of the file
    (the days' reports are read by several tests)."""
    st = path.stat()
    return _page_texts(path, st.st_size, st.st_mtime_ns)


@functools.lru_cache(maxsize=8)
def _page_texts(path: Path, size: int, mtime_ns: int) -> tuple[str, ...]:
    return tuple(page.extract_text() for page in PdfReader(path).pages)


def _write_days(root: Path) -> dict[str, tuple]:
    out = {}
    hull = root / "hull"
    synthetic.make_hull_day(hull, seed=3)
    synthetic.write_protocol(hull / "p.toml", **synthetic.hull_protocol_sections(".", "out"))
    damaged = hull / "data" / f"run_{DAMAGED_RUN:03d}.csv.gz"
    damaged.write_bytes(damaged.read_bytes()[:300])  # truncated gzip: rejected with a reason
    fin = root / "fin"
    synthetic.make_fin_day(fin, seed=4)
    synthetic.write_protocol(fin / "p.toml", **synthetic.fin_protocol_sections(".", "out"))
    processed = {name: (folder, replace(process_day(folder / "p.toml", jobs=1), report_date=date))
                 for name, folder, date in (("hull", hull, REPORT_DATE), ("fin", fin, None))}
    with pytest.MonkeyPatch.context() as mp:
        _forbid_fitting(mp)  # test_report_stage_does_not_refit: the writers fit nothing
        for name, (folder, day) in processed.items():
            # the fin day with two jobs: its writers and PDF page groups drawn beside this
            # process, the report test_one_job_draws_the_same_pdf_in_this_process compares
            out[name] = (day, write_outputs(day, folder / "out", jobs=2 if name == "fin" else 1))
    return out


def _forbid_fitting(mp: pytest.MonkeyPatch) -> None:
    """Replace every fitting function the report could call by one that fails the test."""
    import statsmodels.api as sm

    from towtank.analysis import fins, similarity
    from towtank.analysis import hull as fit

    def boom(*args, **kwargs):
        raise AssertionError("the report stage must not fit anything")

    for mod, name in ((fit, "fit_cd_alpha"), (fit, "joint_regression"), (fit, "fit_hull"),
                      (fit, "curve_difference"), (fit, "fit_added_mass"), (sm, "OLS"),
                      (sm, "WLS"), (np, "polyfit"), (np.linalg, "lstsq"),
                      (fins, "fin_curves"), (fins, "fin_table"), (similarity, "form_factor"),
                      (similarity, "scaling_table")):
        mp.setattr(mod, name, boom)


def _header_map(ws) -> dict[str, int]:
    """Column index (1-based) of each header of row 1, by its name without the unit."""
    return {str(c.value).split(" [")[0]: c.column for c in ws[1] if c.value is not None}


def _same(a, b) -> bool:
    missing = (a is None or (isinstance(a, float) and math.isnan(a)))
    other_missing = (b is None or (isinstance(b, float) and math.isnan(b)))
    if missing or other_missing:
        return missing and other_missing
    return a == b


# ----------------------------------------------------------------------------- the workbook
@pytest.mark.heavy
@pytest.mark.parametrize("name", ["hull", "fin"])
def test_workbook_has_every_sheet_frozen_and_filtered(days, name):
    _, out = days[name]
    wb = openpyxl.load_workbook(out / "report.xlsx")
    day, _ = days[name]
    assert wb.sheetnames == workbook.sheet_names(day)
    expected = {"hull": ["Summary", "Coefficients", "Runs", "Tare", "Fins", "Scaling",
                         "Scaling constants", "Form factor", "Quality", "Provenance"],
                "fin": ["Summary", "Coefficients", "Runs", "Tare", "Fins", "Fin curves",
                        "Fin control", "Scaling", "Quality", "Provenance"]}[name]
    assert wb.sheetnames == expected  # one table per sheet (issue 16)
    for ws in wb.worksheets:
        assert ws.freeze_panes == "A2", ws.title
        assert ws.auto_filter.ref and ws.auto_filter.ref.startswith("A1:"), ws.title
        assert ws["A1"].font.bold, ws.title


@pytest.mark.heavy
def test_workbook_coefficients_equal_the_csv_exactly(days):
    day, out = days["hull"]
    csv = pd.read_csv(out / "coefficients.csv")
    assert csv["value"].tolist() == day.hull.coefficients["value"].tolist()
    ws = openpyxl.load_workbook(out / "report.xlsx")["Coefficients"]
    cols = _header_map(ws)
    assert ws.cell(1, cols["value"]).value == "value [SI]"
    numeric = [c for c in csv.columns if pd.api.types.is_numeric_dtype(csv[c])]
    assert {"value", "ci_low", "ci_high", "prime", "diff_pct", "prototype_value"} <= set(numeric)
    for i, rec in enumerate(csv.to_dict("records"), start=2):
        assert ws.cell(i, cols["symbol"]).value == rec["symbol"]
        for c in numeric:
            cell = ws.cell(i, cols[c]).value
            assert _same(cell, rec[c]), (rec["symbol"], c, cell, rec[c])
            if cell is not None:
                assert isinstance(cell, int | float) and not isinstance(cell, bool)
    # shown with four significant digits or more, whatever their size
    x_udot = ws.cell(2, cols["value"])
    assert x_udot.number_format == "0.000E+00"  # −0.0172: scientific below 0.1 in size
    assert ws.cell(2, cols["prime"]).number_format == "0.000E+00"
    # one format per column (issue 16): Y_vdot's −0.68 as −6.807E-01 beside X_udot's
    # −1.711E-02, never 0.6807 in one row and 1.711E-02 in the next
    y_vdot = next(r for r in range(2, ws.max_row + 1) if ws.cell(r, 1).value == "Y_vdot")
    assert ws.cell(y_vdot, cols["value"]).number_format == "0.000E+00"
    for c in numeric:
        formats = {ws.cell(r, cols[c]).number_format for r in range(2, len(csv) + 2)
                   if ws.cell(r, cols[c]).value is not None}
        assert len(formats) <= 1, (c, formats)
    assert workbook.column_format([0, 5.0, 2]) == "0"  # angles, sample counts
    assert workbook.column_format([0.2, 1.5, 0.0]) == "0.0000"
    assert workbook.display_format(2.67e5) == "0.000E+00" and workbook.display_format(0) == (
        "General")
    # the key results of the Summary sheet are the same floats too
    summary = openpyxl.load_workbook(out / "report.xlsx")["Summary"]
    rows = list(summary.iter_rows(values_only=True))
    head = next(i for i, r in enumerate(rows) if r[0] == "symbol")
    idx = {str(v).split(" [")[0]: j for j, v in enumerate(rows[head]) if v}
    for rec, row in zip(csv.to_dict("records"), rows[head + 1:], strict=False):
        assert row[0] == rec["symbol"]
        assert _same(row[idx["value"]], rec["value"])


@pytest.mark.heavy
@pytest.mark.parametrize("name", ["hull", "fin"])
def test_workbook_numbers_are_numbers(days, name):
    day, out = days[name]
    wb = openpyxl.load_workbook(out / "report.xlsx")
    for ws in wb.worksheets:
        for row in ws.iter_rows():
            for cell in row:
                if isinstance(cell.value, str):
                    assert not NUMERIC.match(cell.value.strip()), (ws.title, cell.coordinate)
    runs = wb["Runs"]
    cols = _header_map(runs)
    assert runs.cell(1, cols["speed_mean"]).value == "speed_mean [m/s]"
    ok = [r for r in runs.iter_rows(min_row=2, values_only=True) if r[cols["status"] - 1] == "ok"]
    assert len(ok) == int((day.runs["status"] == "ok").sum())
    for r in ok:
        assert isinstance(r[cols["speed_mean"] - 1], float)
        assert isinstance(r[cols["run"] - 1], int)


@pytest.mark.heavy
def test_workbook_highlights_rejected_and_void_runs(days):
    day, out = days["hull"]
    ws = openpyxl.load_workbook(out / "report.xlsx")["Runs"]
    cols = _header_map(ws)
    fills = {}
    for row in ws.iter_rows(min_row=2, max_row=1 + len(day.runs)):
        status = row[cols["status"] - 1].value
        fills.setdefault(status, set()).add(row[0].fill.fgColor.rgb[-6:])
    assert fills["rejected"] == {style.XL_REJECTED_FILL}
    assert fills["void"] == {style.XL_VOID_FILL}
    assert style.XL_REJECTED_FILL not in fills["ok"]
    quality = openpyxl.load_workbook(out / "report.xlsx")["Quality"]
    text = " ".join(str(c.value) for row in quality.iter_rows() for c in row if c.value)
    assert f"run {DAMAGED_RUN}" in text and "carriage stopped early" in text


@pytest.mark.heavy
def test_workbook_highlights_large_differences(days, tmp_path):
    day, _ = days["hull"]
    hull = copy.copy(day.hull)
    coef = day.hull.coefficients.copy()
    coef.loc[0, "diff_pct"] = 12.5
    coef.loc[1, "diff_pct"] = -9.0
    changed = replace(day, hull=replace(hull, coefficients=coef))
    ws = openpyxl.load_workbook(workbook.write_workbook(changed, tmp_path))["Coefficients"]
    assert ws["A2"].fill.fgColor.rgb[-6:] == style.XL_DIFF_FILL
    assert ws["A3"].fill.fgColor.rgb[-6:] != style.XL_DIFF_FILL


@pytest.mark.heavy
def test_fin_day_workbook_notes_why_sheets_are_empty(days):
    _, out = days["fin"]
    wb = openpyxl.load_workbook(out / "report.xlsx")
    assert wb["Coefficients"]["A1"].value == "note"
    assert "No hull coefficients" in wb["Coefficients"]["A2"].value
    assert "No scaling" in wb["Scaling"]["A2"].value
    fins = wb["Fins"]
    assert _header_map(fins)["cl_sandia"] > 0
    assert fins.max_row > 30  # the runs, then the per-speed curves below


@pytest.mark.heavy
def test_workbook_provenance_lists_inputs_with_sha256(days):
    day, out = days["hull"]
    ws = openpyxl.load_workbook(out / "report.xlsx")["Provenance"]
    values = [c.value for row in ws.iter_rows() for c in row if c.value is not None]
    for path, sha in day.inputs.items():
        assert path in values and sha in values


# ------------------------------------------------------------------------------------ PDF
def _expected_pages(day) -> int:
    n_figs = len(figures.available_figures(day))
    n_quality = len(quality.paginate(quality.quality_flow(day), quality.QUALITY_HEIGHT_IN))
    n_runs = math.ceil(len(day.runs) / pdf.RUNS_PER_PAGE)
    if day.fins is not None and not pdf.fin_runs_fit(day.fins):
        n_runs += math.ceil(len(day.fins.table) / pdf.RUNS_PER_PAGE)
    n_figs += len(pdf.vehicle_pages(day))  # with a [vehicle]: measured beside predicted
    return 2 + n_figs + n_runs + n_quality + math.ceil(len(day.runs) / pdf.THUMBS_PER_PAGE)


@pytest.mark.heavy
def test_hull_pdf_pages_and_sections(days):
    day, out = days["hull"]
    text = page_texts(out / "report.pdf")
    assert len(text) == _expected_pages(day)
    # title, summary, tare, added mass, damping, scaling, the runs' table, quality, 42 runs on
    # 4 appendix pages
    assert len(text) == 12
    for section in ("Summary", "Tare", "Added mass", "Damping", "Scaling", "Runs", "Quality",
                    "Appendix"):
        assert any(section in t for t in text[1:]), section
    assert "Fins" not in " ".join(text)
    assert REPORT_DATE in text[0]
    assert "X_udot" in text[1] or "−0.01" in text[1]
    all_text = " ".join(text)
    assert f"run {DAMAGED_RUN}" in all_text and "rejected" in all_text


@pytest.mark.heavy
def test_fin_pdf_has_no_hull_pages(days):
    day, out = days["fin"]
    pages = page_texts(out / "report.pdf")
    assert len(pages) == _expected_pages(day)
    # title, summary, the fin post's tare, two fin pages, the fin runs, the runs' table,
    # quality, thumbnails
    assert len(pages) == 2 + 1 + 2 + 1 + 1 + 1 + math.ceil(len(day.runs) / 12)
    text = " ".join(pages)
    assert "Fins" in text and "Quality" in text
    assert "Added mass" not in text and "Damping" not in text
    assert "not given" in pages[0]


@pytest.mark.heavy
def test_pdf_metadata(days):
    """The metadata; that the same day gives the same bytes is checked on both sample days by
    tests/test_one_front_door.py (three writes of each compared byte for byte)."""
    day, out = days["hull"]
    meta = PdfReader(out / "report.pdf").metadata
    assert meta["/Author"] == "towtank"
    assert day.protocol.name in meta["/Title"]
    assert meta["/CreationDate"].startswith("D:20240521")
    fin_meta = PdfReader(days["fin"][1] / "report.pdf").metadata
    assert "/CreationDate" not in fin_meta  # no date known: none invented


@settings(max_examples=60, deadline=None)
@given(kinds=st.lists(st.sampled_from(["title", "summary", "figure", "quality", "thumbs"]),
                      min_size=1, max_size=60),
       parts=st.integers(1, 8))
def test_pages_split_into_contiguous_groups(kinds, parts):
    plan = [pdf.Page(k, "s", list(range(12)) if k == "thumbs" else None) for k in kinds]
    groups = pdf.split_pages(plan, parts)
    assert len(groups) == min(parts, len(plan))
    assert [i for g in groups for i in g] == list(range(len(plan)))
    assert all(groups)


@pytest.mark.heavy
def test_pdf_in_one_part_has_the_same_pages(days, tmp_path):
    day, out = days["fin"]  # the shorter day: its pages are drawn in four parts as well
    one = pdf.write_pdf(day, tmp_path, parts=1)
    assert page_texts(one) == page_texts(out / "report.pdf")
    assert PdfReader(one).metadata == PdfReader(out / "report.pdf").metadata
    assert not list(tmp_path.glob(".report-part-*"))


@pytest.mark.heavy
def test_one_job_draws_the_same_pdf_in_this_process(days, tmp_path, monkeypatch):
    """``jobs=1``: every page group drawn here, one after another, and the same bytes as the
    groups drawn in processes beside this one (the fixture's report). That the forked
    processes draw the layouts this process made with their own font objects is
    tests/test_report_mathcache.py's."""
    day, out = days["fin"]
    drawn_by = tmp_path / "pids"
    real = pdf._write_part

    def noting(*args):  # noqa: ANN002, ANN202
        with open(drawn_by, "a") as fh:
            fh.write(f"{os.getpid()}\n")
        return real(*args)

    monkeypatch.setattr(pdf, "_write_part", noting)
    here = pdf.write_pdf(day, tmp_path, beside=False)
    assert drawn_by.read_text().split() == [str(os.getpid())] * min(
        pdf.PDF_PARTS, len(pdf.page_plan(day)))
    assert here.read_bytes() == (out / "report.pdf").read_bytes()
    assert not list(tmp_path.glob(".report-part-*"))


@pytest.mark.heavy
def test_report_date_order(days):
    day, _ = days["fin"]
    assert provenance.report_date(day) == (None, "not given")
    dated = replace(day, report_date="2023-01-02")
    assert provenance.report_date(dated)[0] == "2023-01-02"
    sheet = day.sheet.copy()
    sheet["date"] = ["2022-03-04"] * (len(sheet) - 1) + ["2022-03-05"]
    assert provenance.report_date(replace(day, sheet=sheet))[0] == "2022-03-05"


# -------------------------------------------------------------------------------- figures
@pytest.mark.heavy
def test_figures_written(days):
    for name, expected in (("hull", {"tare", "added_mass", "damping", "scaling"}),
                           ("fin", {"tare", "fin_forces", "fin_coefficients"})):
        _, out = days[name]
        pngs = {p.stem: p for p in (out / "figures").glob("*.png")}
        assert set(pngs) == expected
        for p in pngs.values():
            assert p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.heavy
def test_damping_figure_draws_the_stored_fit(days):
    day, _ = days["hull"]
    dm = day.hull.fit.damping
    fig = figures.fig_damping(day.hull)
    ax = fig.axes[0]
    line = next(ln for ln in ax.get_lines() if ln.get_label().startswith("fit"))
    a = np.radians(line.get_xdata())
    np.testing.assert_allclose(line.get_ydata(), dm.params @ np.vstack([a * a, a, 1 + 0 * a]))
    # change the stored parameters: the figure follows them (nothing is refitted)
    moved = copy.deepcopy(day)
    moved.hull.fit.damping.params = dm.params + np.array([0.0, 0.0, 0.01])
    line2 = next(ln for ln in figures.fig_damping(moved.hull).axes[0].get_lines()
                 if ln.get_label().startswith("fit"))
    np.testing.assert_allclose(line2.get_ydata(), line.get_ydata() + 0.01)


@pytest.mark.heavy
def test_report_stage_does_not_refit(days):
    """Both days' outputs are written (the ``days`` fixture) with every fitting function
    replaced by one that fails (:func:`_forbid_fitting`): the report and the workbook are
    written all the same."""
    for name in ("hull", "fin"):
        _, out = days[name]
        assert (out / "report.pdf").stat().st_size > 10_000
        assert (out / "report.xlsx").exists()


@pytest.mark.heavy
def test_run_thumbnail_shades_the_phases(days):
    from matplotlib.figure import Figure

    day, _ = days["hull"]
    red = day.reductions[13]
    fig = Figure()
    ax = fig.add_subplot()
    ax2 = figures.run_thumbnail(ax, red)
    spans = [p for p in ax2.patches]
    assert len(spans) == sum(w is not None for w in red.windows.values())
    assert len(ax.get_lines()) == 1 and len(ax2.get_lines()) == 2  # speed; drag and lift
    assert ax.get_xlabel() == "$t$ [s]"


def _write_a(day, folder):
    (Path(folder) / "a.txt").write_text("a")


def _write_b(day, folder):
    (Path(folder) / "b.txt").write_text(str(os.getpid()))


def _fail(day, folder):
    raise ValueError("no ink")


def _die(day, folder):
    os._exit(3)


@pytest.mark.heavy
def test_report_writers_run_beside_each_other(days, tmp_path):
    day, _ = days["hull"]
    out = write_outputs(day, tmp_path / "out", writers=[_write_a, _write_b], jobs=2)
    assert (out / "a.txt").read_text() == "a"
    assert (out / "b.txt").read_text() != str(os.getpid())  # written in a process of its own
    assert (out / "runs.csv").exists()


@pytest.mark.heavy
@pytest.mark.parametrize("bad, message", [(_fail, "_fail: ValueError: no ink"),
                                          (_die, "_die: the process running it stopped")])
def test_a_failing_report_writer_writes_nothing(days, tmp_path, bad, message):
    day, _ = days["hull"]
    out = tmp_path / "out"
    write_outputs(day, out, report=False)
    before = sorted(p.name for p in out.iterdir())
    with pytest.raises(RuntimeError, match=message):
        write_outputs(day, out, writers=[_write_a, bad], jobs=2)
    assert sorted(p.name for p in out.iterdir()) == before  # the previous outputs stand
    assert not (out / "a.txt").exists()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".out.tmp-")]


def test_math_symbol():
    assert figure_base.math_symbol("X_udot") == r"$X_{\dot u}$"
    assert figure_base.math_symbol("Y_v|v|") == "$Y_{v|v|}$"
    assert figure_base.sci(2.7e5) == "2.7×10⁵"
    assert Path(pdf.__file__).name == "pdf.py"


@pytest.mark.heavy
def test_the_runs_table_lists_every_run_with_its_status(days):
    """Issue 16: a per-run table in the PDF (run, config, test, α, U, a, drag, C_D, Re, tare,
    status), one row per run of the sheet."""
    day, out = days["hull"]
    text = next(t for t in page_texts(out / "report.pdf") if "Runs" in t and "tare [N]" in t)
    for r in day.runs.itertuples():
        assert str(int(r.run)) in text
    assert "rejected" in text and "status" in text


@pytest.mark.heavy
def test_runs_table_gives_each_run_its_test_area_coefficient(days):
    """Issue 22: one C_D per run on the area its test uses. The transverse tows (α = 90°) show
    C_D on the lateral area, the C_D,90 of the damping page (not ~6 on the frontal area), and
    runs.csv names the area of cd_ref."""
    day, out = days["hull"]
    runs = pd.read_csv(out / "runs.csv")
    hull = runs[(runs.config == "hull") & (runs.status == "ok")]
    side = hull[hull.angle_deg == 90]
    front = hull[hull.angle_deg != 90]
    assert len(side) >= 2 and len(front) >= 2
    assert (side.ref_area == "lateral").all() and (front.ref_area == "frontal").all()
    np.testing.assert_array_equal(side.cd_ref, side.cd_lateral)
    np.testing.assert_array_equal(front.cd_ref, front.cd)
    assert np.allclose(side.ref_area_m2, day.protocol.model.lateral_area)
    cd90 = day.hull.fit.damping.cd90
    assert np.allclose(side.cd_ref, cd90, rtol=0.01)
    assert (side.cd > 3 * cd90).all()  # the frontal-area value, which the table does not show
    assert runs.loc[runs.config == "sting", "cd_ref"].isna().all()
    text = next(t for t in page_texts(out / "report.pdf") if "tare [N]" in t)
    for v in side.cd_ref:
        assert f"{v:.4f}" in text
    for v in side.cd:
        assert f"{v:.4f}" not in text
    assert "lateral area" in text


@pytest.mark.heavy
def test_runs_table_says_why_an_acceleration_is_blank(days):
    """Issue 22: the usable runs without a mean acceleration (a ramp too short at low speed)
    are marked and explained under the table, in the PDF and the workbook."""
    from towtank.report.tables import missing_accel_note

    day, out = days["hull"]
    ok = day.runs[day.runs.status == "ok"]
    expected = [int(r) for r in ok.loc[ok.accel_mean.isna(), "run"]]
    assert expected, "the synthetic day has slow runs whose ramp is too short"
    blank, note = missing_accel_note(day.runs, day.protocol.processing,
                                     [int(r) for r in day.runs.run])
    assert blank == expected
    assert "no constant-acceleration stretch" in note and "U/a" in note
    text = next(t for t in page_texts(out / "report.pdf") if "tare [N]" in t)
    assert "no constant-acceleration stretch" in text
    ws = openpyxl.load_workbook(out / "report.xlsx")["Runs"]
    notes = [str(c.value) for row in ws.iter_rows() for c in row
             if isinstance(c.value, str) and c.value.startswith("accel_mean empty")]
    assert notes and "no constant-acceleration stretch" in notes[0]


@pytest.mark.heavy
def test_the_hull_lift_slope_says_it_is_a_check_and_what_it_would_give(days):
    """Issue 22: the measured hull lift slope is shown as a check, used in no coefficient, with
    the Y_uv it would give with the hull's lift, −½ρA·(∂C_L/∂α + c)."""
    from towtank.report.quality import lift_slope_text

    day, _ = days["hull"]
    hf = day.hull.fit
    text = lift_slope_text(hf, day.hull.coefficients)
    assert "used in no coefficient" in text and "drag's side component" in text
    dm = hf.damping
    expected = -0.5 * dm.rho * dm.area * (hf.lift_slope[0] + dm.params[2])
    assert f"{expected:.4g} kg/m" in text
    # with lift it is several times the measured Y_uv (the drag's side component alone)
    y_uv = float(day.hull.coefficients.set_index("symbol").loc["Y_uv", "value"])
    assert expected / y_uv > 5
    lines = " ".join(t for _, t in quality.quality_flow(day).items)
    assert text in lines


@pytest.mark.heavy
def test_the_reference_set_is_shown_by_its_name_not_its_key(days):
    """Issue 22: the reader sees "REMUS 100 (SUT-2 report, Table 4)", not the protocol key
    'remus', in the PDF, the workbook and provenance.json."""
    import json

    from towtank.reference.sets import reference_name

    day, out = days["hull"]
    assert day.protocol.campaign.reference == "remus"
    name = "REMUS 100 (SUT-2 report, Table 4)"
    assert reference_name("remus") == name
    assert reference_name("/lab/my_ref.csv") == "my_ref.csv (user reference CSV)"
    summary = page_texts(out / "report.pdf")[1]
    assert name in summary and "'remus'" not in summary
    ws = openpyxl.load_workbook(out / "report.xlsx")["Summary"]
    assert name in [c.value for row in ws.iter_rows() for c in row]
    prov = json.loads((out / "provenance.json").read_text(encoding="utf-8"))
    assert prov["settings"]["reference_name"] == name


@pytest.mark.heavy
def test_report_equations_are_written_out_with_their_source(days):
    """Issue 22: a PDF that cites "report eqs. 7–8" writes those equations out and names the
    report with its title, as README and docs/method.md do."""
    _, out = days["hull"]
    pages = list(page_texts(out / "report.pdf"))
    assert any("report eq" in t for t in pages[1:])
    title = " ".join(pages[0].split())
    name = "Identification of Underwater Vehicle Hydrodynamic Coefficients Using Model Tests"
    assert name in title
    for eq in ("Eqs. 7–8", "Eq. 13", "Eq. 14", "Eq. 15"):
        assert eq in title
    assert "page 1" in pages[1]  # the summary's footnotes point there
    root = Path(__file__).resolve().parents[1]
    for doc in ("README.md", "docs/method.md"):
        text = " ".join((root / doc).read_text(encoding="utf-8").split())
        assert name in text.replace("*", ""), doc
