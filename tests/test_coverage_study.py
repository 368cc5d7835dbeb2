"""Issue 13's coverage study: the hull coefficients under the conditions of other tanks'
signals (1 kHz, 100 Hz, 50 Hz, 50 Hz mains hum, 2.5 Hz vibration in the filter's passband,
4× noise, two transverse acceleration levels, 1200 s runs).

Every test day uses the generator's truth with the model's mass as a lab weighs it (the true
mass plus a weighing error of the protocol's 0.5 g standard uncertainty,
:func:`towtank.testing.coverage.weighed_mass`), so the added masses' intervals, which include
that uncertainty, are judged against errors that include it.

* Always: one day per condition, every coefficient present and within the tolerances of
  tests/test_fit.py (the weighing error, known to the study, taken out of the added masses;
  four times them with four times the noise).
* ``--run-slow`` (hours): 100 days per condition; the 95 % intervals must hold the truth at a
  rate whose Clopper–Pearson 95 % interval reaches into 93–98 %, and the errors stay within
  the tolerances on at least 97 of the 100 days. The measured rates are in
  docs/method.md; ``scripts/coverage_study.py`` runs the same study in the background.
"""

from __future__ import annotations

import pytest

from towtank.testing.coverage import CONDITIONS, SYMBOLS, day_result, summarise, tolerance

STUDY_DAYS = 100
FIRST_SEED = 1000


@pytest.mark.heavy
@pytest.mark.parametrize("condition", list(CONDITIONS))
def test_every_coefficient_present_and_within_tolerance(condition, tmp_path):
    rows = day_result(condition, FIRST_SEED, workdir=tmp_path)
    for row in rows:
        assert row["present"], (condition, row["symbol"], "omitted")
        tol = tolerance(condition, row["symbol"])
        assert abs(row["fit_rel_error"]) <= tol, (condition, row["symbol"], row["fit_rel_error"])
    assert rows[0]["rejected"] == 0


@pytest.mark.slow
@pytest.mark.parametrize("condition", list(CONDITIONS))
def test_95_percent_intervals_hold_the_truth_93_to_98_percent(condition, tmp_path):
    rows = [r for seed in range(FIRST_SEED, FIRST_SEED + STUDY_DAYS)
            for r in day_result(condition, seed, workdir=tmp_path)]
    summary = summarise(rows).set_index("symbol")
    for symbol in SYMBOLS:
        s = summary.loc[symbol]
        assert s["present"] == STUDY_DAYS, (condition, symbol, "omitted on some days")
        assert s["cp_low"] <= 0.98 and s["cp_high"] >= 0.93, (
            condition, symbol, s["coverage"], (s["cp_low"], s["cp_high"]))
        # the tolerances hold on at least 97 of 100 days: X_uv, a small cross term (the
        # C_D(α) fit's linear term), passes its 20 % on 1 or 2 days of 100 in the study
        # (31 % at most, at 1 kHz), while its 95 % interval holds the truth on 93-98 % of days
        errors = [abs(r["fit_rel_error"]) for r in rows if r["symbol"] == symbol]
        within = sum(e <= tolerance(condition, symbol) for e in errors) / len(errors)
        assert within >= 0.97, (condition, symbol, within, max(errors))
