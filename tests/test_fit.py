"""Hull coefficients against the SUT-2 truth (issue 3, "Done when").

Synthetic SUT-2 days at realistic noise give the twelve coefficients; their errors, their 95 %
intervals (per seed and as a coverage rate over many seeds), the prime values and the diff %
against REMUS (Table 4 arithmetic), the report's curve-difference cross-check, the coefficients a
day cannot support, and the filter pitfall of METHOD.md are tested here.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from conftest import Day, SeedResult, process, write_hull_protocol
from hypothesis import given, settings
from hypothesis import strategies as st

from towtank import conditioning, fit
from towtank import synthetic as syn

# |error| / |truth| allowed per coefficient [-] (the mirrored Z/X twins equal their sources)
TOLERANCE = {
    "X_udot": 0.05,
    "Y_vdot": 0.02,
    "X_u|u|": 0.01,
    "Y_uv": 0.01,
    "Y_v|v|": 0.015,
    "X_uv": 0.20,
    "X_v|v|": 0.35,
}
MIRROR = {"Z_wdot": "Y_vdot", "X_uw": "X_uv", "X_w|w|": "X_v|v|", "Z_uw": "Y_uv",
          "Z_w|w|": "Y_v|v|"}
INTERVAL_SYMBOLS = ("X_udot", "Y_vdot", "X_u|u|", "Y_v|v|", "X_uv")

TOLERANCE_SEEDS = (0, 1, 2, 3, 4)
# Per-seed interval check. A 95 % interval misses its truth in 1 of 20 days, so five intervals
# on three days miss somewhere about half the time at exactly nominal coverage: the seeds are
# fixed. Of seeds 0-4, seed 1 (X_uv, -9.9 %) and seed 4 (Y_vdot, +0.6 %) have one interval
# each that misses; the rate of such misses is what test_interval_coverage measures.
INTERVAL_SEEDS = (0, 2, 3)
COVERAGE_SEEDS = tuple(range(30))
COVERAGE_FS = 100.0  # [Hz]: noise densities are fs-independent, so this is as realistic


def _rel_error(res: SeedResult, symbol: str) -> float:
    truth = res.truth[symbol]
    return (float(res.coefficients.loc[symbol, "value"]) - truth) / abs(truth)


def _inside(res: SeedResult, symbol: str) -> bool:
    row = res.coefficients.loc[symbol]
    return bool(row["ci_low"] <= res.truth[symbol] <= row["ci_high"])


# ----------------------------------------------------------------------- accuracy, intervals
@pytest.mark.parametrize("seed", TOLERANCE_SEEDS)
def test_coefficients_within_tolerance(seed_result, seed):
    res = seed_result(seed)
    assert res.rejected == {}
    assert set(res.coefficients.index) == set(fit.SYMBOLS)
    errors = {s: _rel_error(res, s) for s in TOLERANCE}
    for symbol, tol in TOLERANCE.items():
        assert abs(errors[symbol]) <= tol, (symbol, f"{100 * errors[symbol]:+.2f} %")
    for twin, source in MIRROR.items():
        assert res.coefficients.loc[twin, "value"] == res.coefficients.loc[source, "value"]
    # SNAME signs: added mass and damping negative, X_v|v| positive for SUT-2
    for s in ("X_udot", "Y_vdot", "X_u|u|", "Y_uv", "Y_v|v|"):
        assert res.coefficients.loc[s, "value"] < 0


@pytest.mark.parametrize("seed", INTERVAL_SEEDS)
def test_truth_inside_95_percent_interval(seed_result, seed):
    res = seed_result(seed)
    for symbol in INTERVAL_SYMBOLS:
        row = res.coefficients.loc[symbol]
        assert row["ci_low"] < row["value"] < row["ci_high"]
        assert _inside(res, symbol), (
            symbol, res.truth[symbol], (row["ci_low"], row["ci_high"]))


def test_interval_coverage(seed_result):
    """Over 30 seeds the 95 % intervals hold the truth in 85-100 % of the days, per coefficient.

    Measured (30 seeds, 100 Hz): see the report of this test set; X_udot's interval is
    dominated by the stated 0.5 g uncertainty of the weighed mass, hence its full coverage.
    """
    results = [seed_result(s, COVERAGE_FS) for s in COVERAGE_SEEDS]
    coverage = {
        s: float(np.mean([_inside(r, s) for r in results])) for s in INTERVAL_SYMBOLS
    }
    print("coverage:", {s: round(c, 3) for s, c in coverage.items()})
    for symbol, c in coverage.items():
        assert 0.85 <= c <= 1.0, (symbol, c)
    # and the estimates stay within tolerance on every one of those days too
    for r in results:
        for symbol, tol in TOLERANCE.items():
            assert abs(_rel_error(r, symbol)) <= tol, (r.seed, symbol, _rel_error(r, symbol))


# ----------------------------------------------------------------------- primes, diff % (T4)
def _table4() -> pd.DataFrame:
    from importlib import resources

    with resources.files("towtank").joinpath("data", "sut2_table4.csv").open() as fh:
        return pd.read_csv(fh, comment="#")


def _hullfit_from_primes(primes: dict[str, float], rho: float, length: float) -> fit.HullFit:
    estimates = {}
    for s, p in primes.items():
        k = 3 if fit.KIND[s] == "added_mass" else 2
        value = p * 0.5 * rho * length**k
        se = abs(value) * 0.01
        estimates[s] = fit.Estimate(s, value, se, value - 1.96 * se, value + 1.96 * se,
                                    "Table 4", 1)
    return fit.HullFit(estimates=estimates, rho=rho, length=length, mass=0.552,
                       added_mass={}, damping=None, repeats=pd.DataFrame(), messages=[])


def test_prime_values_and_table4_diff_pct():
    """Table 4's SUT-2 primes as estimates: prime = value/(½ρL³) or /(½ρL²), and diff % against
    the built-in REMUS reference is Table 4's printed column (printed unsigned, "***" for X_uv
    whose REMUS value is 0)."""
    t4 = _table4()
    rho, length = 998.6, 0.353
    primes = dict(zip(t4["symbol"], t4["sut2_prime"], strict=True))
    ref = fit.load_reference("remus")
    assert ref == pytest.approx(dict(zip(t4["symbol"], t4["remus_prime"], strict=True)))
    table = fit.coefficients_table(_hullfit_from_primes(primes, rho, length), ref)
    table = table.set_index("symbol")
    assert list(table.index) == list(fit.SYMBOLS)
    for s, row in table.iterrows():
        k = 3 if s.endswith("dot") else 2
        assert row["prime"] == pytest.approx(row["value"] / (0.5 * rho * length**k), rel=1e-12)
        assert row["prime"] == pytest.approx(primes[s], rel=1e-12)
        assert row["unit"] == ("kg" if k == 3 else "kg/m")
        assert row["reference_prime"] == ref[s]
        printed = t4.set_index("symbol").loc[s, "diff_pct"]
        if ref[s] == 0:
            assert math.isnan(row["diff_pct"]) and math.isnan(printed)
        else:
            assert abs(row["diff_pct"]) == pytest.approx(printed, abs=0.006), s
            # signed as FORMATS: (value - ref)/|ref|·100
            assert row["diff_pct"] == pytest.approx(
                (primes[s] - ref[s]) / abs(ref[s]) * 100, rel=1e-12)
    printed = {"X_udot": 1.83, "Y_vdot": 6.90, "X_u|u|": 4.07, "Y_v|v|": 4.00, "X_v|v|": 3.00}
    for s, v in printed.items():
        assert round(abs(table.loc[s, "diff_pct"]), 2) == v
    # the signs: SUT-2's added mass is larger than REMUS's, its axial drag smaller
    assert table.loc["X_udot", "diff_pct"] < 0 < table.loc["X_u|u|", "diff_pct"]


def test_model_scale_values_quoted_in_the_report():
    """Table 4's note: -X_udot = 0.017 kg, -Y_vdot = 0.682 kg at L = 0.353 m (fresh water)."""
    truth = syn.sut2_hull_truth(999.1)
    coef = truth.coefficients(999.1)
    assert -coef["X_udot"] == pytest.approx(0.017, abs=0.0005)
    assert -coef["Y_vdot"] == pytest.approx(0.682, abs=0.002)


def test_prime_values_of_a_generated_day(hull_day: Day):
    table = hull_day.result.hull.coefficients.set_index("symbol")
    rho, length = hull_day.result.hull.fit.rho, 0.353
    for s, row in table.iterrows():
        k = 3 if s.endswith("dot") else 2
        assert row["prime"] == pytest.approx(row["value"] / (0.5 * rho * length**k), rel=1e-12)
        truth_prime = hull_day.truth["primes"][s]
        tol = TOLERANCE[MIRROR.get(s, s)]
        assert abs(row["prime"] - truth_prime) <= tol * abs(truth_prime) + 1e-12, s
        assert row["prime_ci_low"] <= row["prime"] <= row["prime_ci_high"]


def test_primes_do_not_depend_on_water_density_of_run_groups():
    """A prime value is non-dimensional: with exact steady data, it is the truth's whatever the
    water density of each run. Here the transverse tows were made in warmer (lighter) water
    than the angled runs, as happens when they are towed late in the day; C_D(α) and C_D,90
    are properties of the hull, so every prime must equal HullTruth.primes exactly.

    Currently FAILS for Y_v|v| and Z_w|w|: fit.fit_transverse reports Y_v|v| = -K (K from
    R = K·U|U|, i.e. at the transverse runs' density) while coefficients_table divides it by
    ½ρL² with ρ the mean density of all hull runs, so the prime is off by ρ_90/ρ_mean.
    """
    truth = syn.sut2_hull_truth(1000.0)
    rho_angled, rho_transverse = 1010.0, 990.0
    rows = []
    for ang in (0.0, 5.0, 10.0, 15.0):
        for u in (1.0, 2.0):
            drag = float(syn.hull_forces(np.array([u]), np.array([0.0]), ang, truth,
                                         rho_angled)[0][0])
            rows.append((ang, u, drag, rho_angled))
    for u in (0.1, 0.2, 0.3):
        drag = float(syn.hull_forces(np.array([u]), np.array([0.0]), 90.0, truth,
                                     rho_transverse)[0][0])
        rows.append((90.0, u, drag, rho_transverse))
    runs = pd.DataFrame(rows, columns=["angle_deg", "speed_mean", "drag_mean", "rho"])
    runs.insert(0, "run", np.arange(1, len(runs) + 1))
    runs["status"], runs["config"] = "ok", "hull"
    runs["cd"] = runs["drag_mean"] / (0.5 * runs["rho"] * truth.frontal_area
                                      * runs["speed_mean"] ** 2)
    runs["cl"] = np.nan
    hf = fit.fit_hull(runs, {}, mass=truth.m, mass_sd=0.0005, length=truth.length,
                      frontal_area=truth.frontal_area, lateral_area=truth.lateral_area)
    table = fit.coefficients_table(hf, fit.load_reference("remus")).set_index("symbol")
    expected = truth.primes(1000.0)
    for s in ("X_u|u|", "X_uv", "X_v|v|", "Y_uv", "Y_v|v|", "Z_w|w|"):
        assert table.loc[s, "prime"] == pytest.approx(expected[s], rel=1e-6), s
        # and the dimensional value is that prime at the fit's one density
        assert table.loc[s, "value"] == pytest.approx(
            table.loc[s, "prime"] * 0.5 * hf.rho * truth.length**2, rel=1e-12)


# ------------------------------------------------------------------- curve-difference check
def test_curve_difference_agrees_with_joint_regression(hull_day: Day):
    hf = hull_day.result.hull.fit
    for symbol in ("X_udot", "Y_vdot"):
        est = hf.estimates[symbol]
        assert est.agreement.startswith("agree"), (symbol, est.agreement)
        assert math.isfinite(est.alt_value)
        truth = hull_day.truth["coefficients"][symbol]
        assert abs(est.alt_value - truth) <= TOLERANCE[symbol] * abs(truth) * 2
        levels = hf.added_mass[symbol].curve_difference["levels"]
        assert len(levels) >= 2
    table = hull_day.result.hull.coefficients.set_index("symbol")
    assert table.loc["X_udot", "agreement"].startswith("agree")
    assert not any("disagree" in w.lower() for w in hull_day.result.warnings)


# ------------------------------------------------------------------------- missing runs
STINGS = [
    syn.RunSpec("sting", 0.0, 0.3, 0.3),
    syn.RunSpec("sting", 0.0, 0.8, 0.5),
    syn.RunSpec("sting", 0.0, 1.6, 0.5),
    syn.RunSpec("sting", 0.0, 2.0, 0.5),
    syn.RunSpec("sting", 0.0, 2.0, 1.0, test="accel"),
    syn.RunSpec("sting", 0.0, 0.3, 0.2, test="accel"),
]
ZERO_STEADY = [syn.RunSpec("hull", 0.0, v, 0.5) for v in (0.8, 1.2, 1.6, 2.0)]
ZERO_ACCEL = [syn.RunSpec("hull", 0.0, 2.0, a, test="accel") for a in (0.25, 1.0)]
ANGLES = [syn.RunSpec("hull", ang, v, 0.5) for ang in (5.0, 10.0, 15.0) for v in (0.8, 2.0)]
TRANSVERSE = [syn.RunSpec("hull", 90.0, v, 0.15) for v in (0.15, 0.2, 0.3)] + [
    syn.RunSpec("hull", 90.0, 0.3, a, test="accel") for a in (0.1, 0.2)
]


def _small_day(d: Path, plan: list[syn.RunSpec], seed: int) -> Day:
    syn.make_hull_day(d, seed=seed, fs=100.0, runs=plan)
    protocol = write_hull_protocol(d)
    return Day(d, protocol, syn.load_truth(d), process(protocol))


def _omitted(day: Day, symbols: tuple[str, ...]) -> None:
    """Never a fabricated value: absent from the estimates and from coefficients.csv."""
    table = day.result.hull.coefficients
    for s in symbols:
        assert s not in day.result.hull.fit.estimates
        assert s not in set(table["symbol"])
    assert table["value"].notna().all()


def _present(day: Day, symbols: tuple[str, ...]) -> None:
    table = day.result.hull.coefficients.set_index("symbol")
    for s in symbols:
        truth = day.truth["coefficients"][s]
        err = abs(table.loc[s, "value"] - truth) / abs(truth)
        assert err <= TOLERANCE[MIRROR.get(s, s)], (s, err)


def test_day_without_transverse_runs(tmp_path):
    day = _small_day(tmp_path, STINGS + ZERO_STEADY + ZERO_ACCEL + ANGLES, seed=31)
    assert day.result.rejected == {}
    _omitted(day, ("Y_vdot", "Z_wdot", "Y_v|v|", "Z_w|w|"))
    _present(day, ("X_udot", "X_u|u|", "Y_uv", "X_uv", "X_v|v|"))
    msgs = " ".join(day.result.hull.fit.messages)
    assert "Y_vdot" in msgs and "Y_v|v|" in msgs and "Z_w|w|" in msgs
    assert "90°" in msgs and "transverse" in msgs
    assert any("Y_v|v|" in w for w in day.result.warnings)


def test_day_with_one_acceleration_only(tmp_path):
    one_level = [syn.RunSpec("hull", 0.0, 2.0, 0.5, test="accel")]
    day = _small_day(tmp_path, STINGS + ZERO_STEADY + one_level + ANGLES + TRANSVERSE, seed=32)
    assert day.result.rejected == {}
    _omitted(day, ("X_udot",))
    _present(day, ("Y_vdot", "X_u|u|", "X_uv", "Y_v|v|"))
    msg = [m for m in day.result.hull.fit.messages if m.startswith("X_udot")]
    assert len(msg) == 1
    assert "two or more accelerations" in msg[0] and "the day has 1" in msg[0]
    assert "omitted" in msg[0]


def test_day_with_a_single_angle(tmp_path):
    day = _small_day(tmp_path, STINGS + ZERO_STEADY + ZERO_ACCEL + TRANSVERSE, seed=33)
    assert day.result.rejected == {}
    _omitted(day, ("X_uv", "X_uw", "X_v|v|", "X_w|w|"))
    _present(day, ("X_udot", "X_u|u|", "Y_uv", "Y_vdot", "Y_v|v|"))
    assert day.result.hull.fit.damping is None
    msgs = " ".join(day.result.hull.fit.messages)
    assert "X_uv" in msgs and "X_v|v|" in msgs and "three or more angles" in msgs
    row = day.result.hull.coefficients.set_index("symbol").loc["X_u|u|"]
    assert row["ci_low"] <= day.truth["coefficients"]["X_u|u|"] <= row["ci_high"]


# ------------------------------------------------------------------- filter mismatch pitfall
def _speed_one_way(real):
    """Speed (column 0) through the same Butterworth forwards only: a phase lag."""
    from scipy.signal import sosfilt, sosfilt_zi

    def lowpass(x, fs, cutoff_hz, order=4):
        y = real(x, fs, cutoff_hz, order)
        sos = conditioning.butter_sos(float(cutoff_hz), float(fs), int(order))
        y[:, 0] = sosfilt(sos, x[:, 0], zi=sosfilt_zi(sos) * x[0, 0])[0]
        return y

    return lowpass


def _speed_late(real):
    """Speed (column 0) one sample late (5 ms at 200 Hz): two unsynchronised DAQ cards."""

    def lowpass(x, fs, cutoff_hz, order=4):
        y = real(x, fs, cutoff_hz, order)
        y[1:, 0] = y[:-1, 0].copy()
        return y

    return lowpass


@pytest.mark.parametrize("mismatch", [_speed_one_way, _speed_late], ids=["one-way", "5ms"])
def test_filter_mismatch_is_caught(hull_day: Day, monkeypatch, mismatch):
    """METHOD.md: filtering speed and force differently biases the added mass. With the speed
    filtered differently from the forces, X_udot leaves its 5 % tolerance (so the tolerance test
    above would fail), while the unpatched pipeline on the same day is within it.

    The realistic mismatches that break it are a phase lag between speed and force: the speed
    through the same Butterworth one way only (sosfilt; X_udot about -230 % on this day) or
    merely one sample (5 ms) of time skew (about -10 %). A pure cut-off mismatch is not enough:
    with the speed filtered at 1 Hz and the forces at 4 Hz, X_udot moves by only about -3 %
    (the constant-acceleration window is trimmed away from the jerk transitions, and inside it
    any zero-phase filter reproduces the linear speed ramp exactly), under the tolerance.
    """
    truth = hull_day.truth["coefficients"]["X_udot"]
    good = hull_day.result.hull.fit.estimates["X_udot"].value
    assert abs(good - truth) <= 0.05 * abs(truth)

    monkeypatch.setattr(conditioning, "lowpass", mismatch(conditioning.lowpass))
    bad_day = process(hull_day.protocol, jobs=1)
    est = bad_day.hull.fit.estimates.get("X_udot")
    assert est is not None
    assert abs(est.value - truth) > 0.05 * abs(truth), est.value


# ------------------------------------------------------------------- property tests (exact)
# exact data: statsmodels' influence measures divide by zero residuals
@pytest.mark.filterwarnings("ignore::RuntimeWarning")
@settings(max_examples=25, deadline=None)
@given(
    a=st.floats(-2.0, 2.0),
    b=st.floats(-0.5, 0.5),
    c=st.floats(0.05, 1.0),
    angles=st.lists(st.integers(-30, 30), min_size=4, max_size=10, unique=True),
    rho=st.floats(990.0, 1030.0),
    area=st.floats(1e-4, 0.1),
)
def test_cd_alpha_fit_recovers_quadratic(a, b, c, angles, rho, area):
    alpha = np.radians(np.array(angles, dtype=float))
    cd = a * alpha**2 + b * alpha + c
    res = fit.fit_cd_alpha(alpha, cd)
    assert np.allclose(res.params, [a, b, c], rtol=1e-7, atol=1e-9)

    runs = pd.DataFrame({
        "run": np.arange(1, len(angles) + 1), "status": "ok", "config": "hull",
        "angle_deg": np.array(angles, dtype=float), "speed_mean": 1.5, "cd": cd,
    })
    damping, est, msgs = fit.fit_damping(runs, rho, area, 30.0)
    assert damping is not None and msgs == []
    q = 0.5 * rho * area
    expect = {"X_u|u|": -q * c, "Y_uv": -q * c, "X_uv": -q * b, "X_v|v|": -q * (a - c / 2)}
    for s, v in expect.items():
        assert est[s].value == pytest.approx(v, rel=1e-6, abs=1e-10 * q), s
        assert est[s].ci_low <= v + 1e-9 * q and v - 1e-9 * q <= est[s].ci_high


@pytest.mark.filterwarnings("ignore::RuntimeWarning")
@settings(max_examples=25, deadline=None)
@given(
    k2=st.floats(0.01, 10.0),
    k1=st.floats(-0.5, 0.5),
    M=st.floats(0.05, 3.0),
    n_runs=st.integers(2, 8),
    seed=st.integers(0, 2**32 - 1),
)
def test_joint_regression_recovers_parameters(k2, k1, M, n_runs, seed):
    rng = np.random.default_rng(seed)
    U, a, g = [], [], []
    for run in range(n_runs):
        v = rng.uniform(0.1, 3.0)
        acc = rng.uniform(0.05, 1.5)
        ramp = np.linspace(0.2 * v, 0.8 * v, 12)
        U += [np.full(10, v), ramp]
        a += [np.zeros(10), np.full(12, acc)]
        g += [np.full(22, run)]
    U, a, g = np.concatenate(U), np.concatenate(a), np.concatenate(g)
    drag = k2 * U * np.abs(U) + k1 * U + M * a
    res = fit.joint_regression(U, a, drag, g)
    assert np.allclose(res.params, [k2, k1, M], rtol=1e-7, atol=1e-9)
