"""Similarity laws, ITTC-57 extrapolation and the scaling table."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from towtank.analysis.similarity import (
    MIN_PROTOTYPE_REYNOLDS,
    SCALING_COLUMNS,
    FormFactor,
    check_prototype_speeds,
    form_factor,
    froude_force_ratio,
    froude_number,
    froude_speed_model,
    froude_speed_prototype,
    ittc57_cf,
    ittc57_drag,
    prime_value,
    prototype_value,
    reynolds_force_ratio,
    reynolds_number,
    reynolds_speed_model,
    reynolds_speed_prototype,
    scaling_table,
    similarity_statement,
    speed_groups,
)

RHO_M, NU_M = 999.10, 1.1386e-6  # fresh water, 15 °C
RHO_P, NU_P = 1025.98, 1.1893e-6  # sea water, 15 °C, S = 35.165 g/kg


def test_ittc57_cf_at_one_million():
    assert ittc57_cf(1e6) == pytest.approx(0.0046875, rel=1e-12)


def test_ittc57_cf_is_vectorised_and_rejects_low_reynolds():
    re = np.array([1e5, 1e6, 1e7])
    np.testing.assert_allclose(ittc57_cf(re), 0.075 / (np.log10(re) - 2) ** 2, rtol=1e-15)
    with pytest.raises(ValueError, match="above 100"):
        ittc57_cf(100.0)


def test_froude_and_reynolds_numbers():
    assert froude_number(2.0, 0.353) == pytest.approx(2.0 / math.sqrt(9.80665 * 0.353))
    assert froude_number(2.0, 1.0, g=9.81) == pytest.approx(2.0 / math.sqrt(9.81))
    assert reynolds_number(2.0, 0.353, 1e-6) == pytest.approx(7.06e5)


def test_froude_speed_and_force_ratios_at_scale_4():
    assert froude_speed_model(2.0, 4.0) == pytest.approx(1.0)
    assert froude_speed_prototype(1.0, 4.0) == pytest.approx(2.0)
    assert froude_force_ratio(4.0, RHO_M, RHO_P) == pytest.approx(64.0 * RHO_P / RHO_M)
    assert froude_force_ratio(4.0, 1000.0, 1000.0) == pytest.approx(64.0)


def test_froude_speed_round_trip():
    u_m = np.array([0.3, 1.0, 2.5])
    np.testing.assert_allclose(froude_speed_model(froude_speed_prototype(u_m, 4.0), 4.0), u_m)


def test_reynolds_speed_with_equal_viscosity_is_scale_times():
    assert reynolds_speed_model(1.5, 4.0, 1e-6, 1e-6) == pytest.approx(6.0)
    assert reynolds_speed_prototype(6.0, 4.0, 1e-6, 1e-6) == pytest.approx(1.5)


def test_reynolds_speed_round_trip_and_equal_re():
    u_p = 2.0
    u_m = reynolds_speed_model(u_p, 4.0, NU_M, NU_P)
    assert reynolds_speed_prototype(u_m, 4.0, NU_M, NU_P) == pytest.approx(u_p)
    assert reynolds_number(u_m, 0.353, NU_M) == pytest.approx(reynolds_number(u_p, 1.412, NU_P))


def test_reynolds_force_ratio():
    assert reynolds_force_ratio(1000.0, 1000.0, 1e-6, 1e-6) == pytest.approx(1.0)
    expected = (RHO_P / RHO_M) * (NU_P / NU_M) ** 2
    assert reynolds_force_ratio(RHO_M, RHO_P, NU_M, NU_P) == pytest.approx(expected)


def test_invalid_scale_raises():
    with pytest.raises(ValueError, match="scale"):
        froude_speed_model(1.0, 0.0)


scales = st.floats(min_value=1.0, max_value=50.0)
speeds = st.floats(min_value=0.05, max_value=20.0)
densities = st.floats(min_value=990.0, max_value=1035.0)
viscosities = st.floats(min_value=0.6e-6, max_value=1.9e-6)
coefficients = st.floats(min_value=1e-4, max_value=10.0)
lengths = st.floats(min_value=0.1, max_value=5.0)


def _force_coefficient(force, rho, speed, length):
    return force / (0.5 * rho * speed**2 * length**2)


@settings(max_examples=100, deadline=None)
@given(scales, speeds, densities, densities, coefficients, lengths)
def test_froude_scaling_preserves_force_coefficient(lam, u_m, rho_m, rho_p, c, l_m):
    f_m = c * 0.5 * rho_m * u_m**2 * l_m**2
    u_p = froude_speed_prototype(u_m, lam)
    f_p = f_m * froude_force_ratio(lam, rho_m, rho_p)
    assert froude_number(u_p, lam * l_m) == pytest.approx(froude_number(u_m, l_m), rel=1e-12)
    assert _force_coefficient(f_p, rho_p, u_p, lam * l_m) == pytest.approx(c, rel=1e-10)


@settings(max_examples=100, deadline=None)
@given(scales, speeds, densities, densities, viscosities, viscosities, coefficients, lengths)
def test_reynolds_scaling_preserves_force_coefficient(lam, u_m, rho_m, rho_p, nu_m, nu_p, c, l_m):
    f_m = c * 0.5 * rho_m * u_m**2 * l_m**2
    u_p = reynolds_speed_prototype(u_m, lam, nu_m, nu_p)
    f_p = f_m * reynolds_force_ratio(rho_m, rho_p, nu_m, nu_p)
    re_m = reynolds_number(u_m, l_m, nu_m)
    assert reynolds_number(u_p, lam * l_m, nu_p) == pytest.approx(re_m, rel=1e-12)
    assert _force_coefficient(f_p, rho_p, u_p, lam * l_m) == pytest.approx(c, rel=1e-10)


def _synthetic_drag(speed, one_plus_k, area, rho, nu, length):
    re = speed * length / nu
    return one_plus_k * ittc57_cf(re) * 0.5 * rho * area * speed**2


def test_form_factor_recovers_known_value():
    area, length = 0.0483, 0.353
    speed = np.array([0.2, 0.4, 0.8, 1.2, 1.6, 2.0])
    drag = _synthetic_drag(speed, 1.15, area, RHO_M, NU_M, length)
    # a laminar point below re_min must be ignored even though it is far off the line
    drag[0] *= 3.0
    ff = form_factor(drag, speed, area, RHO_M, NU_M, length)
    assert isinstance(ff, FormFactor)
    assert ff.one_plus_k == pytest.approx(1.15, rel=1e-12)
    assert ff.std == pytest.approx(0.0, abs=1e-12)
    re = speed * length / NU_M
    assert ff.n == int(np.sum(re >= 2e5)) == 4
    np.testing.assert_array_equal(ff.used, re >= 2e5)
    assert ff.re_range == pytest.approx((re[2], re[-1]))
    assert ff.values[0] == pytest.approx(3.45)


def test_form_factor_mean_and_sample_std():
    area, length = 0.05, 0.35
    speed = np.array([1.0, 1.5, 2.0])
    k_values = np.array([1.10, 1.15, 1.20])
    drag = _synthetic_drag(speed, k_values, area, 1000.0, 1e-6, length)
    ff = form_factor(drag, speed, area, 1000.0, 1e-6, length)
    assert ff.one_plus_k == pytest.approx(1.15)
    assert ff.std == pytest.approx(0.05)
    np.testing.assert_allclose(ff.values, k_values)


def test_form_factor_is_the_mean_over_tested_speeds_not_over_runs():
    # five repeats at 2 m/s (within 2 % of each other) and one run at 1 and 1.5 m/s: each
    # tested speed weighs the same, so 1 + k = mean(1.10, 1.20, 1.30) = 1.20, not the run
    # mean (1.10 + 1.20 + 5 x 1.30) / 7 = 1.257
    area, length, rho, nu = 0.05, 0.35, 1000.0, 1e-6
    speed = np.array([1.0, 1.5, 2.0, 1.99, 2.01, 2.0, 2.02])
    k_values = np.array([1.10, 1.20, 1.29, 1.31, 1.30, 1.30, 1.30])
    drag = _synthetic_drag(speed, k_values, area, rho, nu, length)
    ff = form_factor(drag, speed, area, rho, nu, length)
    assert ff.n == 3 and ff.n_runs == 7
    np.testing.assert_allclose(ff.speeds, [1.0, 1.5, np.mean(speed[2:])])
    np.testing.assert_allclose(ff.speed_values, [1.10, 1.20, 1.30])
    np.testing.assert_array_equal(ff.speed_runs, [1, 1, 5])
    assert ff.one_plus_k == pytest.approx(1.20, rel=1e-12)
    assert ff.std == pytest.approx(0.10, rel=1e-12)  # s.d. of (1.10, 1.20, 1.30)
    np.testing.assert_allclose(ff.values, k_values)  # the per-run values are kept


def test_form_factor_with_one_tested_speed_has_no_spread():
    speed = np.array([2.0, 2.01, 1.995])
    drag = _synthetic_drag(speed, np.array([1.1, 1.2, 1.3]), 0.05, 1000.0, 1e-6, 0.35)
    ff = form_factor(drag, speed, 0.05, 1000.0, 1e-6, 0.35)
    assert (ff.n, ff.n_runs) == (1, 3)
    assert ff.one_plus_k == pytest.approx(1.2) and math.isnan(ff.std)


def test_speed_groups_chain_repeats_within_two_percent():
    groups = speed_groups([2.0, 0.8, 1.99, 1.2, 2.03, 0.81, 1.26])
    # 0.8/0.81 (1.25 %) and 1.99/2.0/2.03 (< 2 % steps) are repeats; 1.2 -> 1.26 is 5 %
    np.testing.assert_array_equal(groups, [3, 0, 3, 1, 3, 0, 2])
    assert speed_groups([]).size == 0
    np.testing.assert_array_equal(speed_groups([1.0, 1.04], rel_tol=0.05), [0, 0])


def test_form_factor_without_turbulent_points_raises():
    with pytest.raises(ValueError, match="No steady point reaches"):
        form_factor([0.01, 0.02], [0.1, 0.2], 0.05, 1000.0, 1e-6, 0.35)


def test_ittc57_drag_formula():
    u, length, area = 2.0, 1.412, 0.773
    re = u * length / NU_P
    expected = 0.5 * RHO_P * area * u**2 * (1.15 * ittc57_cf(re) + 0.0004)
    assert ittc57_drag(u, length, area, RHO_P, NU_P, 1.15, 0.0004) == pytest.approx(expected)


def test_prime_and_prototype_values():
    rho, length = 1025.0, 1.412
    assert prototype_value(-0.01, rho, length, "added_mass") == pytest.approx(
        -0.01 * 0.5 * rho * length**3
    )
    assert prototype_value(-0.02, rho, length, "damping") == pytest.approx(
        -0.02 * 0.5 * rho * length**2
    )
    for kind in ("added_mass", "damping"):
        value = prototype_value(-0.0123, rho, length, kind)
        assert prime_value(value, rho, length, kind) == pytest.approx(-0.0123)
    with pytest.raises(ValueError, match="added_mass"):
        prototype_value(1.0, rho, length, "stiffness")
    with pytest.raises(ValueError, match="damping"):
        prime_value(1.0, rho, length, "inertia")


def test_scaling_table_small_worked_case():
    # lambda = 4, equal water, R_m = 10 U^2: worked by hand below.
    lam, l_m, l_p = 4.0, 0.25, 1.0
    rho, nu = 1000.0, 1.0e-6
    table = scaling_table(
        [2.0, 4.0],
        scale=lam,
        length_model=l_m,
        length_prototype=l_p,
        rho_m=rho,
        nu_m=nu,
        rho_p=rho,
        nu_p=nu,
        resistance_model=lambda u: 10.0 * u**2,
        tested_speed_range=(0.5, 1.5),
        wetted_area_model=0.01,
        one_plus_k=1.2,
    )
    assert tuple(table.columns) == SCALING_COLUMNS
    assert tuple(table.columns[:7]) == (
        "speed_prototype",
        "re_prototype",
        "fn_prototype",
        "speed_model_froude",
        "speed_model_reynolds",
        "drag_froude",
        "drag_ittc57",
    )
    row = table.iloc[0]
    assert row.speed_prototype == 2.0
    assert row.re_prototype == pytest.approx(2.0e6)
    assert row.fn_prototype == pytest.approx(2.0 / math.sqrt(9.80665))
    assert row.speed_model_froude == pytest.approx(1.0)
    assert row.speed_model_reynolds == pytest.approx(8.0)
    # R_m(1 m/s) = 10 N; x 4^3 = 640 N
    assert row.drag_froude == pytest.approx(640.0)
    # S_p = 0.01 x 16 = 0.16 m^2; C_F(2e6) = 0.075 / (6.30103 - 2)^2 = 0.0040543;
    # R = 0.5 x 1000 x 0.16 x 2^2 x 1.2 x 0.0040543 = 1.55685 N
    assert row.drag_ittc57 == pytest.approx(1.55685, rel=1e-5)
    assert bool(row.froude_in_tested_range) is True
    assert bool(row.reynolds_in_tested_range) is False
    assert row.re_model_froude == pytest.approx(2.5e5)
    second = table.iloc[1]
    assert second.speed_model_froude == pytest.approx(2.0)
    assert second.drag_froude == pytest.approx(40.0 * 64.0)
    assert bool(second.froude_in_tested_range) is False
    assert table["froude_in_tested_range"].dtype == bool


def test_scaling_table_density_ratio_and_wetted_area_scaling():
    table = scaling_table(
        1.6,
        scale=4.0,
        length_model=0.353,
        length_prototype=1.412,
        rho_m=RHO_M,
        nu_m=NU_M,
        rho_p=RHO_P,
        nu_p=NU_P,
        resistance_model=lambda u: 2.0 * u**2,
        tested_speed_range=(0.2, 2.0),
        wetted_area_model=0.0483,
        one_plus_k=1.1,
        delta_cf=0.0002,
    )
    assert len(table) == 1
    assert table.drag_froude.iloc[0] == pytest.approx(2.0 * 0.8**2 * 64.0 * RHO_P / RHO_M)
    expected = ittc57_drag(1.6, 1.412, 0.0483 * 16.0, RHO_P, NU_P, 1.1, 0.0002)
    assert table.drag_ittc57.iloc[0] == pytest.approx(expected)


def _table(speeds, **kw):
    args = dict(
        scale=4.0, length_model=0.353, length_prototype=1.412, rho_m=RHO_M, nu_m=NU_M,
        rho_p=RHO_P, nu_p=NU_P, resistance_model=lambda u: 0.2 * u**2,
        tested_speed_range=(0.8, 2.0), wetted_area_model=0.0472, one_plus_k=1.5,
    )
    args.update(kw)
    return scaling_table(speeds, **args)


def test_scaling_table_without_wetted_area_leaves_only_ittc57_empty():
    full = _table([1.0, 2.0])
    table = _table([1.0, 2.0], wetted_area_model=None)
    assert table["drag_ittc57"].isna().all()
    rest = [c for c in SCALING_COLUMNS if c != "drag_ittc57"]
    assert table[rest].equals(full[rest])
    assert full["drag_ittc57"].notna().all()
    # an unknown form factor (too few turbulent runs) likewise
    assert _table([1.0, 2.0], one_plus_k=math.nan)["drag_ittc57"].isna().all()


@pytest.mark.parametrize("bad", [math.nan, math.inf, -1.0, 0.0, 1e-9, 5e-5])
def test_scaling_table_refuses_unusable_prototype_speeds(bad):
    with pytest.raises(ValueError, match="prototype speed"):
        _table([1.0, bad])
    with pytest.raises(ValueError, match="prototype speed"):
        check_prototype_speeds([bad], 1.412, NU_P)


def test_check_prototype_speeds_threshold():
    u_min = MIN_PROTOTYPE_REYNOLDS * NU_P / 1.412  # Re_p = 1e3 exactly
    np.testing.assert_array_equal(check_prototype_speeds([u_min * 1.001, 2.0], 1.412, NU_P),
                                  [u_min * 1.001, 2.0])
    with pytest.raises(ValueError, match=r"Re = 999.*below 1e\+03.*at least 0.00084 m/s"):
        check_prototype_speeds([u_min * 0.999], 1.412, NU_P)
    with pytest.raises(ValueError, match="no prototype speed"):
        check_prototype_speeds([], 1.412, NU_P)


def test_scaling_table_rejects_inconsistent_lengths():
    with pytest.raises(ValueError, match="does not match scale"):
        scaling_table(
            [1.0],
            scale=4.0,
            length_model=0.353,
            length_prototype=2.0,
            rho_m=RHO_M,
            nu_m=NU_M,
            rho_p=RHO_P,
            nu_p=NU_P,
            resistance_model=lambda u: u,
            tested_speed_range=(0.2, 2.0),
            wetted_area_model=0.05,
            one_plus_k=1.1,
        )


def test_similarity_statement_without_overlap_and_deep():
    text = similarity_statement((2.0e5, 6.0e5), (1.6e6, 4.8e6), depth_m=0.25, diameter_m=0.05)
    assert "Re = 2e+05 to 6e+05" in text
    assert "Reynolds similarity was not met" in text
    assert "factor of 8" in text
    assert "5 D" in text
    assert "Froude similarity was not needed" in text
    assert text.count(".") >= 4


def test_similarity_statement_overlap_shallow_and_laminar():
    text = similarity_statement((5.0e4, 3.0e5), (2.0e5, 1.0e6), depth_m=0.1, diameter_m=0.05)
    assert "Reynolds similarity was met for Re = 2e+05 to 3e+05" in text
    assert "laminar" in text
    assert "Froude similarity would also be needed" in text


def test_similarity_statement_uses_the_form_factor_laminar_threshold():
    # the model's lowest Re, 1.5e5, lies above the SUT-2 report's 1e5 but below the 2e5 the
    # form factor leaves out ([processing] laminar_re): the statement must say so
    text = similarity_statement((1.5e5, 6.0e5), (1.2e6, 3.0e6))
    assert "Part of the model range lies below Re = 2e+05" in text
    assert "left out of the form factor" in text
    assert "All model tests were above" not in text
    low = similarity_statement((1.5e5, 6.0e5), (1.2e6, 3.0e6), turbulent_re=1e5)
    assert "All model tests were above Re = 1e+05" in low


def test_similarity_statement_without_depth_and_bad_arguments():
    text = similarity_statement((2.0e5, 6.0e5), (1.0e6, 5.0e6))
    assert "depth" not in text
    with pytest.raises(ValueError, match="both"):
        similarity_statement((2.0e5, 6.0e5), (1.0e6, 5.0e6), depth_m=0.25)
    with pytest.raises(ValueError, match="re_model_range"):
        similarity_statement((0.0, 6.0e5), (1.0e6, 5.0e6))


# ------------------------------------------------------------ issue 22: trend and recommendation
def test_form_factor_trend_finds_a_rise_with_reynolds_number():
    """A form factor rising by 0.08 per 10^5 of Re with little scatter is a significant trend,
    named with its ends; the same mean with the points shuffled flat is not."""
    from towtank.analysis.similarity import form_factor_trend, form_factor_trend_statement

    re = np.array([2.68e5, 4.02e5, 5.36e5, 6.70e5])
    k = np.array([1.365, 1.509, 1.616, 1.701])
    t = form_factor_trend(re, k)
    assert t.dof == 2 and t.significant
    assert t.slope == pytest.approx(np.polyfit(re, k, 1)[0], rel=1e-12)
    assert 0 < t.ci_low < t.slope < t.ci_high
    assert t.p_value < 0.05
    assert t.first == (2.68e5, 1.365) and t.last == (6.70e5, 1.701)
    text = form_factor_trend_statement(t, float(k.mean()))
    assert text.startswith("1 + k rises with Re from 1.365")
    assert "Reynolds dependence" in text and "laminar" in text and "average" in text
    assert f"Used: the mean {k.mean():.3f}" in text
    flat = form_factor_trend(re, np.array([1.55, 1.50, 1.60, 1.54]))
    assert not flat.significant and flat.ci_low < 0 < flat.ci_high
    assert "no significant trend" in form_factor_trend_statement(flat, 1.548)
    two = form_factor_trend(re[:2], k[:2])
    assert math.isnan(two.slope) and not two.significant
    assert form_factor_trend_statement(two, 1.4) == ""


def test_form_factor_keeps_the_reynolds_number_of_each_tested_speed():
    u = np.array([1.0, 2.0, 2.0])
    re = u * 0.353 / 1.05e-6
    ff = form_factor(np.array([0.3, 1.1, 1.1]), u, 0.0472, 998.6, 1.05e-6, 0.353)
    np.testing.assert_allclose(ff.speed_reynolds, [re[0], re[1]])


def test_recommendation_is_ittc57_for_a_deep_body_and_none_near_the_surface():
    from towtank.analysis.similarity import recommend_resistance

    deep = recommend_resistance(5.0, True)
    assert deep.column == "drag_ittc57"
    assert "no waves" in deep.rule and "Reynolds number" in deep.rule
    assert "not a prototype resistance" in deep.rule
    assert recommend_resistance(None, True).column == "drag_ittc57"
    assert "depth_m not given" in recommend_resistance(None, True).rule
    assert recommend_resistance(2.0, True).column == "none"
    assert "wave-making" in recommend_resistance(2.0, True).rule
    assert recommend_resistance(5.0, False).column == "none"
