"""Powering (B-series propeller, effective power) and the pressure hull (#21 items 5, 6)."""

from __future__ import annotations

import math
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from towtank.vehicle.powering import (
    KQ_TERMS,
    KT_TERMS,
    Propeller,
    bseries_kt_kq,
    effective_power,
    match_thrust,
    powering_table,
)
from towtank.vehicle.pressure_hull import (
    axial_stress,
    buckling_thickness,
    hoop_stress,
    pressure_hull_table,
    von_mises_pressure,
    yield_thickness,
)

ROOT = Path(__file__).resolve().parents[1]


def test_bseries_has_the_39_and_47_terms_of_oosterveld_and_van_oossanen():
    assert len(KT_TERMS) == 39 and len(KQ_TERMS) == 47
    assert len(set(t[1:] for t in KT_TERMS)) == 39 and len(set(t[1:] for t in KQ_TERMS)) == 47
    # J = 0, P/D = 0, A_E/A_0 = 0, Z = 0 leaves the constant terms
    kt, kq = bseries_kt_kq(0.0, 0.0, 0.0, 0)
    assert kt == pytest.approx(0.00880496) and kq == pytest.approx(0.00379368)


def test_b4_70_open_water_curve_is_a_propeller():
    j = np.linspace(0.0, 1.0, 21)
    kt, kq = bseries_kt_kq(j, 1.0, 0.70, 4)
    # regression values of the 39- and 47-term polynomials (no published table was at hand)
    assert kt[0] == pytest.approx(0.4547, abs=5e-4)
    assert 10 * kq[0] == pytest.approx(0.6754, abs=5e-4)
    assert np.all(np.diff(kt) < 0) and np.all(np.diff(kq) < 0)
    eta = j[1:] * kt[1:] / (2 * np.pi * kq[1:])
    assert 0.66 < eta.max() < 0.72 and 0.7 < j[1:][eta.argmax()] < 0.9


def test_match_thrust_returns_the_operating_point_that_gives_the_thrust():
    prop = Propeller(0.14, 1.0, 0.55, 3, 0.1, 0.1)
    point = match_thrust(4.0, 1.35, prop, 1025.0)
    n, d = point["rps"], 0.14
    assert point["K_T"] * 1025.0 * n**2 * d**4 == pytest.approx(4.0, rel=1e-9)
    assert point["J"] == pytest.approx(1.35 / (n * d), rel=1e-12)
    assert point["delivered_power_W"] == pytest.approx(2 * math.pi * n * point["torque_N_m"])
    # open-water efficiency = useful thrust power / delivered power
    assert point["eta_open_water"] == pytest.approx(4.0 * 1.35 / point["delivered_power_W"])
    with pytest.raises(ValueError, match="cannot deliver"):
        match_thrust(1e6, 0.1, prop, 1025.0)


def test_powering_table_effective_power_and_hull_factors():
    prop = Propeller(0.14, 1.0, 0.55, 3, thrust_deduction=0.2, wake_fraction=0.1)
    table = powering_table([1.0, 2.0], [2.0, 8.0], prop, 1025.0)
    assert list(table["effective_power_W"]) == pytest.approx([2.0, 16.0])
    assert list(table["thrust_N"]) == pytest.approx([2.5, 10.0])
    assert list(table["advance_speed_m_s"]) == pytest.approx([0.9, 1.8])
    assert effective_power(3.0, 1.5) == pytest.approx(4.5)


def test_von_mises_long_cylinder_limit_is_bresse():
    # l >> R: q_c -> E h^3 / (4 R^3 (1 - nu^2)) at n = 2 (Bresse/Bryan)
    e, nu, r, h = 200e9, 0.3, 0.5, 0.01
    q, n = von_mises_pressure(h, r, 1e4, e, nu)
    assert n == 2
    assert q == pytest.approx(e * h**3 / (4 * r**3 * (1 - nu**2)), rel=1e-3)


def test_pressure_hull_thicknesses():
    p = 1025.0 * 9.80665 * 300.0
    assert hoop_stress(p, 0.1, 0.002) == pytest.approx(2 * axial_stress(p, 0.1, 0.002))
    h_y = yield_thickness(p, 0.1, 276e6, 1.5)
    assert hoop_stress(1.5 * p, 0.1, h_y) == pytest.approx(276e6)
    h_b = buckling_thickness(p, 0.1, 0.4, 69e9, 0.33, 1.5)
    assert von_mises_pressure(h_b, 0.1, 0.4, 69e9, 0.33)[0] == pytest.approx(1.5 * p, rel=1e-6)
    t = pressure_hull_table(300.0, 0.1, 0.4, 276e6, 69e9, 0.33, 1.5, 1025.0)
    t = t.set_index("quantity")["value"]
    assert t["thickness_required"] == pytest.approx(max(h_y, h_b))
    assert t["pressure"] == pytest.approx(p)


def test_predict_writes_powering_and_pressure_hull(tmp_path, capsys):
    from towtank.commands.cli import main

    text = (ROOT / "protocols" / "remus_vehicle.toml").read_text()
    text = text.replace('output_dir = "../reports/remus"', 'output_dir = "out"')
    text += ("\n[vehicle.propeller]\ndiameter_m = 0.14\npitch_ratio = 1.0\n"
             "blade_area_ratio = 0.55\nblades = 3\nthrust_deduction = 0.1\n"
             "wake_fraction = 0.1\nspeeds_m_s = [1.0, 1.5]\n"
             "\n[vehicle.pressure_hull]\ndepth_m = 100.0\nyield_MPa = 276.0\nE_GPa = 69.0\n"
             "frame_spacing_m = 0.5\n")
    (tmp_path / "p.toml").write_text(text)
    assert main(["predict", str(tmp_path / "p.toml")]) == 0
    power = pd.read_csv(tmp_path / "out" / "powering.csv")
    assert list(power["speed_m_s"]) == [1.0, 1.5]
    assert np.all(power["effective_power_W"] > 0) and np.all(power["eta_open_water"] > 0.5)
    hull = pd.read_csv(tmp_path / "out" / "pressure_hull.csv").set_index("quantity")
    assert 0 < hull.loc["thickness_required", "value"] < 0.0955 / 10
    capsys.readouterr()
    # without the sections: neither file
    shutil.rmtree(tmp_path / "out")
    (tmp_path / "q.toml").write_text(text.split("\n[vehicle.propeller]")[0])
    assert main(["predict", str(tmp_path / "q.toml")]) == 0
    assert not (tmp_path / "out" / "powering.csv").exists()


@pytest.mark.parametrize(("section", "message"), [
    ("[vehicle.propeller]\ndiameter_m = 0.14\npitch_ratio = 2.0\nblade_area_ratio = 0.5\n",
     "'pitch_ratio' in \\[vehicle.propeller\\] must be a number from 0.5 to 1.4"),
    ("[vehicle.propeller]\ndiameter_m = 0.14\nblade_area_ratio = 0.5\n",
     "missing the required key 'pitch_ratio'"),
    ("[vehicle.pressure_hull]\ndepth_m = 100.0\nyield_MPa = 276.0\nE_GPa = 69.0\ncolour = 1\n",
     "unknown key 'colour' in \\[vehicle.pressure_hull\\]"),
])
def test_bad_design_sections_stop_with_exit_2(tmp_path, capsys, section, message):
    from towtank.commands.cli import main

    text = (ROOT / "protocols" / "remus_vehicle.toml").read_text()
    text = text.replace('output_dir = "../reports/remus"', 'output_dir = "out"')
    (tmp_path / "p.toml").write_text(text + "\n" + section)
    assert main(["predict", str(tmp_path / "p.toml")]) == 2
    import re

    assert re.search(message, capsys.readouterr().err)
    assert not (tmp_path / "out").exists()
