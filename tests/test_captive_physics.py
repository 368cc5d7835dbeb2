"""Captive manoeuvring tests (issue #35 items 1-5): loads, inertia removal and moment transfer,
drag/lift rotation, PMM kinematics, cycles and harmonics, the joint fit of the derivatives with
their intervals, agreement over omega', the vertical plane and the run result's arrays."""

from __future__ import annotations

import math
from dataclasses import replace
from functools import cache

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.stats import binomtest

from towtank.analysis.captive import PRIME_POWER, chi2_p_value, fit_captive
from towtank.errors import RunError
from towtank.reduce.captive import (
    REGRESSORS,
    CaptiveRun,
    RunSetting,
    body_kinematics,
    drag_lift_to_body,
    hydrodynamic_loads,
    upward_crossings,
)
from towtank.stats.quantiles import t_quantile
from towtank.testing.captive import (
    HORIZONTAL_SYMBOLS,
    VERTICAL_SYMBOLS,
    CaptiveRunSpec,
    CaptiveTruth,
    captive_day_plan,
    make_captive_day,
    pmm_motion,
    reduce_simulated,
    simulate_captive_run,
    simulated_runs,
)
from towtank.testing.instruments import Noise

RHO, L = 998.6, 1.33


@cache
def day_runs(seed: int = 1, plane: str = "horizontal", slope: float = 0.0):
    """The truth and the generated day's runs, simulated once per session for the fits that
    share them."""
    truth = CaptiveTruth.vertical() if plane == "vertical" else CaptiveTruth(
        frequency_slope={"Y_vdot": slope} if slope else {})
    return truth, simulated_runs(truth, seed=seed)


@cache
def day_fit(seed: int = 1, plane: str = "horizontal", slope: float = 0.0):
    truth, runs = day_runs(seed, plane, slope)
    return truth, runs, fit_captive(runs, rho=RHO, length_m=L, plane=plane,
                                    draught_m=0.19)


# ============================================================================ hand numbers

def test_inertia_removal_and_moment_transfer_by_hand():
    """m = 30, I_zG = 3, x_G = 0.1, x_B = 0.2; u = 2, v = 0.1, r = 0.5, u' = 0.3, v' = -0.4,
    r' = 0.6; fx = 1, fy = 2, mz = 3:
    X = 1 + 30 (0.3 - 0.05 - 0.025) = 7.75;
    Y = 2 + 30 (-0.4 + 1.0 + 0.06) = 21.8;
    N = 3 + 0.2*2 + (3 + 0.3) 0.6 + 30*0.1 (-0.4 + 1.0) = 3 + 0.4 + 1.98 + 1.8 = 7.18."""
    kin = {k: np.array([x]) for k, x in
           (("u", 2.0), ("v", 0.1), ("r", 0.5), ("udot", 0.3), ("vdot", -0.4), ("rdot", 0.6))}
    X, Y, N = hydrodynamic_loads(np.array([1.0]), np.array([2.0]), np.array([3.0]), kin,
                                 mass_kg=30.0, izz_kg_m2=3.0, xg_m=0.1, balance_x_m=0.2)
    assert X[0] == pytest.approx(7.75) and Y[0] == pytest.approx(21.8)
    assert N[0] == pytest.approx(7.18)


def test_drag_and_lift_rotate_into_body_axes():
    """At beta = 0 fx = -drag, fy = lift; at 90 deg fx = lift, fy = drag; at 30 deg by hand."""
    fx, fy = drag_lift_to_body(2.0, 1.0, 0.0)
    assert (fx, fy) == pytest.approx((-2.0, 1.0))
    fx, fy = drag_lift_to_body(2.0, 1.0, math.pi / 2)
    assert (fx, fy) == pytest.approx((1.0, 2.0))
    fx, fy = drag_lift_to_body(2.0, 1.0, math.radians(30))
    assert fx == pytest.approx(-2 * math.sqrt(3) / 2 + 0.5)
    assert fy == pytest.approx(1.0 + math.sqrt(3) / 2)


def test_pure_sway_and_pure_yaw_kinematics():
    """Pure sway: v = y', r = 0, u = U. Pure yaw with tan(psi) = y'/U: v = 0 at O."""
    t = np.linspace(0, 4, 401)
    U, y0, w = 1.5, 0.1, 2.0
    yd, ydd = y0 * w * np.cos(w * t), -y0 * w * w * np.sin(w * t)
    sway = body_kinematics(U, 0.0, y_dot=yd, y_ddot=ydd)
    assert np.allclose(sway["v"], yd) and np.allclose(sway["u"], U)
    assert np.allclose(sway["r"], 0) and np.allclose(sway["vdot"], ydd)
    psi = np.arctan(yd / U)
    psid = np.gradient(psi, t)
    yaw = body_kinematics(U, psi, psi_dot=psid, y_dot=yd, y_ddot=ydd)
    assert np.max(np.abs(yaw["v"])) < 1e-12
    assert np.allclose(yaw["r"], psid)


# ===================================================================================== PMM

def _sway_run(**kw):
    spec = CaptiveRunSpec(run=1, test="sway", amplitude_m=0.1, frequency_hz=0.3, **kw)
    truth = CaptiveTruth()
    return spec, truth, simulate_captive_run(spec, truth, rng=3)


def test_pmm_cycles_drop_the_ramps_and_need_three():
    """Two ramp-in and two ramp-out cycles around 4 steady ones: the 4 are kept; with 2
    steady cycles the run is rejected with the shared sentence."""
    spec, truth, frame = _sway_run(steady_cycles=4, ramp_cycles=2)
    run = reduce_simulated(frame, spec, truth)
    assert run.cycles_used == 4 and len(run.cycles) == 4
    assert run.frequency_hz == pytest.approx(0.3, rel=1e-3)
    assert run.amplitude_m == pytest.approx(0.1, rel=1e-3)
    spec, truth, frame = _sway_run(steady_cycles=2, ramp_cycles=2)
    with pytest.raises(RunError, match=r"has 2 whole steady PMM cycles; at least 3 are needed "
                                       r"\(ramp-in and ramp-out cycles are dropped\)"):
        reduce_simulated(frame, spec, truth)


@pytest.mark.parametrize(("field", "value", "what"), [
    ("frequency_hz", 0.33, "frequency"), ("amplitude_m", 0.107, "amplitude")])
def test_pmm_motion_checked_against_the_sheet(field, value, what):
    """A run whose sway is 10 % / 7 % off the sheet's frequency / amplitude is rejected naming
    both values; 3 % off is accepted."""
    spec, truth, frame = _sway_run()
    sheet = CaptiveRunSpec(**{**spec.__dict__, field: value})
    with pytest.raises(RunError, match=what) as err:
        reduce_simulated(frame, sheet, truth)
    assert f"{value:g}" in str(err.value)
    close = CaptiveRunSpec(**{**spec.__dict__, field: getattr(spec, field) * 1.03})
    assert reduce_simulated(frame, close, truth).cycles_used == 5


def test_upward_crossings_ignore_noise_around_zero():
    t = np.linspace(0, 10, 10001)
    y = np.sin(2 * np.pi * 0.5 * t) + 0.01 * np.sin(2 * np.pi * 400 * t)
    c = upward_crossings(t, y, 0.1)
    assert np.allclose(np.diff(c), 2.0, atol=1e-3) and c.size == 5


def test_harmonics_of_a_pure_sway_run_match_the_truth():
    """Quiet channels: the in-phase Y of pure sway is Y_vdot v' + inertia-free, i.e.
    -(Y_vdot) y0 omega^2 (plus Y_v|v|'s first harmonic in the quadrature part)."""
    from towtank.testing.instruments import Noise

    spec = CaptiveRunSpec(run=1, test="sway", amplitude_m=0.1, frequency_hz=0.3)
    truth = CaptiveTruth()
    run = reduce_simulated(simulate_captive_run(spec, truth, noise=Noise.quiet()), spec, truth)
    rows = run.rows.set_index("component")
    w = 2 * math.pi * 0.3
    assert rows.at["sin", "Y"] == pytest.approx(-truth.derivatives["Y_vdot"] * 0.1 * w * w,
                                                rel=1e-4)
    v0 = 0.1 * w
    expected_cos = (truth.derivatives["Y_uv"] * 1.5 * v0
                    + truth.derivatives["Y_v|v|"] * 8 / (3 * math.pi) * v0 * v0)
    assert rows.at["cos", "Y"] == pytest.approx(expected_cos, rel=1e-3)
    assert len(run.period) == 72 and run.period["v"].abs().max() == pytest.approx(v0, rel=1e-2)


def _quiet_yaw_runs():
    from towtank.testing.instruments import Noise

    plan = [CaptiveRunSpec(run=1, test="yaw", amplitude_m=0.1, frequency_hz=0.2),
            CaptiveRunSpec(run=2, test="yaw", amplitude_m=0.2, frequency_hz=0.35)]
    return CaptiveTruth(), simulated_runs(CaptiveTruth(), plan=plan, noise=Noise.quiet())


def test_quiet_pure_yaw_loads_are_the_truth_of_the_reduced_regressors():
    """Noise-free pure yaw (psi0 = 0.03 and 0.29 rad): each component of the reduced N and Y
    equals the truth's derivatives times the same components of the reduced regressors, to
    1e-4 of the run's largest component (the step of r' where the ramp ends stays outside
    the kept cycles: before, N's cos part was 0.19 % high and its mean 15 % off)."""
    truth, runs = _quiet_yaw_runs()
    for run in runs:
        rows = run.rows.set_index("component")
        for q in ("Y", "N"):
            pred = sum(truth.derivatives.get(f"{q}_{k}", 0.0) * rows[k] for k in REGRESSORS)
            scale = rows[q].abs().max()
            assert np.allclose(rows[q], pred, rtol=0.0, atol=1e-4 * scale), (run.run, q)


def test_quiet_pure_yaw_cycles_are_alike():
    """Noise-free pure yaw: the first and last kept cycles (next to the ramps) give the same
    harmonics of N as the middle ones, to 1e-4 (before, 0.5 % apart)."""
    _, runs = _quiet_yaw_runs()
    for run in runs:
        for col in ("N_in", "N_quad", "Y_in", "Y_quad"):
            x = run.cycles[col].to_numpy()
            assert np.ptp(x) <= 1e-4 * np.max(np.abs(x)), (run.run, col, x)


def test_generated_yaw_rate_derivative_is_exact():
    """The generator's psi'' is the time derivative of its psi' at every sample, the ends of
    the ramps (where psi'' steps) included."""
    spec = CaptiveRunSpec(run=1, test="yaw", amplitude_m=0.2, frequency_hz=0.35)
    t, h, t0 = np.arange(0.0, 30.0, 0.01), 1e-6, 2.003  # no sample within h of a ramp's end
    mo = pmm_motion(t, spec, t0, 1.5)
    ahead, behind = pmm_motion(t + h, spec, t0, 1.5), pmm_motion(t - h, spec, t0, 1.5)
    diff = (ahead["psi1"] - behind["psi1"]) / (2 * h)
    assert np.allclose(mo["psi2"], diff, rtol=0.0, atol=1e-6)


def test_bad_settings_are_one_sentence():
    for row, match in [({"test": "drift", "drift_deg": 95}, "beyond"),
                       ({"test": "arm", "radius_m": 0}, "radius"),
                       ({"test": "sway", "pmm_frequency_hz": 0.3}, "pmm_amplitude_m"),
                       ({"test": "spin"}, "not a captive test")]:
        with pytest.raises(RunError, match=match):
            RunSetting.from_row(row)


# ================================================================================ the fit

def test_joint_fit_recovers_remus():
    """Every one of the 14 derivatives within 1 % of Prestero's REMUS values (Y_r|r|, weakly
    excited, within 2 %) and inside its 95 % interval."""
    truth, _, fit = day_fit()
    for s in HORIZONTAL_SYMBOLS:
        e, true = fit.estimates[s], truth.derivatives[s]
        tol = 0.02 if s == "Y_r|r|" else 0.01
        assert e.value == pytest.approx(true, rel=tol), s
        assert e.ci_low <= true <= e.ci_high, s
    table = fit.table()
    assert {"prime", "prime_LT", "ci_low", "method", "dof", "n_runs"} <= set(table.columns)
    row = table.set_index("symbol").loc["N_rdot"]
    assert row["prime"] == pytest.approx(row["value"] / (0.5 * RHO * L**5))
    assert row["prime_LT"] == pytest.approx(row["value"] / (0.5 * RHO * 0.19 * L**4))
    assert "pure yaw" in row["method"] and "static drift" not in row["method"]
    assert table.set_index("symbol").at["Y_uudr", "method"] == "rudder"


def test_nonlinear_terms_do_not_leak_into_linear_ones():
    """Large-amplitude pure sway only (v up to 0.6 m/s, Y_v|v| v|v| a third of Y): Y_uv
    still comes out right because v|v|'s harmonics are columns of the same fit."""
    truth = CaptiveTruth()
    plan = [CaptiveRunSpec(run=i + 1, test="sway", amplitude_m=a, frequency_hz=f)
            for i, (a, f) in enumerate([(0.3, 0.3), (0.3, 0.2), (0.2, 0.35), (0.1, 0.3)])]
    runs = simulated_runs(truth, seed=5, plan=plan)
    fit = fit_captive(runs, rho=RHO, length_m=L)
    assert fit.estimates["Y_uv"].value == pytest.approx(truth.derivatives["Y_uv"], rel=0.01)
    assert fit.estimates["Y_v|v|"].value == pytest.approx(truth.derivatives["Y_v|v|"],
                                                          rel=0.02)
    assert any("Y_ur" in n and "not determined" in n for n in fit.warnings)


def test_one_drift_angle_cannot_separate_uv_from_v_abs_v():
    truth = CaptiveTruth()
    plan = [CaptiveRunSpec(run=i + 1, test="drift", drift_deg=8) for i in range(3)]
    fit = fit_captive(simulated_runs(truth, seed=2, plan=plan), rho=RHO, length_m=L)
    assert any("not separable" in n and "Y_v|v|" in n for n in fit.warnings)
    assert "Y_v|v|" not in fit.estimates


def test_frequency_agreement_said():
    """A frequency-independent truth: the derivatives agree; a Y_vdot that changes by 8 kg
    per unit omega': Y_vdot differs."""
    _, _, fit = day_fit()
    sentence = next(n for n in fit.notes if n.startswith("Y_vdot from"))
    assert not any(n.startswith("Y_vdot from") for n in fit.warnings)
    assert ": agree (chi^2 = " in sentence and "omega'" in sentence and "y0" in sentence
    _, _, fit = day_fit(slope=8.0)
    sentence = next(n for n in fit.warnings if n.startswith("Y_vdot from"))
    assert ": differ (" in sentence
    assert set(fit.by_run["symbol"]) >= {"Y_vdot", "N_vdot", "Y_rdot", "N_rdot"}


def test_vertical_plane_gives_prestero_vertical_derivatives():
    """A REMUS day with the model rolled +90 deg: Z_uw, M_uw, ... with their signs."""
    truth, _, fit = day_fit(plane="vertical")
    for s in VERTICAL_SYMBOLS:
        e, true = fit.estimates[s], truth.derivatives[s]
        tol = 0.02 if s == "Z_q|q|" else 0.01
        assert e.value == pytest.approx(true, rel=tol), s
    assert fit.estimates["Z_uw"].value == pytest.approx(-28.6, rel=0.01)
    assert fit.estimates["M_uw"].value == pytest.approx(24.0, rel=0.01)
    assert fit.estimates["Z_uq"].value == pytest.approx(-5.22, rel=0.01)


def test_pmm_table():
    _, runs, fit = day_fit()
    pmm = fit.pmm_table()
    assert len(pmm) == sum(r.test in ("sway", "yaw", "yaw_drift") for r in runs)
    row = pmm.iloc[0]
    assert row["omega_prime"] == pytest.approx(2 * math.pi * row["frequency_hz"] * L / 1.5,
                                               rel=1e-3)
    assert row["cycles_used"] == 5


def _coverage(seeds):
    inside = total = 0
    for seed in seeds:
        truth, _, fit = day_fit(seed=seed)
        for s in HORIZONTAL_SYMBOLS:
            e = fit.estimates[s]
            inside += e.ci_low <= truth.derivatives[s] <= e.ci_high
            total += 1
    return inside, total


@pytest.mark.heavy
def test_coverage_short():
    """6 generated days x 14 derivatives: the fraction of 95 %
    intervals holding the truth has a Clopper-Pearson interval that holds 0.95 (the long
    study is test_coverage_study)."""
    inside, total = _coverage(range(1, 7))
    ci = binomtest(inside, total).proportion_ci()
    assert ci.low <= 0.95 <= ci.high, (inside, total)


@pytest.mark.slow
def test_coverage_study():
    """100 generated days: each derivative's 95 % interval holds the truth on a fraction whose
    Clopper-Pearson interval holds 0.95 (N_rdot 96/100 [0.90, 0.99], all 14 1351/1400), and
    the chi^2 warning of model error fires on at most 4 of the 100 matched days (nominal 1 %
    per equation)."""
    truth = CaptiveTruth()
    inside = dict.fromkeys(HORIZONTAL_SYMBOLS, 0)
    warned = 0
    for seed in range(100, 200):
        fit = fit_captive(simulated_runs(truth, seed=seed), rho=RHO, length_m=L)
        warned += any("reduced chi^2" in w for w in fit.warnings)
        for s in HORIZONTAL_SYMBOLS:
            e = fit.estimates[s]
            inside[s] += e.ci_low <= truth.derivatives[s] <= e.ci_high
    for s, k in inside.items():
        ci = binomtest(k, 100).proportion_ci()
        assert ci.low <= 0.95 <= ci.high, (s, k)
    assert warned <= 4, warned


def test_pmm_only_derivatives_take_the_dof_of_their_cycles():
    """A derivative only PMM rows carry (5 cycles, 4 dof each) gets the Welch-Satterthwaite
    dof of those rows (about 10) and a t quantile to match; one the static runs carry keeps
    dozens; every interval is value -/+ t(dof) SE."""
    _, _, fit = day_fit()
    for s in ("Y_vdot", "N_vdot", "Y_rdot", "N_rdot"):
        assert 4 <= fit.estimates[s].dof < 20, (s, fit.estimates[s].dof)
    assert fit.estimates["Y_uv"].dof > 30
    for e in fit.estimates.values():
        half = (e.ci_high - e.ci_low) / 2
        assert half == pytest.approx(t_quantile(e.dof) * e.std_error, rel=1e-9)


def test_chi2_of_few_cycle_weights_is_heavier_tailed_than_chi2():
    """40 rows weighted by variances from 4 dof: the chi^2 distribution's 99 % point on 40
    dof is exceeded far more often than 1 % (t^2 on 4 dof has no variance); the p value of
    the right null is then well above 0.01, and a sum far out is still rejected."""
    from scipy.stats import chi2

    lev, dof = np.full(40, 0.0), np.full(40, 4.0)
    assert chi2_p_value(float(chi2.ppf(0.99, 40)), lev, dof) > 0.05
    assert chi2_p_value(1000.0, lev, dof) < 0.01


def test_n_rdot_of_generated_yaw_runs_inside_its_interval():
    """N_rdot within 0.05 % of the truth and inside its 95 % interval."""
    truth, _, fit = day_fit()
    e, true = fit.estimates["N_rdot"], truth.derivatives["N_rdot"]
    assert e.value == pytest.approx(true, rel=5e-4)
    assert e.ci_low <= true <= e.ci_high


@pytest.mark.heavy
def test_reduced_chi2_near_one_when_the_truth_is_the_model():
    """The rows' variances hold the zero's and the motion channels' scatter: 5 generated days
    of the model's own truth give reduced chi^2 within 0.5-1.6 (56 dof) and no chi^2
    warning; the same days with Y_vdot and N_rdot that change with omega' (a term the model
    lacks) give chi^2 far above 1 and the warning."""
    for seed in range(1, 6):
        _, _, fit = day_fit(seed=seed)
        assert all(0.5 < c < 1.6 for c in fit.chi2_reduced.values()), fit.chi2_reduced
        assert not any("reduced chi^2" in w for w in fit.warnings)
    _, _, fit = day_fit(slope=8.0)
    assert fit.chi2_reduced["Y"] > 10
    assert any(w.startswith("Y: reduced chi^2") for w in fit.warnings)


def test_static_run_standard_error_holds_the_zeros_uncertainty():
    """40 draws of one rudder run: the mean of ((Y - Y_truth) / Y_se)^2 is near Student's
    7-dof 1.4 once the still windows' uncertainty of the zero is in Y_se (the steady
    window's block means alone give about 6)."""
    truth = CaptiveTruth()
    spec = CaptiveRunSpec(run=1, test="rudder", rudder_deg=10)
    z2 = []
    for seed in range(40):
        run = reduce_simulated(simulate_captive_run(spec, truth, rng=seed), spec, truth)
        row = run.rows.iloc[0]
        true = sum(truth.derivatives[f"Y_{k}"] * row[k] for k in ("uv", "uudr", "uu"))
        z2.append(((row["Y"] - true) / row["Y_se"]) ** 2)
    assert 0.6 < np.mean(z2) < 2.4, np.mean(z2)


# ============================================================================ arrays, files

def test_from_arrays_round_trips_and_rejects_malformed():
    _, runs, _ = day_fit()
    for run in (runs[0], next(r for r in runs if r.test == "yaw")):
        back = CaptiveRun.from_arrays(run.run, run.file, run.to_arrays())
        pd.testing.assert_frame_equal(back.rows, run.rows)
        pd.testing.assert_frame_equal(back.cycles, run.cycles, check_dtype=False)
        pd.testing.assert_frame_equal(back.period, run.period)
        assert back.notes == run.notes and back.test == run.test
    arrays = runs[0].to_arrays()
    bad = [{**arrays, "rows": arrays["rows"][:, :5]}, {**arrays, "scalars": arrays["scalars"][:3]},
           {k: v for k, v in arrays.items() if k != "period"},
           {**arrays, "notes": np.array([300.0])}, {**arrays, "rows": np.array(["x"])}]
    for a in bad:
        with pytest.raises(ValueError, match="malformed captive arrays"):
            CaptiveRun.from_arrays(1, "f", a)


@settings(max_examples=40, deadline=None)
@given(test=st.sampled_from(["drift", "arm"]), speed=st.floats(0.1, 5),
       values=st.lists(st.floats(-1e6, 1e6), min_size=14, max_size=14),
       notes=st.lists(st.text(alphabet=st.characters(blacklist_characters="\x00",
                                                     blacklist_categories=("Cs",))),
                      max_size=3))
def test_arrays_round_trip_exactly(test, speed, values, notes):
    from towtank.reduce.captive import CYCLE_COLUMNS, PERIOD_COLUMNS, ROW_COLUMNS, _empty

    rows = pd.DataFrame([["mean", *values]], columns=list(ROW_COLUMNS))
    run = CaptiveRun(run=3, file="r.csv", test=test, plane="horizontal", speed=speed,
                     drift_deg=2.0, rudder_deg=math.nan, radius_m=4.0, frequency_hz=math.nan,
                     amplitude_m=math.nan, cycles_used=0, rows=rows,
                     cycles=_empty(CYCLE_COLUMNS), period=_empty(PERIOD_COLUMNS),
                     notes=tuple(notes))
    back = CaptiveRun.from_arrays(3, "r.csv", run.to_arrays())
    pd.testing.assert_frame_equal(back.rows, run.rows)
    assert back.notes == run.notes and back.speed == speed


@pytest.mark.parametrize("layout", ["csv-units", "lvm"])
def test_make_captive_day_writes_protocol_sheet_and_files(tmp_path, layout):
    plan = captive_day_plan()[:2]
    make_captive_day(tmp_path, layout=layout, plan=plan)
    assert (tmp_path / "protocol.toml").is_file()
    sheet = pd.read_csv(tmp_path / "run_sheet.csv")
    assert list(sheet["test"]) == ["drift", "drift"]
    files = sorted((tmp_path / "data").iterdir())
    assert len(files) == 2 and all(f.stat().st_size > 1000 for f in files)


@pytest.mark.heavy
def test_pmm_derivatives_of_a_frequency_independent_truth_agree_over_omega():
    """The agreement over omega' (issue 35 item 3) takes a run's standard error from the
    covariance of its load AND its regressors: the yaw channel's noise enters N through the
    inertia removed (I_z r') and the regressor r' together, so the load's scatter alone is
    (I_z - N_rdot)/I_z ~ 2.4 times too small and 10 generated days said "differ" 34 times.
    Now the REMUS truth, whose derivatives do not depend on frequency, agrees on every day
    (measured: 0 "differ" lines over 52 days)."""
    # the fits of seeds 1-6 are those of test_coverage_short: made once for both. The
    # agreement over omega' depends on the runs, rho and the length only (not on the draught
    # day_fit gives), and simulated_result's CaptiveResult carries the fit's warnings as they are
    differ = [w for seed in range(10) for w in day_fit(seed)[2].warnings if ": differ (" in w]
    assert len(differ) <= 1, differ


# ======================================================== the point the derivatives refer to

def test_a_means_row_about_the_balance_point_by_hand():
    """The balance 0.5 m ahead of O, m = 30 kg, x_G = 0.1 m; a static drift row (beta = 4 deg)
    and a rotating-arm row (R = 5 m, U = 1.5 m/s: r = 0.3 rad/s, u r = 0.45 m/s^2), each with
    fy = 4 N, mz = 1 N m. About O: N = mz + x_B fy = 3 N m (drift) and, the arm's
    centripetal inertia m x_G u r = 1.35 N m added, 4.35 N m; v = 0 on the arm. About the
    balance point P = B: N = mz = 1 N m (drift) and 1 + 30 (0.1 - 0.5) 0.45 = -4.4 N m
    (= N_O - x_B Y with Y = 4 + 30 * 0.45 = 17.5 N), and the arm's v_B = x_B r = 0.15 m/s
    (u v = 0.225 m^2/s^2)."""
    from towtank.analysis.captive import captive_runs_from_means
    from towtank.reduce.captive import reference_x

    table = pd.DataFrame({"run": [1, 2], "drift_deg": [4.0, 0.0], "rudder_deg": [0.0, 0.0],
                          "radius_m": [math.nan, 5.0], "speed": [1.5, 1.5], "fx": [0.0, 0.0],
                          "fy": [4.0, 4.0], "mz": [1.0, 1.0]})

    def rows(moment_ref: str) -> pd.DataFrame:
        runs = captive_runs_from_means(table, balance_x_m=0.5, mass_kg=30.0, xg_m=0.1,
                                       ref_x_m=reference_x(moment_ref, 0.5))
        return pd.concat([r.rows for r in runs], ignore_index=True)

    o, b = rows("origin"), rows("balance")
    assert o["N"].tolist() == pytest.approx([3.0, 4.35])
    assert b["N"].tolist() == pytest.approx([1.0, -4.4])
    assert o["Y"].tolist() == pytest.approx([4.0, 17.5]) and b["Y"].tolist() == o["Y"].tolist()
    assert o.at[1, "uv"] == pytest.approx(0.0, abs=1e-15)
    assert b.at[1, "uv"] == pytest.approx(1.5 * 0.15)
    assert b.at[0, "uv"] == pytest.approx(o.at[0, "uv"])  # no yaw rate: v_B = v
    assert reference_x("balance", None) == 0.0 and reference_x("origin", 0.5) == 0.0


def _scaled_programme(length_m: float) -> tuple[CaptiveTruth, list[CaptiveRunSpec]]:
    """The REMUS truth and a ship-like programme (static drift 4-16 deg, rudder 10-20 deg,
    pure sway v' = 0.05, 0.1 and pure yaw r' = 0.1, 0.2, both at omega' = 2, no rotating
    arm) made for a model of ``length_m`` by Froude similarity from the 1.33 m REMUS at
    0.9 m/s: every prime and every non-dimensional setting the same at any length."""
    lam = length_m / L
    base = CaptiveTruth()
    power = {s: PRIME_POWER[s.split("_", 1)[1]][int(s[0] in "NM")] for s in base.derivatives}
    truth = replace(base, derivatives={s: v * lam ** power[s]
                                       for s, v in base.derivatives.items()},
                    mass_kg=base.mass_kg * lam**3, izz_kg_m2=base.izz_kg_m2 * lam**5,
                    iyy_kg_m2=base.iyy_kg_m2 * lam**5, xg_m=base.xg_m * lam,
                    balance_x_m=base.balance_x_m * lam, length_m=length_m,
                    X_uu=base.X_uu * lam**2, X_vv=base.X_vv * lam**2, X_rr=base.X_rr * lam**4)
    speed = 0.9 * math.sqrt(lam)
    omega = 2.0 * speed / length_m  # omega' = 2
    f = omega / (2.0 * math.pi)
    specs: list[dict] = [{"test": "drift", "drift_deg": b} for b in (-16, -12, -8, -4, 4, 8, 12,
                                                                      16)]
    specs += [{"test": "rudder", "rudder_deg": d} for d in (-20, -10, 10, 20)]
    specs += [{"test": "sway", "amplitude_m": vp * speed / omega, "frequency_hz": f}
              for vp in (0.05, 0.1)]
    # pure yaw: r0 = psi0 omega with tan(psi0) = y0 omega / U; r' = r0 L / U
    specs += [{"test": "yaw", "frequency_hz": f,
               "amplitude_m": speed * math.tan(rp * speed / length_m / omega) / omega}
              for rp in (0.1, 0.2)]
    return truth, [CaptiveRunSpec(run=i + 1, speed=speed, **s) for i, s in enumerate(specs)]


@pytest.mark.parametrize("length_m", [1.33, 6.8279])
def test_which_derivatives_are_determined_does_not_depend_on_the_models_size(length_m):
    """The same non-dimensional programme on the 1.33 m REMUS and on a 6.83 m model (KVLCC2's
    length), Froude-scaled, without noise: all 14 derivatives determined at both sizes, their
    primes within 1 % of the truth's, and no "not determined" warning. Judged in SI, r|r|
    [rad^2/s^2] beside u^2 [m^2/s^2] fell below the excitation threshold on the long model
    (pure yaw r' <= 0.034 L counted as noise): Y_r|r| and N_r|r| were left out, the yaw-rate
    derivatives took their part (Y_ur', N_ur' 7.6 % off) and the warning said that no
    yaw-rate run excited them."""
    truth, plan = _scaled_programme(length_m)
    runs = simulated_runs(truth, plan=plan, noise=Noise.quiet(), fs=20.0)
    fit = fit_captive(runs, rho=RHO, length_m=length_m)
    assert not [w for w in fit.warnings if "not determined" in w], fit.warnings
    for s in HORIZONTAL_SYMBOLS:
        e = fit.estimates[s]
        true_prime = truth.derivatives[s] / e.scale
        assert e.prime == pytest.approx(true_prime, rel=0.01, abs=1e-6), s
