"""Tests of the synthetic-run generator: exact truth, file round trips, determinism."""

from __future__ import annotations

import gzip
import io
import json
import math
import tomllib
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from scipy import integrate

from towtank.testing import synthetic as syn

ROOT = Path(__file__).resolve().parents[1]
WATER = SimpleNamespace(rho=998.6, nu=1.054e-6)  # stand-in for towtank.reference.water at 18 degC
RHO = WATER.rho


def _table4() -> dict[str, float]:
    path = ROOT / "towtank" / "reference" / "data" / "sut2_table4.csv"
    assert path.exists(), "towtank/reference/data/sut2_table4.csv must ship with the package"
    df = pd.read_csv(path, comment="#")
    return dict(zip(df["symbol"], df["sut2_prime"].astype(float), strict=True))


def _quiet_run(config="hull", angle=0.0, speed=1.2, accel=0.5, **kw):
    kw.setdefault("water", WATER)
    kw.setdefault("fs", 500.0)
    kw.setdefault("noise", syn.Noise.quiet())
    return syn.simulate_run(config, angle, speed, accel, **kw)


# ------------------------------------------------------------------------------------ profile
@pytest.mark.parametrize(
    "speed, accel",
    [(2.0, 0.25), (2.0, 1.0), (1.2, 0.5), (0.3, 0.1), (0.1, 0.05), (0.1, 2.0), (3.0, 2.0)],
)
def test_profile_exact_speed_accel_and_fits_tank(speed, accel):
    plan = syn.plan_profile(speed, accel)
    t, u, a = syn.carriage_profile(speed, accel, fs=1000.0)
    assert u.max() == speed
    plateau = (t >= plan.t_plateau_start) & (t < plan.t_plateau_end)
    assert plateau.sum() > 0.9 * plan.plateau_s * 1000
    assert np.all(u[plateau] == speed)
    assert np.all(a[plateau] == 0.0)
    const = (t >= plan.t_const_accel_start) & (t < plan.t_const_accel_end)
    assert const.sum() > 0
    assert np.all(a[const] == accel)
    # the constant stretch gains at least half of the speed, even at low speed / high accel
    assert accel * (plan.t_const_accel_end - plan.t_const_accel_start) >= 0.5 * speed - 1e-12
    assert np.all(u >= 0.0)
    assert u[0] == 0.0 and u[-1] == 0.0 and a[0] == 0.0 and a[-1] == 0.0
    assert plan.distance <= 100.0
    assert integrate.trapezoid(u, t) == pytest.approx(plan.distance, rel=1e-4, abs=1e-3)
    assert 2.0 <= plan.plateau_s <= 8.0
    # speed is the integral of the acceleration (S-curve consistent)
    assert np.allclose(np.cumsum(a) / 1000.0, u, atol=speed * 2e-3 + 1e-3)


def test_profile_phases_and_defaults():
    plan = syn.plan_profile(2.0, 0.25, jerk=4.0)
    assert plan.t_accel_start == 3.0
    assert plan.t_const_accel_start == pytest.approx(3.0 + 0.25 / 4.0)
    assert plan.t_plateau_start == pytest.approx(3.0 + 2.0 / 0.25 + 0.25 / 4.0)
    assert plan.plateau_s == 8.0
    assert plan.decel == 0.5  # max(accel, 0.5)
    assert syn.plan_profile(1.0, 1.5).decel == 1.5
    assert plan.duration == pytest.approx(plan.t_decel_end + 3.0)
    ph = plan.phases()
    assert ph["t_still_end"] == ph["t_accel_start"]
    assert ph["t_accel_end"] == ph["t_plateau_start"]
    assert ph["t_decel_start"] == ph["t_plateau_end"]
    order = [
        "t_accel_start",
        "t_const_accel_start",
        "t_const_accel_end",
        "t_plateau_start",
        "t_plateau_end",
        "t_decel_const_start",
        "t_decel_const_end",
        "t_decel_end",
        "t_end",
    ]
    assert all(ph[a] < ph[b] for a, b in zip(order, order[1:], strict=False))


def test_profile_plateau_shrinks_then_refuses():
    plan = syn.plan_profile(3.0, 0.06, tank_length_m=100.0)  # ramp 75 m, stop 9+ m
    assert 2.0 <= plan.plateau_s < 8.0
    assert plan.distance == pytest.approx(100.0)
    with pytest.raises(ValueError, match="does not fit"):
        syn.plan_profile(3.0, 0.05)
    with pytest.raises(ValueError, match="more than"):
        syn.plan_profile(2.0, 0.5, plateau_s=60.0)
    with pytest.raises(ValueError):
        syn.plan_profile(0.0, 0.5)
    with pytest.raises(ValueError):
        syn.plan_profile(1.0, -0.5)


@settings(max_examples=150, deadline=None)
@given(
    speed=st.floats(min_value=0.1, max_value=3.0),
    accel=st.floats(min_value=0.05, max_value=2.0),
)
def test_profile_property_monotone_and_nonnegative(speed, accel):
    try:
        plan = syn.plan_profile(speed, accel)
    except ValueError:
        assume(False)
        return
    t, u, a = syn.carriage_profile(speed, accel, fs=200.0)
    assert np.all(u >= 0.0)
    assert u.max() == speed
    up = t <= plan.t_plateau_start
    assert np.all(np.diff(u[up]) >= 0.0)
    down = t >= plan.t_plateau_end
    assert np.all(np.diff(u[down]) <= 0.0)
    assert plan.distance <= 100.0 * (1 + 1e-12)
    const = (t >= plan.t_const_accel_start) & (t < plan.t_const_accel_end)
    assert np.all(a[const] == accel)


# ------------------------------------------------------------------------------------ physics
@pytest.mark.parametrize("angle", [0.0, 10.0, 90.0])
def test_quiet_hull_run_is_exact(angle):
    hull = syn.sut2_hull_truth(RHO)
    frame, truth = _quiet_run("hull", angle, 0.3 if angle == 90 else 1.6, 0.2, hull=hull)
    t, drag, lift = frame["time"].to_numpy(), frame["drag"].to_numpy(), frame["lift"].to_numpy()
    v, acc = truth["speed"], truth["accel"]
    if angle == 90.0:
        q_area_cd = 0.5 * RHO * hull.lateral_area * hull.cd90
    else:
        q_area_cd = 0.5 * RHO * hull.frontal_area * hull.cd(angle)
    plateau = (t >= truth["t_plateau_start"]) & (t < truth["t_plateau_end"])
    assert np.all(drag[plateau] == q_area_cd * (v * v))
    assert np.all(drag[plateau] == truth["drag_model"])
    assert np.all(frame["speed"].to_numpy()[plateau] == v)
    # the constant-acceleration stretch: D - R(U) = M_eff a
    const = (t >= truth["t_const_accel_start"]) & (t < truth["t_const_accel_end"])
    u = frame["speed"].to_numpy()[const]
    m_eff = hull.m - hull.X_udot * math.cos(math.radians(angle)) ** 2
    m_eff -= hull.Y_vdot * math.sin(math.radians(angle)) ** 2
    np.testing.assert_allclose(drag[const] - q_area_cd * u * u, m_eff * acc, rtol=1e-12, atol=1e-14)
    assert truth["m_eff"] == pytest.approx(m_eff, rel=1e-14)
    assert truth["inertia_drag"] == pytest.approx(m_eff * acc, rel=1e-14)
    # lift: body lift at small angles, none at 0 and 90 deg
    expected_cl = 0.0 if angle in (0.0, 90.0) else hull.cl_alpha * math.radians(angle)
    np.testing.assert_allclose(
        lift[plateau], 0.5 * RHO * hull.frontal_area * expected_cl * v * v, rtol=1e-14, atol=0
    )
    assert truth["tare_drag"] == 0.0 and truth["zero_drag"] == 0.0 and truth["drift_drag"] == 0.0
    still = t < truth["t_still_end"]
    assert np.all(drag[still] == 0.0) and np.all(lift[still] == 0.0)


def test_quiet_hull_cd_and_truth_fields():
    hull = syn.sut2_hull_truth(RHO)
    _, truth = _quiet_run("hull", 15.0, 2.0, 0.5, hull=hull)
    al = math.radians(15.0)
    assert truth["cd"] == pytest.approx(hull.a2 * al**2 + hull.b1 * al + hull.c0, rel=1e-12)
    assert truth["cl"] == pytest.approx(2.0 * al, rel=1e-12)
    assert truth["reynolds"] == pytest.approx(2.0 * 0.353 / WATER.nu)
    assert truth["reynolds"] > 1e5
    with pytest.raises(ValueError, match="30 deg"):
        _quiet_run("hull", 45.0, 1.0, 0.5, hull=hull)


def test_tare_forces_on_sting_and_hull():
    tare = syn.TareTruth()
    hull = syn.sut2_hull_truth(RHO)
    sting, st_truth = _quiet_run("sting", 0.0, 2.0, 0.5, tare=tare, rng=3)
    model, m_truth = _quiet_run("hull", 0.0, 2.0, 0.5, tare=tare, hull=hull, rng=3)
    bare, _ = _quiet_run("hull", 0.0, 2.0, 0.5, hull=hull, rng=3)
    t = sting["time"].to_numpy()
    u, a = syn.plan_profile(2.0, 0.5).evaluate(t)
    f_tare = tare.t2 * u * np.abs(u) + tare.t1 * u + tare.m_t * a
    np.testing.assert_allclose(sting["drag"], f_tare, rtol=1e-13, atol=1e-15)
    np.testing.assert_allclose(model["drag"] - bare["drag"], f_tare, rtol=1e-12, atol=1e-14)
    l_tare = tare.lift_t2 * u * np.abs(u) + tare.lift_t1 * u + tare.lift_m_t * a
    np.testing.assert_allclose(sting["lift"], l_tare, rtol=1e-13, atol=1e-15)
    assert st_truth["tare_drag"] == pytest.approx(0.08 * 4.0 + 0.01 * 2.0)
    assert st_truth["drag_model"] == 0.0
    assert m_truth["tare_drag"] == st_truth["tare_drag"]


def test_quiet_fin_run_uses_sandia_at_each_reynolds():
    from towtank.reference import sandia
    fin = syn.FinTruth()
    frame, truth = _quiet_run("fin", 10.0, 2.0, 0.5, fin=fin)
    t = frame["time"].to_numpy()
    u, a = syn.plan_profile(2.0, 0.5).evaluate(t)
    moving = u > 0.2
    re = u[moving] * fin.chord / WATER.nu
    cl, cd = sandia.section_coefficients(np.full(re.shape, 10.0), re)
    q = 0.5 * RHO * fin.area * u[moving] ** 2
    np.testing.assert_allclose(frame["lift"].to_numpy()[moving], q * cl, rtol=1e-12)
    np.testing.assert_allclose(
        frame["drag"].to_numpy()[moving], q * cd + fin.m_fin * a[moving], rtol=1e-12, atol=1e-12
    )
    cl_p, cd_p = sandia.section_coefficients(10.0, 2.0 * fin.chord / WATER.nu)
    assert truth["cl"] == pytest.approx(float(cl_p), rel=1e-12)
    assert truth["cd"] == pytest.approx(float(cd_p), rel=1e-12)
    assert truth["reynolds"] == pytest.approx(2.0 * 0.12 / WATER.nu)


# -------------------------------------------------------------------------------------- truth
def test_sut2_truth_reproduces_table4_primes():
    table = _table4()
    assert table == pytest.approx(syn.SUT2_TABLE4_PRIME, rel=0, abs=0)
    for rho in (998.6, 1000.0, 1025.0):
        hull = syn.sut2_hull_truth(rho)
        coeffs = hull.coefficients(rho)
        assert tuple(coeffs) == syn.COEFFICIENT_SYMBOLS
        for sym, value in coeffs.items():
            k = 3 if sym.endswith("dot") else 2
            assert value / (0.5 * rho * 0.353**k) == pytest.approx(table[sym], rel=1e-12), sym
        assert hull.primes(rho) == pytest.approx(table, rel=1e-12)


def test_sut2_truth_model_scale_values():
    hull = syn.sut2_hull_truth(998.6)
    assert -hull.X_udot == pytest.approx(0.017, rel=0.02)
    assert -hull.Y_vdot == pytest.approx(0.682, rel=0.02)
    assert hull.frontal_area == pytest.approx(math.pi * 0.05**2 / 4)
    assert hull.c0 == pytest.approx(0.2094, abs=2e-4)
    assert hull.cd90 == pytest.approx(0.787, abs=1e-3)
    c = hull.coefficients(998.6)
    assert c["Z_wdot"] == c["Y_vdot"] and c["Z_w|w|"] == c["Y_v|v|"]
    assert c["X_uw"] == c["X_uv"] and c["X_w|w|"] == c["X_v|v|"] and c["Z_uw"] == c["Y_uv"]
    assert c["Y_uv"] == c["X_u|u|"]
    assert hull.m_eff(0.0) == pytest.approx(0.552 - hull.X_udot)
    assert hull.m_eff(90.0) == pytest.approx(0.552 - hull.Y_vdot)


def test_sut2_truth_at_18C_with_water_module():
    from towtank.reference import water
    rho = water.water_properties(18.0).rho
    hull = syn.sut2_hull_truth(rho)
    assert -hull.X_udot == pytest.approx(0.017, rel=0.02)
    assert -hull.Y_vdot == pytest.approx(0.682, rel=0.02)


# -------------------------------------------------------------------------------------- noise
def test_noise_defaults_statistics():
    noise = syn.Noise()
    fs = 1000.0
    frame, truth = syn.simulate_run(
        "hull", 0.0, 1.2, 0.5, water=WATER, fs=fs, rng=11, noise=noise, pre_still_s=6.0
    )
    t = frame["time"].to_numpy()
    still = t < truth["t_still_end"]
    drag = frame["drag"].to_numpy()[still]
    assert abs(truth["zero_drag"]) <= 0.3 and abs(truth["zero_lift"]) <= 0.3
    assert abs(truth["drift_drag"]) <= 0.005 and abs(truth["drift_lift"]) <= 0.005
    assert 8.0 <= truth["vibration_hz"] <= 15.0
    # white (5 mN) + hum (2 mN amplitude, rms 1.41 mN), carriage at rest: no vibration
    expected = math.sqrt(0.005**2 + 0.002**2 / 2)
    assert np.std(drag) == pytest.approx(expected, rel=0.1)
    assert np.mean(drag) == pytest.approx(truth["zero_drag"], abs=1e-3)
    speed = frame["speed"].to_numpy()[still]
    assert np.std(speed) == pytest.approx(0.001, rel=0.15)
    q = np.round(speed / 1e-4)
    assert np.allclose(speed, q * 1e-4, atol=1e-12)


def test_noise_density_fixed_across_fs():
    stds = {}
    for fs in (200.0, 2000.0):
        noise = syn.Noise(hum_amplitude=0.0, zero_offset=0.0, drift=0.0)
        frame, truth = syn.simulate_run(
            "sting", 0.0, 1.0, 0.5, water=WATER, fs=fs, rng=5, noise=noise
        )
        still = frame["time"].to_numpy() < truth["t_still_end"]
        stds[fs] = np.std(frame["drag"].to_numpy()[still])
    assert stds[2000.0] / stds[200.0] == pytest.approx(math.sqrt(10.0), rel=0.1)


def test_accel_channel_optional():
    frame, _ = _quiet_run(accel_channel=True)
    assert list(frame.columns) == ["time", "speed", "accel", "drag", "lift"]
    frame, _ = _quiet_run()
    assert list(frame.columns) == ["time", "speed", "drag", "lift"]


# ------------------------------------------------------------------------------ files and I/O
def _noisy_frame(seed=1, accel_channel=True):
    return syn.simulate_run(
        "hull", 5.0, 1.2, 0.5, water=WATER, fs=200.0, rng=seed, accel_channel=accel_channel
    )[0]


@pytest.mark.parametrize("ext", ["csv", "csv.gz"])
def test_csv_round_trip_pandas_and_pyarrow(tmp_path, ext):
    import pyarrow.csv as pacsv

    frame = _noisy_frame()
    path = syn.write_run_file(frame, tmp_path / f"run.{ext}")
    written = syn.to_file_frame(frame)
    back = pd.read_csv(path)
    assert list(back.columns) == list(frame.columns)
    np.testing.assert_array_equal(back.to_numpy(), written.to_numpy())
    arrow = pacsv.read_csv(path).to_pandas()
    np.testing.assert_array_equal(arrow.to_numpy(), written.to_numpy())
    tol = {"time": 5e-7, "speed": 5e-7, "accel": 5e-6, "drag": 5e-7, "lift": 5e-7}
    for col, atol in tol.items():
        np.testing.assert_allclose(back[col], frame[col], rtol=0, atol=atol * 1.0001)


def test_lab_style_round_trip_with_calibration(tmp_path):
    frame = _noisy_frame(accel_channel=False)
    lab = syn.LabChannels(drag_offset=0.0125)
    path = syn.write_run_file(frame, tmp_path / "run.csv.gz", channel_style="lab", channels=lab)
    with gzip.open(path, "rt") as fh:
        header = fh.readline().strip()
    assert header == "Time (s),Carriage speed (m/s),Fx load cell (V),Fy load cell (V)"
    back = pd.read_csv(path)
    drag = 20.0 * (back["Fx load cell (V)"] - 0.0125)
    lift = -25.0 * back["Fy load cell (V)"]
    np.testing.assert_allclose(drag, frame["drag"], rtol=0, atol=20.0 * 5e-9 + 1e-12)
    np.testing.assert_allclose(lift, frame["lift"], rtol=0, atol=25.0 * 5e-9 + 1e-12)
    np.testing.assert_allclose(back["Time (s)"], frame["time"], atol=5e-7)
    section = lab.protocol_section()
    assert section["drag"] == {"column": "Fx load cell (V)", "gain": 20.0, "offset": 0.0125}
    assert section["lift"]["gain"] == -25.0


@pytest.mark.parametrize("dtype", ["float64", "float32"])
@pytest.mark.parametrize("style", ["canonical", "lab"])
def test_tdms_round_trip(tmp_path, dtype, style):
    from nptdms import TdmsFile

    frame = _noisy_frame()
    path = syn.write_run_file(frame, tmp_path / "run.tdms", channel_style=style, tdms_dtype=dtype)
    written = syn.to_file_frame(frame, style)
    tdms = TdmsFile.read(path)
    assert [g.name for g in tdms.groups()] == ["data"]
    group = tdms["data"]
    assert [c.name for c in group.channels()] == list(written.columns)
    for col in written.columns:
        values = group[col][:]
        is_time = col in ("time", "Time (s)")
        assert values.dtype == (np.float64 if is_time else np.dtype(dtype))
        if dtype == "float64" or is_time:
            np.testing.assert_array_equal(values, written[col].to_numpy())
        else:
            np.testing.assert_allclose(values, written[col].to_numpy(), rtol=1e-7, atol=1e-12)
    assert group[written.columns[0]].properties["unit_string"] == "s"


def test_same_seed_same_bytes_different_seed_differs(tmp_path):
    def csv_bytes(seed, name):
        frame, _ = syn.simulate_run("hull", 0.0, 1.6, 0.5, water=WATER, fs=200.0, rng=seed)
        return syn.write_run_file(frame, tmp_path / name).read_bytes()

    assert csv_bytes(42, "a.csv") == csv_bytes(42, "b.csv")
    assert csv_bytes(42, "c.csv") != csv_bytes(43, "d.csv")
    g1 = np.random.default_rng(7)
    g2 = np.random.default_rng(7)
    f1, t1 = syn.simulate_run("sting", 0.0, 0.8, 0.5, water=WATER, fs=200.0, rng=g1)
    f2, t2 = syn.simulate_run("sting", 0.0, 0.8, 0.5, water=WATER, fs=200.0, rng=g2)
    pd.testing.assert_frame_equal(f1, f2)
    assert t1 == t2


def test_run_sheet_csv_and_xlsx(tmp_path):
    rows = [
        {"run": 1, "file": "run_001.csv", "config": "sting", "test": "steady", "angle_deg": 0.0,
         "speed_nominal": 1.0, "accel_nominal": 0.5, "tare_group": "A", "water_temp_C": 18.0,
         "status": "ok", "remarks": ""},
        {"run": 2, "file": "run_002.csv", "config": "hull", "test": "accel", "angle_deg": 0.0,
         "speed_nominal": 2.0, "accel_nominal": 1.0, "tare_group": "A", "water_temp_C": 18.1,
         "status": "void", "remarks": "carriage stopped early"},
    ]  # fmt: skip
    a = syn.write_run_sheet(rows, tmp_path / "a.xlsx").read_bytes()
    b = syn.write_run_sheet(rows, tmp_path / "b.xlsx").read_bytes()
    assert a == b  # reproducible workbook
    x = pd.read_excel(tmp_path / "a.xlsx")
    c = pd.read_csv(syn.write_run_sheet(rows, tmp_path / "s.csv"), keep_default_na=False)
    for df in (x, c):
        assert tuple(df.columns) == syn.SHEET_COLUMNS
        assert df["run"].tolist() == [1, 2]
        assert df["status"].tolist() == ["ok", "void"]
        assert df["water_temp_C"].tolist() == [18.0, 18.1]
    assert c["remarks"].tolist() == ["", "carriage stopped early"]


# ------------------------------------------------------------------------------------- days
SMALL_HULL_PLAN = [
    syn.RunSpec("sting", 0.0, 0.8, 0.5),
    syn.RunSpec("sting", 0.0, 1.2, 1.0, test="accel"),
    syn.RunSpec("hull", 0.0, 1.2, 1.0, test="accel"),
    syn.RunSpec("hull", 10.0, 1.0, 0.5, status="void", remarks="carriage stopped early",
                plateau_s=0.6),
    syn.RunSpec("hull", 90.0, 0.2, 0.1, water_temp_C=18.0, run=20),
]  # fmt: skip


def test_make_hull_day_small(tmp_path):
    kw = dict(seed=5, runs=SMALL_HULL_PLAN, file_format="csv", sheet_format="csv")
    truth = syn.make_hull_day(tmp_path / "a", **kw)
    syn.make_hull_day(tmp_path / "b", **kw)
    files = sorted(p.name for p in (tmp_path / "a" / "data").iterdir())
    assert files == ["run_001.csv", "run_002.csv", "run_003.csv", "run_004.csv", "run_020.csv"]
    for name in files:
        a = (tmp_path / "a" / "data" / name).read_bytes()
        assert a == (tmp_path / "b" / "data" / name).read_bytes()
    sheet = pd.read_csv(tmp_path / "a" / "run_sheet.csv", keep_default_na=False)
    assert tuple(sheet.columns) == syn.SHEET_COLUMNS
    assert sheet["run"].tolist() == [1, 2, 3, 4, 20]
    assert sheet["status"].tolist() == ["ok", "ok", "ok", "void", "ok"]
    assert sheet["water_temp_C"].between(17.8, 18.3).all()
    assert sheet["water_temp_C"].iloc[-1] == 18.0
    header = (tmp_path / "a" / "data" / "run_001.csv").read_text().splitlines()[0]
    assert header.startswith("Time (s),Carriage speed (m/s),Fx load cell (V)")

    data = syn.load_truth(tmp_path / "a")
    assert data == json.loads((tmp_path / "b" / "truth.json").read_text())
    assert data["seed"] == 5 and data["generator_version"] == syn.GENERATOR_VERSION
    assert set(data["coefficients"]) == set(syn.COEFFICIENT_SYMBOLS)
    assert data["coefficients"] == pytest.approx(truth.hull.coefficients(truth.water["rho"]))
    assert data["tares"]["A"]["t2"] == 0.08
    run3 = data["runs"]["3"]
    assert run3["config"] == "hull" and run3["accel"] == 1.0 and run3["test"] == "accel"
    assert run3["tare_drag"] == pytest.approx(0.08 * 1.44 + 0.01 * 1.2)
    assert run3["m_eff"] == pytest.approx(0.552 - truth.hull.X_udot)
    assert data["runs"]["4"]["t_plateau_end"] - data["runs"]["4"]["t_plateau_start"] == (
        pytest.approx(0.6)
    )
    # the recorded file, calibrated back, carries the truth: zero + tare + model on the plateau
    run = truth.runs[3]
    back = pd.read_csv(tmp_path / "a" / "data" / "run_003.csv")
    t = back["Time (s)"].to_numpy()
    drag = 20.0 * back["Fx load cell (V)"].to_numpy()
    plateau = (t > run["t_plateau_start"] + 0.5) & (t < run["t_plateau_end"] - 0.5)
    still = t < run["t_still_end"] - 0.2
    measured = drag[plateau].mean() - drag[still].mean()
    assert measured == pytest.approx(run["drag_model"] + run["tare_drag"], abs=0.01)


def test_make_hull_day_quiet_is_exact(tmp_path):
    plan = [syn.RunSpec("hull", 0.0, 1.6, 0.5), syn.RunSpec("sting", 0.0, 1.6, 0.5)]
    truth = syn.make_hull_day(
        tmp_path, runs=plan, noise=syn.Noise.quiet(), file_format="csv",
        channel_style="canonical", sheet_format="csv", temperature_spread_C=None,
    )  # fmt: skip
    for number in (1, 2):
        run = truth.runs[number]
        expected = run["drag_model"] + run["tare_drag"]  # the day's sting tare is in both
        back = pd.read_csv(tmp_path / "data" / f"run_{number:03d}.csv")
        t = back["time"].to_numpy()
        plateau = (t >= run["t_plateau_start"]) & (t < run["t_plateau_end"])
        np.testing.assert_allclose(back["drag"].to_numpy()[plateau], expected, atol=5e-7)
        np.testing.assert_array_equal(back["speed"].to_numpy()[plateau], 1.6)
        assert run["water_temp_C"] == 18.0 and run["rho"] == truth.water["rho"]
    assert truth.runs[2]["drag_model"] == 0.0 and truth.runs[1]["tare_drag"] > 0.0


def test_make_fin_day_small(tmp_path):
    from nptdms import TdmsFile

    plan = [
        syn.RunSpec("sting", 0.0, 1.5, 0.5, tare_group="post"),
        syn.RunSpec("fin", 15.0, 2.0, 0.5, tare_group="post"),
    ]
    truth = syn.make_fin_day(tmp_path, seed=9, runs=plan)
    assert (tmp_path / "run_sheet.csv").exists() and (tmp_path / "truth.json").exists()
    tdms = TdmsFile.read(tmp_path / "data" / "run_002.tdms")
    assert [c.name for c in tdms["data"].channels()] == ["time", "speed", "drag", "lift"]
    run = truth.runs[2]
    assert run["config"] == "fin" and run["reynolds"] == pytest.approx(2.0 * 0.12 / run["nu"])
    t = tdms["data"]["time"][:]
    lift = tdms["data"]["lift"][:].astype(float)
    plateau = (t > run["t_plateau_start"] + 0.5) & (t < run["t_plateau_end"] - 0.5)
    still = t < run["t_still_end"] - 0.2
    measured = lift[plateau].mean() - lift[still].mean()
    assert measured == pytest.approx(run["lift_model"] + run["tare_lift"], abs=0.01)
    assert truth.fin.area == pytest.approx(0.018)


def test_day_plans():
    hull = syn.hull_day_plan()
    counts = pd.Series([r.config for r in hull]).value_counts().to_dict()
    assert counts == {"hull": 30, "sting": 12}
    assert sum(r.status == "void" for r in hull) == 1
    angles = {r.angle_deg for r in hull if r.config == "hull"}
    assert angles == {0.0, 5.0, 10.0, 15.0, 90.0}
    assert all(r.speed * 0.353 / 1.06e-6 > 1e5 for r in hull if r.config == "hull"
               and r.angle_deg <= 30)  # fmt: skip
    accel0 = sorted(r.accel for r in hull if r.config == "hull" and r.angle_deg == 0.0
                    and r.test == "accel")  # fmt: skip
    assert accel0 == [0.25, 0.5, 1.0]
    fin = syn.fin_day_plan()
    # 10 angles (0, 2.5, 5, 7.5, 10, 15, ..., 35 deg) x 4 speeds, and 5 post tares
    assert pd.Series([r.config for r in fin]).value_counts().to_dict() == {"fin": 40, "sting": 5}
    assert {r.tare_group for r in fin} == {"post"}
    fin_runs = [r for r in fin if r.config == "fin"]
    assert sorted({r.angle_deg for r in fin_runs}) == [0.0, 2.5, 5.0, 7.5, 10.0, 15.0, 20.0,
                                                       25.0, 30.0, 35.0]
    from towtank.analysis import fins

    for v in sorted({r.speed for r in fin_runs}):  # >= 3 angles below the section's stall
        stall = float(fins.section_stall_angle(v * 0.12 / 1.06e-6))
        below = {r.angle_deg for r in fin_runs if r.speed == v and r.angle_deg < stall}
        assert len(below) >= 3 and 0.0 in below, (v, stall)
    for spec in hull + fin:  # every planned run fits the tank
        syn.plan_profile(spec.speed, spec.accel, plateau_s=spec.plateau_s)


# -------------------------------------------------------------------------------- protocols
def test_write_protocol_round_trip(tmp_path):
    path = syn.write_protocol(
        tmp_path / "p.toml",
        header="test protocol",
        campaign={"name": 'Day "1"\\x', "run_sheet": "s.csv", "data_dir": "data"},
        water={"type": "fresh", "temperature_C": 18.0},
        prototype={"length_m": 1.412, "speeds_m_s": [1.0, 2.5], "water": {"type": "sea"}},
        channels={"drag": {"column": "Fx (V)", "gain": 20.0}},
        processing={"flag": True, "n": 3, "tiny": 1e-5},
    )
    text = path.read_text()
    assert "[prototype.water]" in text
    assert 'drag = { column = "Fx (V)", gain = 20.0 }' in text
    data = tomllib.loads(text)
    assert data["campaign"]["name"] == 'Day "1"\\x'
    assert data["prototype"] == {"length_m": 1.412, "speeds_m_s": [1.0, 2.5],
                                 "water": {"type": "sea"}}  # fmt: skip
    assert data["processing"] == {"flag": True, "n": 3, "tiny": 1e-5}


FORMATS_KEYS = {
    "campaign": {"name", "run_sheet", "data_dir", "output_dir", "reference"},
    "water": {"type", "temperature_C"},
    "model": {"name", "length_m", "diameter_m", "mass_kg", "lateral_area_m2", "wetted_area_m2",
              "scale", "frontal_area_m2"},
    "fin": {"chord_m", "span_m", "section"},
    "prototype": {"length_m", "speeds_m_s", "water"},
    "channels": {"time", "speed", "drag", "lift", "accel"},
    "processing": set(),
    "vehicle": {"hull", "hull_table", "mass_kg", "cg_m", "cb_m", "inertia_kg_m2", "fins"},
}  # fmt: skip


def test_sample_protocols(tmp_path):
    paths = syn.write_sample_protocols(tmp_path)
    hull = tomllib.loads(paths[0].read_text())
    fin = tomllib.loads(paths[1].read_text())
    # only FORMATS keys, plus the extensions towtank documents in docs/formats.md (the hull
    # day shows the submergence depth and a Myring description, the fin day its position)
    extensions = {"model": {"depth_m", "myring"}, "fin": {"x_m", "linear_max_deg"},
                  "vehicle": {"name", "speed_m_s"}}
    for data in (hull, fin):
        for section, values in data.items():
            assert set(values) <= FORMATS_KEYS[section] | extensions.get(section, set()), section
    assert hull["campaign"]["run_sheet"] == "../sample_runs/sut2_hull/run_sheet.xlsx"
    assert hull["campaign"]["data_dir"] == "../sample_runs/sut2_hull/data"
    assert hull["campaign"]["output_dir"] == "../reports/sut2_hull"
    assert hull["model"]["length_m"] == 0.353 and hull["model"]["scale"] == 4.0
    assert hull["prototype"]["water"] == {"type": "sea", "temperature_C": 15.0}
    assert hull["channels"]["lift"]["gain"] == -25.0
    assert "model" not in fin and fin["fin"]["chord_m"] == 0.12 and "channels" not in fin
    for p in paths:  # the shipped protocols are these
        shipped = ROOT / "protocols" / p.name
        if shipped.exists():
            assert shipped.read_text() == p.read_text()


def test_shipped_sample_days_match_generator():
    truth_path = ROOT / "sample_runs" / "sut2_hull" / "truth.json"
    assert truth_path.exists(), "the sample days must ship in sample_runs/"
    hull = syn.load_truth(truth_path)
    assert hull["generator_version"] == syn.GENERATOR_VERSION
    assert len(hull["runs"]) == len(syn.hull_day_plan())
    data_dir = ROOT / "sample_runs" / "sut2_hull" / "data"
    assert sorted(p.name for p in data_dir.iterdir()) == sorted(
        r["file"] for r in hull["runs"].values()
    )
    sheet = pd.read_excel(ROOT / "sample_runs" / "sut2_hull" / "run_sheet.xlsx")
    assert tuple(sheet.columns) == syn.SHEET_COLUMNS + ("date",)
    assert (sheet["date"] == syn.HULL_SAMPLE_DATE).all()
    fin = syn.load_truth(ROOT / "sample_runs" / "naca0015_fin")
    assert len(fin["runs"]) == len(syn.fin_day_plan())
    fin_sheet = pd.read_csv(ROOT / "sample_runs" / "naca0015_fin" / "run_sheet.csv")
    assert tuple(fin_sheet.columns) == syn.SHEET_COLUMNS + ("date",)
    assert (fin_sheet["date"] == syn.FIN_SAMPLE_DATE).all()
    with gzip.open(data_dir / "run_001.csv.gz", "rb") as fh:
        first = pd.read_csv(io.BytesIO(fh.read()))
    assert list(first.columns)[:2] == ["Time (s)", "Carriage speed (m/s)"]


def test_sheet_date_is_optional(tmp_path):
    plan = [syn.RunSpec("sting", 0.0, 1.5, 0.5, tare_group="post")]
    plain = syn.make_fin_day(tmp_path / "plain", seed=9, runs=plan)
    dated = syn.make_fin_day(tmp_path / "dated", seed=9, runs=plan, date="2024-05-22")
    sheet = pd.read_csv(tmp_path / "plain" / "run_sheet.csv")
    assert tuple(sheet.columns) == syn.SHEET_COLUMNS  # other generated days are unchanged
    sheet = pd.read_csv(tmp_path / "dated" / "run_sheet.csv")
    assert tuple(sheet.columns) == syn.SHEET_COLUMNS + ("date",)
    assert sheet["date"].tolist() == ["2024-05-22"]
    # the date is in the sheet only: the data and the truth are the same
    assert (tmp_path / "plain" / "truth.json").read_bytes() == (
        tmp_path / "dated" / "truth.json").read_bytes()
    assert plain.runs == dated.runs
    import datetime as dt

    syn.make_hull_day(tmp_path / "hull", seed=9, runs=[syn.RunSpec("sting", 0.0, 1.5, 0.5)],
                      date=dt.date(2024, 5, 21))
    assert pd.read_excel(tmp_path / "hull" / "run_sheet.xlsx")["date"].tolist() == [
        "2024-05-21"]
    with pytest.raises(ValueError, match="ISO date"):
        syn.make_fin_day(tmp_path / "bad", seed=9, runs=plan, date="21/05/2024")


@pytest.mark.parametrize(("day", "protocol", "date"), [
    ("sut2_hull", "sut2_hull.toml", "2024-05-21"),
    ("naca0015_fin", "naca0015_fin.toml", "2024-05-22"),
])
def test_sample_days_report_date_comes_from_the_sheet(day, protocol, date):
    """The shipped days' report says "Test date: <date>", found in the run sheet's date column."""
    from towtank.ingest.protocol import load_protocol
    from towtank.ingest.runsheet import read_run_sheet
    from towtank.report import provenance

    p = load_protocol(ROOT / "protocols" / protocol)
    assert p.campaign.run_sheet.parent.name == day
    sheet = read_run_sheet(p.campaign.run_sheet, p.water.temperature_C)
    result = SimpleNamespace(protocol=p, sheet=sheet, reductions={}, report_date=None)
    assert provenance.date_from_inputs(result) == date
    source = "newest date recorded in the run sheet or run files"
    assert provenance.report_date(result) == (date, source)
