"""Issue 27, item 3: which run next (towtank.analysis.next_run).

Every day here is generated at 50 Hz with float64 TDMS files (the numbers of a CSV day to the
last bit, without writing and parsing the decimal text), reduced once, and refitted with
subsets of its runs: the runs "still to tow" are held out of the fit, ranked, and then put
back one at a time to see what the refit actually gives.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest

from towtank.analysis.hull import HullFit, fit_hull
from towtank.analysis.next_run import (
    COLUMNS,
    Condition,
    cd_alpha_rows,
    hull_models,
    predicted_half_widths,
    rank_next_runs,
    variance_ratio,
)
from towtank.testing.coverage import clopper_pearson

HELD_OUT = 8  # runs still to tow on each study day
STUDY_FIRST_SEED = 0
DAY_SEED = 5  # the unit checks' day


@dataclass
class Reduced:
    """A generated day reduced once: runs.csv rows, the sheet, reductions, tares, model."""

    runs: pd.DataFrame
    sheet: pd.DataFrame
    reductions: dict[int, Any]
    tares: dict[str, Any]
    model: Any
    rho: float

    def fit(self, without: list[int] | tuple[int, ...] = ()) -> HullFit:
        """The hull fit of the day's runs but ``without``."""
        m = self.model
        return fit_hull(self.runs[~self.runs["run"].isin(list(without))], self.reductions,
                        mass=m.mass_kg, mass_sd=m.mass_uncertainty_kg, length=m.length_m,
                        frontal_area=m.frontal_area, lateral_area=m.lateral_area,
                        tares=self.tares, rho=self.rho)

    def hull_runs(self) -> list[int]:
        ok = (self.runs["config"] == "hull") & (self.runs["status"] == "ok")
        return [int(r) for r in self.runs.loc[ok, "run"]]


def reduce_day(seed: int, where: Path) -> Reduced:
    from towtank.pipeline import process_day
    from towtank.testing.days import hull_protocol_sections, make_hull_day, write_protocol

    make_hull_day(where, seed=seed, fs=50.0, file_format="tdms", sheet_format="csv")
    protocol = write_protocol(where / "p.toml",
                              **hull_protocol_sections(".", "out", sheet_format="csv"))
    day = process_day(protocol, jobs=1)
    assert day.hull is not None
    return Reduced(day.runs, day.sheet, day.reductions, day.tares, day.protocol.model,
                   day.hull.fit.rho)


def half_width(fit: HullFit, symbol: str) -> float:
    e = fit.estimates[symbol]
    return (e.ci_high - e.ci_low) / 2.0


@pytest.fixture(scope="session")
def reduced(tmp_path_factory) -> Callable[[int], Reduced]:
    """``reduced(seed)``: the day of that seed reduced; the unit checks' day (seed 5, one of
    the study's) kept for the session, the tests only read it."""
    cache: dict[int, Reduced] = {}

    def get(seed: int) -> Reduced:
        if seed in cache:
            return cache[seed]
        red = reduce_day(seed, tmp_path_factory.mktemp(f"next_run{seed}"))
        if seed == DAY_SEED:
            cache[seed] = red
        return red

    return get


@pytest.fixture(scope="session")
def day(reduced) -> Reduced:
    return reduced(DAY_SEED)


# ---------------------------------------------------------------------------- unit checks
def test_a_new_angle_narrows_the_curvature_more_than_a_repeat():
    """C_D(α) = a·α² + b·α + c over runs at 0, 5 and 10°: a run at 15° pins the curvature
    (X_v|v| ∝ a − c/2) far better than one more at 10°."""
    x = np.vstack([cd_alpha_rows(a) for a in (0, 0, 5, 5, 10, 10)])
    ell = np.array([1.0, 0.0, -0.5])
    new_angle = variance_ratio(x, cd_alpha_rows(15.0), ell)
    repeat = variance_ratio(x, cd_alpha_rows(10.0), ell)
    assert new_angle < 0.5 * repeat < 0.5
    assert variance_ratio(x, np.zeros((0, 3)), ell) == 1.0  # nothing added, nothing gained


def test_a_new_angle_ranks_above_a_repeat_on_a_day(day):
    """On a day without its 15° runs, the sheet's 15° run is ranked above a repeat at 10°,
    and its predicted X_v|v| half-width is smaller."""
    held = [29, 30, 31, 32]  # α = 15° at 0.8-2.0 m/s
    fit = day.fit(held)
    cand = pd.DataFrame([
        {"run": 31, "config": "hull", "angle_deg": 15.0, "speed_nominal": 1.6,
         "accel_nominal": 0.5, "test": "steady"},
        {"run": 99, "config": "hull", "angle_deg": 10.0, "speed_nominal": 1.6,
         "accel_nominal": 0.5, "test": "steady"},
    ])
    out = rank_next_runs(fit, day.runs, cand, reductions=day.reductions, suggest=False)
    assert list(out.columns) == COLUMNS
    assert out["run"].tolist() == [31, 99]
    models = hull_models(fit, day.reductions)
    new = predicted_half_widths(fit, models, Condition(31, "hull", 15.0, 1.6, 0.5))
    rep = predicted_half_widths(fit, models, Condition(99, "hull", 10.0, 1.6, 0.5))
    assert new["X_v|v|"] < 0.8 * rep["X_v|v|"]
    assert out["description"].iloc[0] == "run 31: α 15°, 1.6 m/s, steady"


def test_predicted_half_width_agrees_with_the_refit(day):
    """For each of 8 held-out runs, the target's predicted 95 % half-width after it agrees with
    the one the refit with that run gives. The prediction is an expectation (the refit's own
    residual variance scatters about it): on this day (seed 5) the 8 errors are at most 6.2 %
    (median 1.6 %); on seeds 5-10 (48 candidates) the median |error| is 3.5 %, the 90th
    percentile 12 %, the largest 39 % (a low-speed run whose C_D came out far off the curve).
    Asserted here: median within 5 %, every one within 10 %."""
    held = [21, 24, 27, 29, 30, 31, 33, 39]
    fit = day.fit(held)
    cand = day.sheet[day.sheet["run"].isin(held)]
    out = rank_next_runs(fit, day.runs, cand, reductions=day.reductions, top=len(held),
                         suggest=False)
    assert len(out) == len(held)
    target = out["target"].iloc[0]
    errors = []
    for row in out.itertuples():
        actual = half_width(day.fit([h for h in held if h != row.run]), target)
        errors.append(abs(row.half_width_after / actual - 1.0))
    assert float(np.median(errors)) < 0.05 and max(errors) < 0.10, errors
    # the best ranked run does shrink the target, and more than the worst ranked
    first = half_width(day.fit([h for h in held if h != int(out["run"].iloc[0])]), target)
    last = half_width(day.fit([h for h in held if h != int(out["run"].iloc[-1])]), target)
    assert first < out["half_width_now"].iloc[0] and first < last


def test_the_nominal_profile_carries_the_information_of_the_towed_run(day):
    """The joint added-mass regression's rows of a run built from its nominal speed and
    acceleration (ramp, trimmed as the day's runs are, then plateau) carry the information of
    the samples the run actually gave: diag X'X within 1 % for U|U| and U, within 20 % for a
    (measured 0.5 % and 8 % at most at α = 0, seed 5), and the same number of samples ± 2."""
    from towtank.analysis.next_run import day_profile, profile_rows

    ids = [13, 14, 15, 16, 17, 18, 19, 33, 34]  # the α = 0 runs
    profile = day_profile(day.reductions, ids)
    assert profile is not None and profile.dt == pytest.approx(0.06, rel=1e-6)
    sheet = day.sheet.set_index("run")
    for r in ids:
        s = day.reductions[r].samples
        x = np.column_stack([s["U"] * np.abs(s["U"]), s["U"], s["a"]])
        rows = profile_rows(float(sheet.loc[r, "speed_nominal"]),
                            float(sheet.loc[r, "accel_nominal"]), profile)
        assert abs(rows.shape[0] - x.shape[0]) <= 2, r
        ratio = np.diag(rows.T @ rows) / np.diag(x.T @ x)
        assert ratio[:2] == pytest.approx([1.0, 1.0], abs=0.01), (r, ratio)
        assert ratio[2] == pytest.approx(1.0, abs=0.2), (r, ratio)


def test_suggestions_are_not_on_the_sheet(day):
    held = [29, 30, 31, 32]
    fit = day.fit(held)
    cand = day.sheet[day.sheet["run"].isin(held)]
    out = rank_next_runs(fit, day.runs, cand, reductions=day.reductions, n_suggest=3)
    new = out[out["run"].isna()]
    assert 1 <= len(new) <= 3 and new["rank"].tolist() == list(range(1, len(new) + 1))
    assert out["run"].dtype == "Int64"
    assert all(d.startswith("new: ") for d in new["description"])
    sheet = day.sheet[day.sheet["config"] == "hull"]
    for r in new.itertuples():
        same = sheet[(np.abs(sheet["angle_deg"] - r.angle_deg) <= 0.5)
                     & (np.abs(sheet["speed_nominal"] - r.speed_m_s) <= 0.03 * r.speed_m_s)]
        if "accel" in r.description:
            same = same[np.abs(same["accel_nominal"] - r.accel_m_s2) <= 0.1 * r.accel_m_s2]
        assert same.empty, r.description
    # within the sheet's range
    assert new["angle_deg"].between(sheet["angle_deg"].min(), sheet["angle_deg"].max()).all()
    assert (new["half_width_after"] <= new["half_width_now"]).all()


def test_no_fit_or_no_candidate_gives_an_empty_frame(day):
    fit = day.fit([29, 30])
    cand = day.sheet[day.sheet["run"].isin([29, 30])]
    for out in (rank_next_runs(None, day.runs, cand),
                rank_next_runs(fit, day.runs, cand.iloc[:0], suggest=False),
                rank_next_runs(fit, day.runs, None, suggest=False),
                rank_next_runs(HullFit({}, math.nan, 1.0, 1.0, {}, None, pd.DataFrame(), []),
                               day.runs, cand)):
        assert out.empty and list(out.columns) == COLUMNS


def test_a_degenerate_fit_never_raises(day):
    """One hull run (no coefficient: an empty frame), then the smallest C_D(α) fit (four runs
    at three angles: one residual degree of freedom, t₀.₉₇₅ = 12.7): nothing raises, and a
    fifth run more than halves the widest interval (t₀.₉₇₅(2) = 4.3)."""
    hull = day.hull_runs()
    cand = day.sheet[day.sheet["run"].isin([22, 35])]
    one = day.fit([r for r in hull if r != 13])
    out = rank_next_runs(one, day.runs, cand, reductions=day.reductions)
    assert out.empty and list(out.columns) == COLUMNS
    four = day.fit([r for r in hull if r not in (13, 14, 21, 25)])
    out = rank_next_runs(four, day.runs, cand, reductions=day.reductions)
    assert list(out.columns) == COLUMNS and out["run"].notna().sum() == 2
    assert (out["half_width_after"] < 0.5 * out["half_width_now"]).all()


# ------------------------------------------------------------------------- the proof
def study_day(red: Reduced, seed: int) -> dict[str, Any]:
    """One study day, ``red`` that of ``seed``: hold 8 random hull runs out, rank them, refit
    with the first ranked and with another drawn at random among the other seven; does the
    first shrink the target's 95 % half-width more?"""
    rng = np.random.default_rng(seed)
    held = sorted(int(r) for r in rng.choice(red.hull_runs(), size=HELD_OUT, replace=False))
    fit = red.fit(held)
    out = rank_next_runs(fit, red.runs, red.sheet[red.sheet["run"].isin(held)],
                         reductions=red.reductions, top=HELD_OUT, suggest=False)
    target, first = out["target"].iloc[0], int(out["run"].iloc[0])
    other = int(rng.choice([h for h in held if h != first]))
    hw_first = half_width(red.fit([h for h in held if h != first]), target)
    hw_other = half_width(red.fit([h for h in held if h != other]), target)
    return {"seed": seed, "target": target, "first": first, "other": other,
            "first_better": hw_first < hw_other}


def _fraction(days: int, reduced: Callable[[int], Reduced]) -> tuple[float,
                                                                     tuple[float, float]]:
    rows = [study_day(reduced(s), s) for s in range(STUDY_FIRST_SEED, STUDY_FIRST_SEED + days)]
    k = sum(r["first_better"] for r in rows)
    return k / days, clopper_pearson(k, days)


@pytest.mark.heavy
def test_the_first_ranked_run_beats_a_random_one_on_20_days(reduced):
    """The 20-day version of the issue's proof (seeds 0-19, about 11 s): the first ranked run
    shrinks the targeted interval more than a random other remaining run on 18 of 20 days
    (90 %, Clopper–Pearson 95 % interval 68–99 %); asserted at least 15 of 20 (75 %)."""
    frac, _ = _fraction(20, reduced)
    assert frac >= 0.75, frac


@pytest.mark.slow
def test_the_first_ranked_run_beats_a_random_one_on_100_days(reduced):
    """The issue's proof (seeds 0-99, about 80 s): the first ranked run shrinks the targeted
    interval more than a random other remaining run on at least 80 % of the days: measured on
    88 of 100 days (Clopper–Pearson 95 % interval 80.0–93.6 %); the target was X_uv on every
    day."""
    frac, (lo, hi) = _fraction(100, reduced)
    assert frac >= 0.80, (frac, lo, hi)
