"""Hull coefficients against the SUT-2 truth (issue 3, "Done when").

Synthetic SUT-2 days at realistic noise give the twelve coefficients; their errors, their 95 %
intervals (per seed and as a coverage rate over many seeds), the prime values and the diff %
against REMUS (Table 4 arithmetic), the report's curve-difference cross-check, the coefficients a
day cannot support, and the filter pitfall of docs/method.md are tested here.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from conftest import Day, SeedResult, process, workbook_block, write_hull_protocol
from hypothesis import given, settings
from hypothesis import strategies as st

from towtank.analysis import hull as fit
from towtank.signal import conditioning
from towtank.testing import synthetic as syn

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


@pytest.mark.heavy
def test_interval_coverage(seed_result):
    """Over 30 seeds the 95 % intervals hold the truth in 85-100 % of the days, per coefficient.

    Measured (these 30 seeds, 100 Hz): X_udot 100 %, Y_vdot 90 %, X_u|u| 100 %, Y_v|v| 100 %,
    X_uv 100 % (200 seeds: 100, 97, 99, 96.5, 97 %). X_udot's interval is dominated by the
    stated 0.5 g uncertainty of the weighed mass, hence its full coverage; the test below
    takes the mass out.
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


def _refit(res: SeedResult, mass_sd: float) -> fit.HullFit:
    """The hull fit of a cached day again, with another stated mass uncertainty."""
    m = res.model
    return fit.fit_hull(res.runs, res.reductions, mass=m.mass_kg, mass_sd=mass_sd,
                        length=m.length_m, frontal_area=m.frontal_area,
                        lateral_area=m.lateral_area, tares=res.tares)


@pytest.mark.heavy
def test_added_mass_interval_coverage_without_mass_uncertainty(seed_result):
    """With mass_uncertainty_kg = 0 the added-mass intervals are the regression's and the tare's
    alone; over the 30 cached days of test_interval_coverage they still hold the truth in
    85-100 % of the days, and so does the tare's own interval for m_t.

    The default 0.5 g of the weighed mass dominates X_udot's interval and would hide a
    regression-only interval that is too narrow: a tare fit that treats its samples as
    independent gives a standard error of m_t, which goes one-for-one into X_udot and Y_vdot,
    1.8 times too small (m_t coverage 70 %; X_udot 88.5 % over 200 days at 100 Hz, |error|/
    standard error spread 1.44). With the tare and the joint regression clustered by run (CR2,
    towtank.stats.intervals) and t at the Welch-Satterthwaite degrees of freedom, 200 days at 100 Hz
    give 94.5 % for X_udot, 95.0 % for Y_vdot and 94.5 % for m_t (100 days at 200 Hz: 97 %,
    96 %). These 30 seeds are unluckier than that: 93 % for X_udot, 87 % for Y_vdot and m_t.
    """
    from scipy.stats import t

    symbols = ("X_udot", "Y_vdot")
    inside: dict[str, list[bool]] = {s: [] for s in (*symbols, "m_t")}
    m_t = syn.TareTruth().m_t
    for seed in COVERAGE_SEEDS:
        res = seed_result(seed, COVERAGE_FS)
        hf = _refit(res, mass_sd=0.0)
        for s in symbols:
            e, am = hf.estimates[s], hf.added_mass[s]
            # the same estimate as the day's, with the mass's uncertainty taken out
            assert e.value == res.coefficients.loc[s, "value"]
            assert e.std_error == pytest.approx(am.M_se, rel=1e-12)
            assert e.std_error < res.coefficients.loc[s, "std_error"]
            inside[s].append(bool(e.ci_low <= res.truth[s] <= e.ci_high))
        tare = res.tares["A"].drag
        assert tare.dof == 11  # clustered by sting run: 12 runs
        half = t.ppf(0.975, tare.dof) * math.sqrt(tare.cov[2, 2])
        inside["m_t"].append(bool(abs(tare.coef[2] - m_t) <= half))
    coverage = {s: float(np.mean(v)) for s, v in inside.items()}
    print("coverage without the mass uncertainty:", {s: round(c, 3) for s, c in coverage.items()})
    for s, c in coverage.items():
        assert 0.85 <= c <= 1.0, (s, c)


# ----------------------------------------------------------------------- primes, diff % (T4)
def _table4() -> pd.DataFrame:
    from importlib import resources

    with resources.files("towtank.reference").joinpath("data", "sut2_table4.csv").open() as fh:
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

    fit.fit_transverse fits each run's R/(½ρ_run·A_lat), so C_D,90 is density-free and the
    prime exact; a Y_v|v| = -K taken from R = K·U|U| (at the transverse runs' density) and
    divided by ½ρL² with ρ the mean density of all hull runs would be off by ρ_90/ρ_mean.
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
        assert str(est.agreement).startswith("agree"), (symbol, est.agreement)
        assert math.isfinite(est.alt_value)
        truth = hull_day.truth["coefficients"][symbol]
        assert abs(est.alt_value - truth) <= TOLERANCE[symbol] * abs(truth) * 2
        levels = hf.added_mass[symbol].curve_difference["levels"]
        assert len(levels) >= 2
    table = hull_day.result.hull.coefficients.set_index("symbol")
    assert table.loc["X_udot", "agreement"].startswith("agree")
    assert not any("disagree" in str(w).lower() for w in hull_day.result.warnings)

    # the second estimate is in the method column of the primary rows, beside the primary
    assert table.loc["Z_wdot", "method"].startswith("same as Y_vdot")
    for symbol in ("X_udot", "Y_vdot"):
        method = table.loc[symbol, "method"]
        assert method.startswith("joint regression"), method
        alt = table.loc[symbol, "alt_value"]
        assert (f"; second estimate (curve difference, report eqs. 7–8) {alt:.5g} kg: agree "
                "(difference ") in method, method
        assert method.endswith(" kg)"), method


def _rehull(day: Day, runs: pd.DataFrame | None = None):
    """The hull stage of the pipeline again, on a copy of the processed day."""
    from dataclasses import replace

    from towtank import pipeline
    from towtank.results import notices

    r = day.result
    runs = r.runs if runs is None else runs
    hull, warns = pipeline.hull_stage(r.protocol, runs, r.reductions, r.tares)
    return replace(r, runs=runs, warnings=notices(warns, "hull"), hull=hull)


def test_curve_difference_disagreement_is_reported(hull_day: Day, monkeypatch):
    """A second estimate 10 g away from the joint regression (a bias no noise explains): the
    agreement column, the method text and a day warning all say DISAGREE, with the numbers."""
    real = fit.curve_difference
    runs = hull_day.result.runs
    zero = set(runs.loc[(runs["config"] == "hull") & (runs["angle_deg"] == 0.0), "run"])

    def shifted(reductions, run_ids, mass):
        out = real(reductions, run_ids, mass)
        if set(run_ids) <= zero:  # X_udot's runs only
            out["value"] = float(out["value"]) + 0.010
        return out

    monkeypatch.setattr(fit, "curve_difference", shifted)
    day = _rehull(hull_day)
    est = day.hull.fit.estimates["X_udot"]
    am = day.hull.fit.added_mass["X_udot"]
    diff = est.alt_value - est.value
    assert 0.009 < diff < 0.011
    spread = am.curve_difference["spread"]
    assert est.agreement == fit.agreement(est.value, est.alt_value, am.M_se, spread)
    tol = 2 * math.hypot(am.M_se, spread)
    assert str(est.agreement) == f"DISAGREE: difference {diff:+.2g} kg exceeds {tol:.2g} kg"
    row = day.hull.coefficients.set_index("symbol").loc["X_udot"]
    assert row["agreement"] == str(est.agreement)
    assert row["method"].endswith(
        f"; second estimate (curve difference, report eqs. 7–8) {est.alt_value:.5g} kg: "
        f"DISAGREE (difference {diff:+.2g} kg exceeds {tol:.2g} kg)")
    assert str(day.hull.fit.estimates["Y_vdot"].agreement).startswith("agree")
    warned = [str(w) for w in day.warnings if "disagree" in str(w).lower()]
    assert len(warned) == 1, day.warnings
    assert warned[0].startswith(f"X_udot: the curve-difference estimate {est.alt_value:.4g} kg "
                                f"and the joint regression {est.value:.4g} kg disagree ("
                                f"difference {diff:+.2g} kg exceeds {tol:.2g} kg).")


def test_agreement_threshold():
    """Agree when |difference| ≤ 2·√(se² + spread²): here 2·√(3² + 4²)·1e-4 = 1e-3 kg."""
    assert str(fit.agreement(-0.0170, -0.0161, 3e-4, 4e-4)) == (
        "agree: difference +0.0009 kg within 0.001 kg")
    assert str(fit.agreement(-0.0170, -0.0179, 3e-4, 4e-4)) == (
        "agree: difference -0.0009 kg within 0.001 kg")
    assert str(fit.agreement(-0.0170, -0.0159, 3e-4, 4e-4)) == (
        "DISAGREE: difference +0.0011 kg exceeds 0.001 kg")
    assert str(fit.agreement(-0.0170, -0.0181, 3e-4, 4e-4)).startswith(
        "DISAGREE: difference -0.0011")


# ----------------------------------------------------------------------------- diagnostics
def test_corrupted_run_is_flagged_as_outlier(hull_day: Day, tmp_path):
    """One steady run at 10° and 1.2 m/s with its drag 2 % high (a fouled or misread run):
    the C_D(α) fit flags it alone, by name, in its outliers, in the day warnings and in the
    workbook's Quality sheet."""
    from towtank.report.workbook import write_workbook

    runs = hull_day.result.runs.copy()
    pick = (runs["config"] == "hull") & (runs["angle_deg"] == 10.0) & (
        np.abs(runs["speed_mean"] - 1.2) < 0.05) & (runs["status"] == "ok")
    assert pick.sum() == 1
    bad = int(runs.loc[pick, "run"].iloc[0])
    runs.loc[pick, ["drag_mean", "cd"]] *= 1.02
    # this clean day already has a flagged run: 15°, 0.8 m/s, at the corner of the design
    # (leverage 0.3), with Cook's distance 0.6
    before = hull_day.result.hull.fit.damping.outliers
    assert bad not in before
    day = _rehull(hull_day, runs)
    dm = day.hull.fit.damping
    assert bad in dm.outliers and set(dm.outliers) <= {bad, *before}
    row = dm.runs.set_index("run").loc[bad]
    assert row["student"] > 20  # 2 % of C_D is about 60 times its scatter between runs
    warned = [str(w) for w in day.warnings if str(w).startswith("C_D(α) fit:")]
    assert len(warned) == 1
    assert f"{bad} (studentized residual +{row['student']:.3g}, Cook's distance" in warned[0]
    assert "flagged as" in warned[0] and "still in the fit" in warned[0]
    sheet = workbook_block(write_workbook(day, tmp_path), "Quality",
                            "C_D(α) fit: residuals")
    flagged = sheet.loc[sheet["outlier"].astype(bool), "run"].astype(int).tolist()
    assert flagged == dm.outliers


def test_residuals_per_run_of_the_added_mass_and_transverse_fits(hull_day: Day):
    hf = hull_day.result.hull.fit
    runs = hull_day.result.runs
    for symbol, angle in (("X_udot", 0.0), ("Y_vdot", 90.0)):
        am = hf.added_mass[symbol]
        expected = runs.loc[(runs["config"] == "hull") & (runs["status"] == "ok")
                            & (runs["angle_deg"] == angle), "run"].astype(int).tolist()
        assert sorted(am.residual_by_run) == sorted(expected) == sorted(am.runs)
        # mean residual of each run's samples: a few tenths of a millinewton at most
        assert all(abs(v) < 1e-3 for v in am.residual_by_run.values()), am.residual_by_run
    tr = hf.damping.transverse_runs
    assert sorted(tr["run"]) == sorted(hf.added_mass["Y_vdot"].runs)
    # the drag residual [N] of R = ½ρ_run·A_lat·C_D,90·U|U|, each run at its own density
    rho = runs.set_index("run").loc[tr["run"], "rho"].to_numpy()
    q = 0.5 * rho * 0.0152
    np.testing.assert_allclose(tr["resid"], tr["drag"] - q * hf.damping.cd90 * tr["speed"] ** 2,
                               rtol=1e-9, atol=1e-12)
    assert np.all(np.abs(tr["resid"]) < 1e-3)
    assert set(hf.damping.runs.columns) >= {"run", "resid", "student", "cooks"}


# ----------------------------------------------------------- uncertainty keys, reference CSV
def test_uncertainty_keys_and_user_reference_csv(hull_day: Day, tmp_path):
    """[model] mass_uncertainty_kg and length_uncertainty_m enter the intervals exactly as
    propagated, diameter_uncertainty_m enters none (it is recorded in provenance.json), and a
    user reference CSV gives reference_prime and diff_pct, the Z/X twins taking their source's
    reference where the CSV lacks them."""
    from scipy.stats import t

    from towtank.report.provenance import provenance
    from towtank.stats.intervals import welch_satterthwaite

    mass_sd, length_sd, diameter_sd = 0.002, 0.002, 0.01
    ref = {"X_udot": -0.0008, "Y_vdot": -0.03, "X_u|u|": -0.0032, "X_uv": -0.0002,
           "X_v|v|": 0.0011, "Y_uv": -0.0035, "Y_v|v|": -0.1, "Z_w|w|": -0.09}
    (tmp_path / "my_ref.csv").write_text(
        "# a user reference: no Z_wdot, X_uw, X_w|w|, Z_uw\nsymbol,prime\n"
        + "".join(f"{s},{v}\n" for s, v in ref.items()), encoding="utf-8")
    sections = syn.hull_protocol_sections(str(hull_day.dir), "out")
    sections["campaign"]["reference"] = "my_ref.csv"
    sections["model"].update(mass_uncertainty_kg=mass_sd, length_uncertainty_m=length_sd,
                             diameter_uncertainty_m=diameter_sd)
    day = process(syn.write_protocol(tmp_path / "p.toml", **sections))
    table = day.hull.coefficients.set_index("symbol")
    base = hull_day.result.hull.coefficients.set_index("symbol")
    length = 0.353

    # reference CSV: own symbols, twins from their source unless the CSV has them (Z_w|w|)
    for s in fit.SYMBOLS:
        expected = ref.get(s, ref.get(MIRROR.get(s, s)))
        assert table.loc[s, "reference_prime"] == expected, s
        prime = table.loc[s, "prime"]
        assert table.loc[s, "diff_pct"] == pytest.approx(
            (prime - expected) / abs(expected) * 100, rel=1e-12), s
        assert prime == pytest.approx(base.loc[s, "prime"], rel=1e-12)  # the same data
    assert table.loc["Z_w|w|", "reference_prime"] != table.loc["Y_v|v|", "reference_prime"]

    # mass: u_c = √(u_reg² + u_tare² + u_m²), half-width t(ν_eff)·u_c (Welch-Satterthwaite)
    for day_, sd, tab in ((day, mass_sd, table), (hull_day.result, 0.0005, base)):
        for s in ("X_udot", "Y_vdot"):
            am = day_.hull.fit.added_mass[s]
            u_c = math.sqrt(am.regression_se**2 + am.tare_se**2 + sd**2)
            assert tab.loc[s, "std_error"] == pytest.approx(u_c, rel=1e-12)
            nu = welch_satterthwaite(
                [am.regression_se**2, am.tare_se**2, sd**2],
                [am.regression_dof, day_.tares["A"].drag.dof, math.inf])
            assert am.dof == pytest.approx(nu, rel=1e-12)
            half = (tab.loc[s, "ci_high"] - tab.loc[s, "ci_low"]) / 2
            assert half == pytest.approx(t.ppf(0.975, nu) * u_c, rel=1e-9)
            assert tab.loc[s, "value"] == base.loc[s, "value"]
    assert day.hull.fit.added_mass["X_udot"].M_se == pytest.approx(
        hull_day.result.hull.fit.added_mass["X_udot"].M_se, rel=1e-12)
    assert (table.loc["X_udot", "ci_high"] - table.loc["X_udot", "ci_low"]
            > 3 * (base.loc["X_udot", "ci_high"] - base.loc["X_udot", "ci_low"]))

    # length: prime intervals only, u(prime)² = (u/(½ρL^k))² + (prime·k·u(L)/L)²
    for tab, sd in ((table, length_sd), (base, 0.0005)):
        for s in ("X_udot", "Y_vdot", "X_u|u|", "X_uv", "X_v|v|", "Y_v|v|"):
            r = tab.loc[s]
            k = 3 if s.endswith("dot") else 2
            scale = r["value"] / r["prime"]
            factor = (r["ci_high"] - r["ci_low"]) / (2 * r["std_error"])
            u_prime = math.hypot(r["std_error"] / scale, r["prime"] * k * sd / length)
            assert (r["prime_ci_high"] - r["prime_ci_low"]) / 2 == pytest.approx(
                factor * u_prime, rel=1e-9), s
            assert r["prime_ci_low"] < r["prime"] < r["prime_ci_high"]

    # damping: neither the mass, the length nor the diameter enters the SI values' intervals
    for s in ("X_u|u|", "X_uv", "X_v|v|", "Y_uv", "Y_v|v|"):
        for col in ("value", "ci_low", "ci_high", "std_error"):
            assert table.loc[s, col] == pytest.approx(base.loc[s, col], rel=1e-12), (s, col)
    assert provenance(day)["settings"]["model_uncertainty"] == {
        "mass_uncertainty_kg": mass_sd, "length_uncertainty_m": length_sd,
        "diameter_uncertainty_m": diameter_sd}


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
    assert "Y_vdot and Z_wdot need accelerated hull runs at α = 90°" in msgs
    assert "Y_v|v|" in msgs and "Z_w|w|" in msgs
    assert "90°" in msgs and "transverse" in msgs
    assert any("Y_v|v|" in str(w) for w in day.result.warnings)


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
    """docs/method.md: filtering speed and force differently biases the added mass. With the speed
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


def test_intervals_carry_the_subtracted_tares_uncertainty(hull_day: Day):
    """The tare subtracted sample by sample has the regressors of the joint regression, so its
    m_t error goes one for one into m − X_udot; and its (t2, t1, m_t) covariance reaches C_D(α)
    through each run's steady regressors: cov_tare = P·R·Σ·Rᵀ·Pᵀ with P = pinv([α², α, 1]),
    R = (U|U|, U, a)/(½ρA·U²). Computed here from the tare fit alone, independently of fit.py."""
    from statsmodels.regression.linear_model import OLS

    res = hull_day.result
    (group,) = res.tares
    sigma = np.asarray(res.tares[group].drag.cov)
    hf = res.hull.fit
    for sym in ("X_udot", "Y_vdot"):
        assert hf.added_mass[sym].tare_se == pytest.approx(math.sqrt(sigma[2, 2]), rel=1e-9)
    dm = hf.damping
    t = dm.runs
    alpha = t["alpha_rad"].to_numpy(float)
    x = np.column_stack([alpha**2, alpha, np.ones_like(alpha)])
    regression = OLS(t["cd"].to_numpy(float), x).fit()
    u = t["speed"].to_numpy(float)
    q = 0.5 * dm.rho * dm.area
    r = np.array([res.reductions[int(run)].steady_regressors for run in t["run"]])
    r = r / (q * u * u)[:, None]
    p = np.linalg.pinv(x)
    expected = p @ r @ sigma @ r.T @ p.T
    np.testing.assert_allclose(dm.cov - np.asarray(regression.cov_params()), expected,
                               rtol=1e-6, atol=1e-18)
    assert expected[2, 2] > 0.1 * np.asarray(regression.cov_params())[2, 2]  # not negligible
    # and the interval of X_u|u| = −½ρA·c is as wide as regression and tare together make it
    est = hf.estimates["X_u|u|"]
    se_c = math.sqrt(np.asarray(regression.cov_params())[2, 2] + expected[2, 2])
    assert est.std_error == pytest.approx(q * se_c, rel=1e-6)


def test_four_angles_judge_no_run_an_outlier():
    """C_D(α) at four angles (0, 5, 10, 15°) and one speed: the quadratic leaves n − p = 1
    degree of freedom, so no run can be left out of the variance (its studentized residual is
    0/0) and Cook's distance is fixed by the angles: no run is flagged (the day said "runs 15
    (studentized residual +nan, Cook's distance 6.3) ... are flagged as outliers" on every such
    day). With six angles a run 0.05 off the curve is still flagged."""
    def runs(angles, bump):
        alpha = np.radians(np.array(angles, dtype=float))
        cd = 0.8 * alpha**2 + 0.02 * alpha + 0.12 + 1e-3 * np.cos(40.0 * alpha)
        cd[-2] += bump
        return pd.DataFrame({"run": np.arange(1, len(angles) + 1), "status": "ok",
                             "config": "hull", "angle_deg": np.array(angles, dtype=float),
                             "speed_mean": 1.5, "cd": cd})

    damping, _, _ = fit.fit_damping(runs([0, 5, 10, 15], 0.0), 998.0, 0.03, 30.0)
    assert damping is not None and damping.outliers == []
    damping, _, _ = fit.fit_damping(runs([0, 3, 6, 9, 12, 15], 0.05), 998.0, 0.03, 30.0)
    assert damping is not None and 5 in damping.outliers
