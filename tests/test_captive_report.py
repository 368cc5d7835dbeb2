"""What users see of a captive day: the PDF's captive pages, the workbook's Captive and PMM
sheets, the run table, ``inspect``, ``watch`` and ``--export simman`` (issue #35 items 8, 9).

One generated captive day is processed once (module fixture) and every test reads it.
"""

from __future__ import annotations

import math
import shutil
import subprocess

import numpy as np
import pandas as pd
import pytest

from towtank.testing.captive import captive_day_plan, make_captive_day


@pytest.fixture(scope="module")
def captive_day(tmp_path_factory):
    """A generated horizontal captive day processed with its reports: (DayResult, out)."""
    from towtank.api import process_day

    folder = tmp_path_factory.mktemp("captive_day")
    make_captive_day(folder, seed=3)
    out = folder / "out"
    day = process_day(folder / "protocol.toml", out, jobs=2)
    return day, out


@pytest.fixture(scope="module")
def vertical_day(tmp_path_factory):
    """A small vertical-plane captive day (drift, arm and PMM runs), processed without files."""
    from towtank.api import process_day

    folder = tmp_path_factory.mktemp("captive_vertical")
    plan = [s for s in captive_day_plan() if s.test in ("drift", "arm", "sway", "yaw")]
    make_captive_day(folder, seed=4, plane="vertical", plan=plan)
    return process_day(folder / "protocol.toml", jobs=2)


# ------------------------------------------------------------------------------ the PDF
def test_pdf_has_a_captive_section_with_table_and_figure(captive_day):
    from towtank.report.pdf import page_plan

    day, _ = captive_day
    plan = page_plan(day)
    captive = [p for p in plan if p.section == "Captive"]
    assert [p.kind for p in captive] == ["captive", "figure"]
    assert captive[1].payload[0] == "captive"


def test_captive_pages_drawn_in_the_pdf(captive_day):
    from pypdf import PdfReader

    day, out = captive_day
    text = [p.extract_text() for p in PdfReader(out / "report.pdf").pages]
    table = next(t for t in text if "derivative" in t and "95 % interval" in t)
    assert "Reduced chi^2" in table
    assert "agree" in table  # the fit's agreement lines over omega'
    assert any("Static drift" in t and "Rotating arm" in t and "PMM run" in t for t in text)
    runs = next(t for t in text if "X or drag [N]" in t)
    y = float(day.runs.loc[day.runs["run"] == 1, "captive_Y_N"].iloc[0])
    assert f"{y:.4g}".replace("-", "\u2212") in runs


def test_drift_curve_goes_through_the_drift_runs(captive_day):
    from towtank.report.captive_figure import drift_curve, static_points

    day, _ = captive_day
    fit = day.captive
    pts = static_points(fit, ("drift",), 90.0)
    assert len(pts) == 9
    for eq, moment in (("Y", False), ("N", True)):
        mean, half = drift_curve(fit, pts["drift_deg"].to_numpy(float), 90.0, eq, moment,
                                 fit.runs[0])
        scale = np.max(np.abs(pts[eq]))
        assert np.all(np.abs(mean - pts[eq]) < 0.02 * scale)
        assert np.all(np.isfinite(half)) and np.all(half > 0)


def test_pmm_prediction_follows_the_cycle_averaged_loads(captive_day):
    from towtank.report.captive_figure import pmm_prediction, shown_pmm_run

    day, _ = captive_day
    fit = day.captive
    run = shown_pmm_run(fit)
    assert run is not None and run.cycles_used >= 3
    rows, pred = pmm_prediction(fit, run, 90.0)
    for eq in ("Y", "N"):
        measured = rows[eq].to_numpy(float)
        rms = math.sqrt(np.mean((pred[eq][0] - measured) ** 2))
        assert rms < 0.05 * np.max(np.abs(measured))


def test_vertical_day_gets_its_captive_page(vertical_day):
    from towtank.report.captive_figure import fig_captive
    from towtank.report.pdf import _draw_captive, _page, page_plan

    plan = page_plan(vertical_day)
    pages = [p for p in plan if p.section == "Captive, vertical plane"]
    assert [p.kind for p in pages] == ["captive", "figure"]
    fig = _page()
    _draw_captive(fig, vertical_day.captive_vertical)
    texts = " ".join(t.get_text() for t in fig.texts)
    assert "vertical plane (Z, M)" in texts
    assert fig_captive(vertical_day.captive_vertical, page=True) is not None


# -------------------------------------------------------------------------- the workbook
def test_workbook_has_captive_and_pmm_sheets(captive_day):
    from openpyxl import load_workbook

    day, out = captive_day
    wb = load_workbook(out / "report.xlsx")
    assert {"Captive", "PMM"} <= set(wb.sheetnames)
    ws = wb["Captive"]
    cells = {ws.cell(r, 1).value: ws.cell(r, 2).value for r in range(1, ws.max_row + 1)}
    coef = day.coefficients.set_index("symbol")
    assert cells["Y_uv"] == coef.at["Y_uv", "value"]
    assert cells["N_rdot"] == coef.at["N_rdot", "value"]
    pmm = wb["PMM"]
    assert pmm.cell(1, 1).value == "run"
    runs = [pmm.cell(r, 1).value for r in range(2, pmm.max_row + 1)]
    assert [r for r in runs if isinstance(r, int)] == day.pmm["run"].tolist()
    for sheet in ("Captive", "PMM"):
        for row in wb[sheet].iter_rows():
            assert all(c.data_type != "f" for c in row)


def test_captive_sheet_text_is_never_a_formula(captive_day, tmp_path):
    from dataclasses import replace

    from openpyxl import load_workbook

    from towtank.report.workbook import write_workbook

    day, _ = captive_day
    evil = replace(day.captive, notes=("=HYPERLINK(\"http://x\",\"y\")", "+1+2"))
    write_workbook(replace(day, captive=evil), tmp_path)
    ws = load_workbook(tmp_path / "report.xlsx")["Captive"]
    values = [c for row in ws.iter_rows() for c in row if c.value is not None]
    texts = {c.value: c.data_type for c in values}
    assert texts["=HYPERLINK(\"http://x\",\"y\")"] == "s"
    assert texts["+1+2"] == "s"


@pytest.mark.skipif(shutil.which("soffice") is None, reason="LibreOffice not installed")
def test_libreoffice_opens_the_captive_workbook(captive_day, tmp_path):
    day, out = captive_day
    book = tmp_path / "report.xlsx"
    shutil.copy(out / "report.xlsx", book)
    every_sheet = "csv:Text - txt - csv (StarCalc):44,34,76,1,,0,false,true,false,false,false,-1"
    subprocess.run(["soffice", "--headless", f"-env:UserInstallation=file://{tmp_path}/lo",
                    "--convert-to", every_sheet, "--outdir", str(tmp_path), str(book)],
                   check=True, capture_output=True, timeout=180)
    captive = pd.read_csv(tmp_path / "report-Captive.csv", skiprows=1)
    got = captive.dropna(subset=["value [SI]"]).set_index("symbol")["value [SI]"]
    coef = day.coefficients.set_index("symbol")["value"]
    assert got.loc["Y_uv"] == pytest.approx(coef.loc["Y_uv"], rel=1e-12)
    pmm = pd.read_csv(tmp_path / "report-PMM.csv")
    runs = pd.to_numeric(pmm["run"], errors="coerce").dropna().astype(int).tolist()
    assert runs == day.pmm["run"].tolist()


def test_hull_day_has_no_captive_sheets_or_pages(captive_day):
    from dataclasses import replace

    from towtank.report.pdf import page_plan
    from towtank.report.workbook import sheet_names

    day, _ = captive_day
    plain = replace(day, captive=None, captive_vertical=None)
    assert "Captive" not in sheet_names(plain) and "PMM" not in sheet_names(plain)
    assert not [p for p in page_plan(plain) if p.section.startswith("Captive")]
