"""The sting tare as a lab checks it first (issue 16): tare.csv, the workbook's Tare sheet,
provenance.json's ``tare`` and the report's tare figure, with the generator's tare inside the
fitted intervals."""

from __future__ import annotations

import json

import pandas as pd
import pytest

from towtank.report import write_outputs
from towtank.testing.truth import TareTruth


@pytest.fixture(scope="session")
def out(hull_day, tmp_path_factory):
    """The day's tables, provenance and workbook (the tests read no PDF or figure)."""
    from towtank.report.workbook import write_workbook

    folder = tmp_path_factory.mktemp("tare_out") / "out"
    write_outputs(hull_day.result, folder, writers=[write_workbook])
    return folder


@pytest.mark.heavy
def test_tare_csv_holds_the_generators_tare_inside_its_intervals(out):
    truth = TareTruth()
    table = pd.read_csv(out / "tare.csv").set_index("channel")
    expected = {"drag": (truth.t2, truth.t1, truth.m_t),
                "lift": (truth.lift_t2, truth.lift_t1, truth.lift_m_t)}
    for channel, values in expected.items():
        row = table.loc[channel]
        for name, value in zip(("t2", "t1", "m_t"), values, strict=True):
            assert row[f"{name}_ci_low"] <= value <= row[f"{name}_ci_high"], (channel, name)
            assert row[name] == pytest.approx(value, rel=0.1, abs=2e-3)
        assert row["speed_min"] < row["speed_max"] and row["dof"] >= 3
        assert len(str(row["runs"]).split()) >= 4


def test_tare_is_in_the_workbook_and_the_provenance(out):
    from openpyxl import load_workbook

    ws = load_workbook(out / "report.xlsx", read_only=True)["Tare"]
    header = [c for c in next(ws.iter_rows(min_row=1, max_row=1, values_only=True)) if c]
    assert "t2 [N s²/m²]" in header and "m_t [kg]" in header
    table = pd.read_csv(out / "tare.csv")
    prov = json.loads((out / "provenance.json").read_text(encoding="utf-8"))["tare"]
    assert [r["m_t"] for r in prov] == pytest.approx(table["m_t"].tolist(), rel=1e-12)


def test_every_coefficient_has_its_uncertainty_budget(out):
    """u_regression, u_tare, u_mass add in quadrature to std_error, and the interval's
    half-width is t(dof)·std_error (issue 16: the budget behind each interval)."""
    from scipy.stats import t

    coef = pd.read_csv(out / "coefficients.csv").set_index("symbol")
    for sym, row in coef.iterrows():
        total = (row["u_regression"] ** 2 + row["u_tare"] ** 2 + row["u_mass"] ** 2) ** 0.5
        assert total == pytest.approx(row["std_error"], rel=1e-9), sym
        half = (row["ci_high"] - row["ci_low"]) / 2
        assert half == pytest.approx(t.ppf(0.975, row["dof"]) * row["std_error"], rel=1e-6), sym
    assert coef.loc["X_udot", "u_mass"] == pytest.approx(0.0005)  # the stated 0.5 g
    assert coef.loc["X_udot", "u_tare"] > 0 and coef.loc["X_u|u|", "u_mass"] == 0
