"""Issue 5 on the sample hull day: prototype coefficients and the scaling table.

The SUT-2 prototype (L = 1.412 m, λ = 4) in sea water at 15 °C: every coefficient carries
prime × ½ρ_p·L_p^k, scaling.csv follows Froude and Reynolds similarity and the ITTC-57 line,
and ``towtank scale`` prints the same numbers from the cached reduction.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from towtank import similarity
from towtank.cli import main
from towtank.water import water_properties

ROOT = Path(__file__).resolve().parents[1]
PROTOCOL = ROOT / "protocols" / "sut2_hull.toml"
SCALING_COLUMNS = ["speed_prototype", "re_prototype", "fn_prototype", "speed_model_froude",
                   "speed_model_reynolds", "drag_froude", "drag_ittc57"]


@pytest.fixture(scope="module")
def outputs(tmp_path_factory):
    out = tmp_path_factory.mktemp("sut2") / "out"
    code = main(["process", str(PROTOCOL), "--no-report", "--out", str(out), "-q"])
    assert code == 0
    return out


def test_prototype_values_are_prime_times_prototype_scale(outputs):
    coef = pd.read_csv(outputs / "coefficients.csv")
    sea = water_properties(15.0, "sea")
    for row in coef.itertuples():
        k = 3 if row.symbol.endswith("dot") else 2
        expected = row.prime * 0.5 * sea.rho * 1.412**k
        assert row.prototype_value == pytest.approx(expected, rel=1e-12), row.symbol
    # prime values carry over unchanged: prototype/model ratio = (ρ_p/ρ_m)·λ^k
    x = coef.set_index("symbol")
    ratio = x.loc["X_udot", "prototype_value"] / x.loc["X_udot", "value"]
    fresh = water_properties(18.0, "fresh")
    assert ratio == pytest.approx(sea.rho / fresh.rho * 4.0**3, rel=2e-3)


def test_scaling_table_laws(outputs):
    sc = pd.read_csv(outputs / "scaling.csv")
    assert list(sc.columns[: len(SCALING_COLUMNS)]) == SCALING_COLUMNS
    assert sc["speed_prototype"].tolist() == [1.0, 1.5, 2.0, 2.5]
    sea = water_properties(15.0, "sea")
    fresh = water_properties(18.0, "fresh")
    up = sc["speed_prototype"].to_numpy()
    np.testing.assert_allclose(sc["speed_model_froude"], up / 2.0, rtol=1e-12)
    np.testing.assert_allclose(sc["speed_model_reynolds"], up * 4.0 * fresh.nu / sea.nu,
                               rtol=1e-9)
    np.testing.assert_allclose(sc["re_prototype"], up * 1.412 / sea.nu, rtol=1e-9)
    np.testing.assert_allclose(sc["fn_prototype"], up / np.sqrt(9.80665 * 1.412), rtol=1e-12)
    # Froude drag: the model's zero-angle resistance at U_p/2, times λ³ ρ_p/ρ_m
    runs = pd.read_csv(outputs / "runs.csv")
    zero = runs[(runs.config == "hull") & (runs.status == "ok") & (runs.angle_deg == 0)]
    k2 = np.linalg.lstsq(np.column_stack([zero.speed_mean**2, zero.speed_mean]),
                         zero.drag_mean, rcond=None)[0]
    um = sc["speed_model_froude"].to_numpy()
    r_m = k2[0] * um**2 + k2[1] * um
    np.testing.assert_allclose(sc["drag_froude"], r_m * 64 * sea.rho / fresh.rho, rtol=1e-3)
    # flagged where the Froude model speed was not tested (0.5 and 0.75 m/s < 0.8 m/s)
    assert sc["froude_in_tested_range"].tolist() == [False, False, True, True]


def test_ittc57_drag_follows_form_factor(outputs):
    sc = pd.read_csv(outputs / "scaling.csv")
    runs = pd.read_csv(outputs / "runs.csv")
    zero = runs[(runs.config == "hull") & (runs.status == "ok") & (runs.angle_deg == 0)]
    ff = similarity.form_factor(zero.drag_mean.to_numpy(), zero.speed_mean.to_numpy(), 0.0472,
                                float(zero.rho.mean()), float(zero.nu.mean()), 0.353)
    sea = water_properties(15.0, "sea")
    up = sc["speed_prototype"].to_numpy()
    cf = 0.075 / (np.log10(up * 1.412 / sea.nu) - 2) ** 2
    expected = 0.5 * sea.rho * 0.0472 * 16 * up**2 * ff.one_plus_k * cf
    np.testing.assert_allclose(sc["drag_ittc57"], expected, rtol=1e-9)
    # a deeply submerged hull scaled by Reynolds drags less than Froude-scaled, at every speed
    assert np.all(sc["drag_ittc57"] < sc["drag_froude"])


def test_ittc57_line_value():
    assert similarity.ittc57_cf(1e6) == pytest.approx(0.0046875, rel=1e-12)


def test_scale_command_prints_table_from_cache(outputs, capsys, monkeypatch):
    import towtank.reduce as reduce_stage

    def no_read(*args, **kwargs):
        raise AssertionError("the scale command re-read a run file despite the cache")

    monkeypatch.setattr(reduce_stage, "load_run", no_read)
    code = main(["scale", str(PROTOCOL), "--speeds", "2", "3", "--out", str(outputs)])
    text = capsys.readouterr().out
    assert code == 0
    assert "U_m Froude" in text and "ITTC-57" in text
    assert "1.000" in text and "1.500" in text  # Froude model speeds of 2 and 3 m/s
    assert "depth" in text.lower() or "froude similarity" in text.lower()


def test_myring_geometry_feeds_the_model():
    from towtank.protocol import load_protocol

    p = load_protocol(PROTOCOL)
    assert p.model.myring is not None
    assert p.model.volume_m3 == pytest.approx(math.pi * 0.05**2 / 4 * 0.353, rel=0.5)
    assert "Myring" in p.model.geometry_source
    assert p.model.frontal_area == pytest.approx(math.pi * 0.05**2 / 4, rel=1e-12)
