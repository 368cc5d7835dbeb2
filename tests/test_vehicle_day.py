"""A processed hull day with a [vehicle]: predicted beside measured, model.json, samples."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from conftest import Day, process

from towtank.commands.cli import main
from towtank.report.outputs import write_outputs

VEHICLE = """
[vehicle]
name = "SUT-2 model"
hull = "myring"
speed_m_s = 1.0
[[vehicle.fins]]
plane = "rudder"
x_m = -0.16
span_m = 0.02
chord_m = 0.02
[[vehicle.fins]]
plane = "sternplane"
x_m = -0.16
span_m = 0.02
chord_m = 0.02
"""


@pytest.mark.heavy
def test_hull_day_with_a_vehicle_writes_predicted_beside_measured(hull_day: Day, tmp_path,
                                                                  capsys):
    text = hull_day.protocol.read_text()
    assert "[model.myring]" in text
    proto = hull_day.protocol.with_name("vehicle.toml")
    proto.write_text(text + VEHICLE)
    day = process(proto)
    coef = day.coefficients.set_index("symbol")
    assert {"predicted", "predicted_diff_pct"} <= set(coef.columns)
    # the synthetic SUT-2 day's added mass is a Myring body's: prediction and measurement agree
    assert abs(coef.loc["X_udot", "predicted_diff_pct"]) < 50
    assert abs(coef.loc["Y_vdot", "predicted_diff_pct"]) < 25
    d = coef.loc["Y_vdot"]
    assert d["predicted_diff_pct"] == (d["prime"] - d["predicted"]) / abs(d["predicted"]) * 100
    out = write_outputs(day, tmp_path / "out", report=False)
    model = json.loads((out / "model.json").read_text())
    assert model["sources"]["Y_vdot"] == "measured" and model["sources"]["N_rdot"] == "predicted"
    # the measured value is carried as it was measured (vehicle = the model itself)
    assert model["coefficients"]["Y_vdot"] == np.float64(coef.loc["Y_vdot", "value"]).item() \
        or abs(model["coefficients"]["Y_vdot"] / coef.loc["Y_vdot", "value"] - 1) < 1e-9
    symbols = model["covariance"]["symbols"]
    assert "Y_vdot" in symbols and len(model["covariance"]["matrix"]) == len(symbols)
    assert (out / "predicted.csv").is_file()
    assert not (out / "figures").exists()  # --no-report: no figure
    from towtank.report.vehicle import predicted_figure

    fig = predicted_figure(day.coefficients)
    assert [t.get_text() for t in fig.axes[0].get_yticklabels()][:2] == ["X_udot", "Y_vdot"]
    written = pd.read_csv(out / "coefficients.csv")
    assert "predicted_diff_pct" in written.columns
    # the measured covariance carries into the manoeuvre: 95 % bands (of 2 draws: the
    # bands' columns and their order are what is asserted, not their width)
    code = main(["simulate", str(out / "model.json"), "--manoeuvre", "turning",
                 "--rudder-deg", "10", "--samples", "2", "--duration-s", "40",
                 "--out", str(tmp_path / "sim")])
    assert code == 0
    met = pd.read_csv(tmp_path / "sim" / "metrics.csv").set_index("metric")
    lo, hi = met.loc["tactical_diameter_m", ["ci_low", "ci_high"]]
    assert lo <= hi and np.isfinite(lo)
    assert (tmp_path / "sim" / "manoeuvre.png").stat().st_size > 1000
