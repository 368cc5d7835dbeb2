"""Tests of towtank.analysis.fins: lifting line, fin table, curves, warnings, control
derivatives."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from towtank.analysis import fins
from towtank.reference import sandia

A0_SANDIA = 0.11 * 180.0 / math.pi  # Sandia NACA 0015 at Re >= 3.6e5: 0.11 per deg up to 6 deg


def linear_section(a0: float = 2 * math.pi, cd0: float = 0.01):
    """A synthetic 2-D section: C_l = a0 alpha [rad], C_d = cd0."""

    def section(alpha_deg, reynolds):
        alpha = np.asarray(alpha_deg, dtype=float)
        shape = np.broadcast_shapes(alpha.shape, np.shape(reynolds))
        return np.broadcast_to(a0 * np.deg2rad(alpha), shape), np.full(shape, cd0)

    return section


# --------------------------------------------------------------------------------------------
# Lifting line
# --------------------------------------------------------------------------------------------


def test_finite_span_slope_closed_form():
    slope = fins.finite_span_slope(2 * math.pi, 6.0)
    assert float(slope) == pytest.approx(2 * math.pi / (1 + 2 / 6), rel=1e-15)
    assert float(slope) == pytest.approx(4.71238898038469, rel=1e-12)
    # e < 1 lowers it further
    assert fins.finite_span_slope(2 * math.pi, 6.0, e=0.8) < slope


def test_induced_drag_closed_form():
    assert float(fins.induced_drag(0.5, 6.0)) == pytest.approx(0.25 / (6 * math.pi), rel=1e-15)
    assert float(fins.induced_drag(0.5, 6.0)) == pytest.approx(0.013262911924, rel=1e-10)
    assert float(fins.induced_drag(-0.5, 6.0, e=0.5)) == pytest.approx(0.25 / (3 * math.pi))


def test_wall_mounting_doubles_aspect_ratio():
    free = fins.effective_aspect_ratio(0.30, 0.10)
    wall = fins.effective_aspect_ratio(0.30, 0.10, mounting="wall")
    assert float(free) == pytest.approx(3.0)
    assert float(wall) == pytest.approx(2 * float(free))
    with pytest.raises(ValueError, match="mounting"):
        fins.effective_aspect_ratio(0.3, 0.1, mounting="endplate")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="positive"):
        fins.effective_aspect_ratio(-0.3, 0.1)


@pytest.mark.parametrize("a0", [2 * math.pi, 5.5, 6.8])
@pytest.mark.parametrize("aspect_ratio", [0.5, 1.0, 6.0, 30.0])
@pytest.mark.parametrize("e", [1.0, 0.7])
def test_linear_section_reproduces_closed_form(a0, aspect_ratio, e):
    alpha = np.array([-10.0, -3.0, 0.0, 1.0, 4.0, 12.0])
    cl, cd = fins.finite_span_coefficients(
        alpha, 1e6, aspect_ratio, e, section=linear_section(a0, cd0=0.01)
    )
    expected_slope = fins.finite_span_slope(a0, aspect_ratio, e)
    np.testing.assert_allclose(cl, expected_slope * np.deg2rad(alpha), rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(
        cd, 0.01 + cl**2 / (math.pi * e * aspect_ratio), rtol=1e-12, atol=1e-15
    )


def test_exact_case_ar6_e1_a0_2pi():
    cl, _ = fins.finite_span_coefficients(5.0, 1e6, 6.0, section=linear_section())
    assert float(cl) / math.radians(5.0) == pytest.approx(4.71238898038469, rel=1e-12)


def test_sandia_solution_is_self_consistent_everywhere():
    alpha = np.linspace(-180, 180, 721)
    for aspect_ratio in (0.5, 2.0, 8.0):
        for re in (2e4, 1.6e5, 1e6, 1e7):
            cl, cd = fins.finite_span_coefficients(alpha, re, aspect_ratio)
            assert np.isfinite(cl).all() and np.isfinite(cd).all()
            alpha_i = np.rad2deg(cl / (math.pi * aspect_ratio))
            eff = alpha - alpha_i
            eff = np.where(np.abs(eff) > 180, (eff + 180) % 360 - 180, eff)
            cl2d, cd2d = sandia.section_coefficients(eff, re)
            np.testing.assert_allclose(cl, cl2d, atol=1e-8)
            np.testing.assert_allclose(cd, cd2d + cl**2 / (math.pi * aspect_ratio), atol=1e-8)


def test_sandia_linear_range_matches_closed_form():
    alpha = np.array([1.0, 2.0, 3.0])
    cl, _ = fins.finite_span_coefficients(alpha, 1e6, 4.0)
    expected = fins.finite_span_slope(A0_SANDIA, 4.0) * np.deg2rad(alpha)
    np.testing.assert_allclose(cl, expected, rtol=1e-9)


def test_finite_span_broadcasts_and_propagates_nan():
    cl, cd = fins.finite_span_coefficients([[2.0], [np.nan]], [1e6, np.nan, 2e6], 5.0)
    assert cl.shape == cd.shape == (2, 3)
    assert np.isnan(cl[1]).all() and np.isnan(cl[0, 1])
    assert np.isfinite(cl[0, [0, 2]]).all()


def test_finite_span_clamp_warning_once():
    with pytest.warns(sandia.SandiaRangeWarning) as record:
        fins.finite_span_coefficients([2.0, 4.0], 5e3, 5.0)
    assert len([w for w in record if issubclass(w.category, sandia.SandiaRangeWarning)]) == 1


@settings(deadline=None, max_examples=200)
@given(
    alpha=st.floats(-8.0, 8.0, allow_nan=False),
    log_re=st.floats(math.log10(1.6e5), 7.0, allow_nan=False),
    aspect_ratio=st.floats(0.3, 50.0, allow_nan=False),
    e=st.floats(0.5, 1.0, allow_nan=False),
)
def test_finite_span_lift_never_exceeds_2d_in_linear_range(alpha, log_re, aspect_ratio, e):
    re = 10.0**log_re
    cl3d, cd3d = fins.finite_span_coefficients(alpha, re, aspect_ratio, e)
    cl2d, cd2d = sandia.section_coefficients(alpha, re)
    assert abs(float(cl3d)) <= abs(float(cl2d)) + 1e-12
    assert float(cl3d) * alpha >= 0  # same sign as the angle
    # and the drag is the 2-D drag at the effective angle plus a non-negative induced part
    alpha_eff = alpha - math.degrees(float(cl3d) / (math.pi * e * aspect_ratio))
    _, cd_eff = sandia.section_coefficients(alpha_eff, re)
    assert float(cd3d) - float(cd_eff) >= -1e-15


@settings(deadline=None, max_examples=300)
@given(
    cl=st.floats(-5.0, 5.0, allow_nan=False),
    aspect_ratio=st.floats(0.1, 100.0, allow_nan=False),
    e=st.floats(0.1, 1.0, allow_nan=False),
)
def test_induced_drag_is_never_negative(cl, aspect_ratio, e):
    assert float(fins.induced_drag(cl, aspect_ratio, e)) >= 0.0


# --------------------------------------------------------------------------------------------
# Fin table
# --------------------------------------------------------------------------------------------


def sandia_runs() -> pd.DataFrame:
    """Synthetic fin runs whose measured coefficients are Sandia's own 2-D values."""
    rows = []
    run = 1
    for speed, re in ((0.99, 1e6), (1.0, 1e6), (1.01, 1e6), (2.0, 2e6), (2.02, 2e6)):
        for angle in (-4.0, 0.0, 2.0, 4.0, 6.0, 8.0, 10.0, 12.0, 14.0, 16.0):
            cl, cd = sandia.section_coefficients(angle, re)
            rows.append(
                {
                    "run": run,
                    "angle_deg": angle,
                    "speed_mean": speed,
                    "re": re,
                    "cl": float(cl),
                    "cd": float(cd),
                    "drag_mean": 10.0 * float(cd) * speed**2,
                    "lift_mean": 10.0 * float(cl) * speed**2,
                    "config": "fin",
                }
            )
            run += 1
    return pd.DataFrame(rows)


def test_fin_table_columns_and_values():
    runs = sandia_runs()
    table = fins.fin_table(runs, aspect_ratio=4.0)
    assert tuple(table.columns) == fins.FIN_TABLE_COLUMNS
    assert tuple(table.columns[:8]) == (
        "run", "angle_deg", "speed_mean", "re", "cl", "cd", "cl_sandia", "cd_sandia",
    )
    assert len(table) == len(runs)
    np.testing.assert_array_equal(table["cl"], table["cl_sandia"])
    np.testing.assert_array_equal(table["cd"], table["cd_sandia"])
    np.testing.assert_array_equal(table["run"], runs["run"])
    np.testing.assert_array_equal(table["drag_mean"], runs["drag_mean"])
    # 3-D expectation: lower lift, more drag (away from zero lift)
    lifting = (table["angle_deg"] != 0) & (table["angle_deg"].abs() <= 10)
    assert (table.loc[lifting, "cl_3d"].abs() < table.loc[lifting, "cl_sandia"].abs()).all()
    assert (table["cd_3d"] >= table["cd_sandia"] - 1e-12)[table["angle_deg"].abs() <= 10].all()
    assert sorted(table["speed_group"].unique()) == [1.0, 2.01]


def test_fin_table_requires_columns():
    with pytest.raises(ValueError, match="lift_mean"):
        fins.fin_table(sandia_runs().drop(columns="lift_mean"), aspect_ratio=4.0)


def test_speed_groups():
    speeds = [0.50, 0.51, 1.00, 1.02, 0.98, np.nan, 1.5]
    labels = fins.speed_groups(speeds)
    np.testing.assert_array_equal(labels[:5], [0.51, 0.51, 1.0, 1.0, 1.0])
    assert np.isnan(labels[5])
    assert labels[6] == 1.5


# --------------------------------------------------------------------------------------------
# Curves
# --------------------------------------------------------------------------------------------


def test_fin_curves_recovers_linear_slope_with_interval():
    rng = np.random.default_rng(20240611)
    true_slope, c0 = 4.3, 0.02
    angles = np.repeat(np.arange(-8.0, 8.1, 2.0), 3)
    cl = true_slope * np.deg2rad(angles) + c0 + rng.normal(0, 0.01, angles.size)
    runs = pd.DataFrame(
        {
            "run": np.arange(angles.size) + 1,
            "angle_deg": angles,
            "speed_mean": 1.5 + rng.normal(0, 0.005, angles.size),
            "re": 1.5e5,
            "cl": cl,
            "cd": 0.02 + 0.5 * np.deg2rad(angles) ** 2,
            "drag_mean": 1.0,
            "lift_mean": 1.0,
        }
    )
    table = fins.fin_table(runs, aspect_ratio=3.0)
    curves = fins.fin_curves(table, linear_max_deg=10.0)
    assert tuple(curves.columns) == fins.CURVE_COLUMNS
    assert len(curves) == 1
    row = curves.iloc[0]
    assert row["n_runs"] == angles.size
    assert row["lift_slope_ci_low"] < true_slope < row["lift_slope_ci_high"]
    assert row["lift_slope"] == pytest.approx(true_slope, abs=0.2)
    assert row["cd_min_angle_deg"] == 0.0
    assert row["cd_min"] == pytest.approx(0.02)


def test_fin_curves_sandia_and_3d_slopes():
    table = fins.fin_table(sandia_runs(), aspect_ratio=4.0)
    curves = fins.fin_curves(table, linear_max_deg=6.0, aspect_ratio=4.0)
    slow = curves.set_index("speed_group").loc[1.0]
    # measured == Sandia here, all in the exactly linear part of the table
    assert slow["lift_slope"] == pytest.approx(A0_SANDIA, rel=1e-9)
    assert slow["lift_slope_sandia_2d"] == pytest.approx(A0_SANDIA, rel=1e-9)
    assert slow["lift_slope_3d"] == pytest.approx(fins.finite_span_slope(A0_SANDIA, 4.0), rel=1e-8)
    # without the aspect ratio the cl_3d column gives the same answer (all runs at the mean Re)
    from_column = fins.fin_curves(table, linear_max_deg=6.0).set_index("speed_group").loc[1.0]
    assert from_column["lift_slope_3d"] == pytest.approx(slow["lift_slope_3d"], rel=1e-8)
    assert slow["re_mean"] == pytest.approx(1e6)
    assert slow["n_runs"] == 30


def test_stall_detection():
    curves = fins.fin_curves(fins.fin_table(sandia_runs(), aspect_ratio=4.0))
    slow = curves.set_index("speed_group").loc[1.0]
    # Sandia at Re = 1e6: C_L peaks at 12 deg (1.0971), tested up to 16 deg
    assert slow["stall_angle_deg"] == 12.0
    assert slow["cl_max"] == pytest.approx(1.0971)
    assert bool(slow["stall_reached"]) is True
    assert slow["cd_min_angle_deg"] == 0.0

    runs = sandia_runs()
    short = runs[runs["angle_deg"] <= 8.0]
    curves = fins.fin_curves(fins.fin_table(short, aspect_ratio=4.0))
    assert curves["stall_angle_deg"].tolist() == [8.0, 8.0]
    assert not curves["stall_reached"].any()


def sandia_group(angles, re: float = 1.14e5, speed: float = 1.0, start: int = 1) -> pd.DataFrame:
    """One speed group of fin runs whose measured coefficients are Sandia's at ``re``."""
    alpha = np.asarray(angles, dtype=float)
    cl, cd = sandia.section_coefficients(alpha, np.full(alpha.shape, re))
    return pd.DataFrame(
        {
            "run": np.arange(alpha.size) + start,
            "angle_deg": alpha,
            "speed_mean": speed,
            "re": re,
            "cl": cl,
            "cd": cd,
            "drag_mean": 1.0,
            "lift_mean": 1.0,
        }
    )


def test_stall_is_found_on_folded_negative_angles():
    """A day at negative angles only: folded to (|α|, sign(α) C_L), it stalls as its mirror."""
    runs = sandia_runs()
    positive = runs[runs["angle_deg"] >= 0]
    mirrored = positive.assign(angle_deg=-positive["angle_deg"], cl=-positive["cl"])
    mirrored = mirrored[mirrored["angle_deg"] < 0]  # negative angles only (0 dropped)
    neg = fins.fin_curves(fins.fin_table(mirrored, aspect_ratio=4.0)).set_index("speed_group")
    pos = fins.fin_curves(fins.fin_table(positive[positive["angle_deg"] > 0], aspect_ratio=4.0))
    pos = pos.set_index("speed_group")
    # Sandia at Re = 1e6: C_L peaks at 12 deg (1.0971)
    assert neg.loc[1.0, "stall_angle_deg"] == 12.0
    assert neg.loc[1.0, "cl_max"] == pytest.approx(1.0971)
    assert bool(neg.loc[1.0, "stall_reached"]) is True
    for col in ("stall_angle_deg", "cl_max", "lift_slope", "lift_slope_sandia_2d"):
        np.testing.assert_allclose(neg[col], pos[col], rtol=1e-12, err_msg=col)
    assert (neg["cd_min_angle_deg"] == -pos["cd_min_angle_deg"]).all()


def test_stall_folds_mixed_signs_before_averaging():
    """±α runs fold onto one curve: the fall after 12 deg is seen at -14 deg only."""
    alpha = [4.0, 8.0, -12.0, 12.0, -14.0, -16.0]
    runs = sandia_group(alpha, re=1e6)
    curves = fins.fin_curves(fins.fin_table(runs, aspect_ratio=4.0))
    assert curves.loc[0, "stall_angle_deg"] == 12.0
    assert bool(curves.loc[0, "stall_reached"]) is True
    assert curves.loc[0, "cl_max"] == pytest.approx(1.0971)  # mean of sign(α) C_L at |α| = 12


def test_lift_slope_excludes_a_stalled_point_in_the_linear_range():
    """At Re = 1.14e5 Sandia's C_L peaks near 9 deg: 10 deg lies in |α| <= 10 but past stall.

    The tested C_L falls from 7.5 to 10 deg, so the stall is 7.5 deg and the slope is fitted
    through 0, 2.5 and 5 deg only; fitting every |α| <= 10 deg (10 deg included) would pull it
    far below the section's linear slope (~5.2 instead of ~6.1 1/rad).
    """
    runs = sandia_group([0.0, 2.5, 5.0, 7.5, 10.0, 15.0, 20.0] * 2)
    table = fins.fin_table(runs, aspect_ratio=1.25)
    row = fins.fin_curves(table, linear_max_deg=10.0, aspect_ratio=1.25).iloc[0]
    assert row["stall_angle_deg"] == 7.5 and bool(row["stall_reached"])
    linear = np.array([0.0, 2.5, 5.0])
    cl, _ = sandia.section_coefficients(linear, 1.14e5)
    expected = np.polyfit(np.deg2rad(linear), cl, 1)[0]
    assert row["lift_slope"] == pytest.approx(expected, rel=1e-9)
    assert row["lift_slope"] > 6.0
    assert row["slope_angles_deg"] == "0 2.5 5"
    with_stalled = np.array([0.0, 2.5, 5.0, 7.5, 10.0])
    cl_all, _ = sandia.section_coefficients(with_stalled, 1.14e5)
    # a fit over the stalled angles too
    assert np.polyfit(np.deg2rad(with_stalled), cl_all, 1)[0] < 5.5
    # the Sandia 2-D and lifting-line slopes use the same angles
    assert row["lift_slope_sandia_2d"] == pytest.approx(expected, rel=1e-9)
    cl3d, _ = fins.finite_span_coefficients(linear, 1.14e5, 1.25)
    assert row["lift_slope_3d"] == pytest.approx(np.polyfit(np.deg2rad(linear), cl3d, 1)[0])
    assert fins.lift_slope_warnings(fins.fin_curves(table)) == []


def test_linear_max_deg_bounds_the_fit():
    runs = sandia_group([0.0, 2.0, 4.0, 6.0, 8.0, 10.0, 12.0, 14.0], re=1e6)
    table = fins.fin_table(runs, aspect_ratio=4.0)
    narrow = fins.fin_curves(table, linear_max_deg=6.0).iloc[0]
    wide = fins.fin_curves(table, linear_max_deg=30.0).iloc[0]
    assert narrow["slope_angles_deg"] == "0 2 4 6"
    assert narrow["lift_slope"] == pytest.approx(A0_SANDIA, rel=1e-9)
    assert wide["stall_angle_deg"] == 12.0
    assert wide["slope_angles_deg"] == "0 2 4 6 8 10"  # stops below the stall, not at 30 deg


def test_no_slope_below_two_non_zero_angles_and_the_warning_says_why():
    """5, 10 and 15 deg at Re = 1.14e5: stall at 10 deg leaves 5 deg alone: no slope, no secant."""
    runs = pd.concat([sandia_group([5.0, 10.0, 15.0] * 2),
                      sandia_group([0.0, 5.0, 10.0, 15.0], re=2.28e5, speed=2.0, start=10),
                      sandia_group([20.0, 25.0], re=2.85e5, speed=2.5, start=20)])
    table = fins.fin_table(runs, aspect_ratio=1.25)
    curves = fins.fin_curves(table, aspect_ratio=1.25)
    assert curves["lift_slope"].isna().all()
    for col in ("lift_slope_ci_low", "lift_slope_ci_high", "lift_slope_sandia_2d",
                "lift_slope_3d"):
        assert curves[col].isna().all(), col
    assert curves["slope_angles_deg"].tolist() == ["5", "0 5", ""]
    assert fins.lift_slope_warnings(curves) == [
        "fin lift slope at U ≈ 1.00 m/s: only 5° lies below stall (10°) within the linear "
        "range (≤ 10°); no slope.",
        "fin lift slope at U ≈ 2.00 m/s: only 0° and 5° lie below stall (10°) within the "
        "linear range (≤ 10°), fewer than two distinct non-zero angles; no slope.",
        "fin lift slope at U ≈ 2.50 m/s: no tested angle lies within the linear range "
        "(≤ 10°); no slope.",
    ]
    slope, source = fins.control_lift_slope(curves)
    assert math.isnan(slope) and "no speed group" in source


def test_a_lift_falling_from_zero_is_no_stall():
    """A lift of reversed sign falls from 0° on: no stall at 0° (it cut every angle off the
    slope fit and blamed the stall), but a negative slope for the plausibility check."""
    runs = sandia_group([0.0, 2.5, 5.0, 7.5, 10.0, 15.0])
    table = fins.fin_table(runs.assign(cl=-runs["cl"]), aspect_ratio=1.25)
    row = fins.fin_curves(table, aspect_ratio=1.25).iloc[0]
    assert not bool(row["stall_reached"])
    assert row["slope_angles_deg"] == "0 2.5 5 7.5 10"
    assert row["lift_slope"] < -3.0
    assert fins.lift_slope_warnings(fins.fin_curves(table)) == []


def test_no_slope_warning_names_the_rejected_runs_of_its_range():
    """A group that lost its 5° run to a rejection says so, not only that the stall leaves
    too few angles; a rejected run past the stall, or of another speed, is not named."""
    table = fins.fin_table(sandia_group([0.0, 2.5, 7.5, 10.0, 15.0]), aspect_ratio=1.25)
    curves = fins.fin_curves(table)
    rejected = pd.DataFrame({"run": [14, 30, 15], "angle_deg": [5.0, 20.0, 5.0],
                             "speed_nominal": [1.0, 1.0, 1.5]})
    assert fins.lift_slope_warnings(curves, rejected=rejected) == [
        "fin lift slope at U ≈ 1.00 m/s: only 0° and 2.5° lie below stall (7.5°) within the "
        "linear range (≤ 10°), fewer than two distinct non-zero angles; no slope (run 14 at "
        "5° was rejected)."
    ]


def test_two_non_zero_angles_fit_through_the_origin():
    runs = sandia_group([2.0, 4.0, 2.0, 4.0], re=1e6)
    row = fins.fin_curves(fins.fin_table(runs, aspect_ratio=4.0)).iloc[0]
    assert row["slope_angles_deg"] == "2 4"
    assert row["lift_slope"] == pytest.approx(A0_SANDIA, rel=1e-9)


def test_section_stall_angle():
    stall = fins.section_stall_angle([1e6, 1.6e5, 1.14e5, np.nan, 1e4])
    # first local maxima of the Sandia table: 12 deg at 1e6, 10 deg at 1.6e5, 3 deg at 1e4;
    # 9 deg between 8e4 (8 deg) and 1.6e5 (10 deg)
    np.testing.assert_array_equal(stall[[0, 1, 2, 4]], [12.0, 10.0, 9.0, 3.0])
    assert np.isnan(stall[3])
    assert fins.section_stall_angle(2e6).shape == ()


def test_finite_span_values_only_for_attached_flow():
    """cl_3d, cd_3d are NaN where the effective angle is past the section's stall."""
    runs = pd.concat([sandia_group(np.arange(0.0, 36.0, 5.0), re=re, speed=u, start=10 * k)
                      for k, (u, re) in enumerate(((1.0, 1.14e5), (1.5, 1.71e5), (2.0, 2.28e5),
                                                   (2.5, 2.85e5)))])
    table = fins.fin_table(runs, aspect_ratio=1.25)
    cl3d, cd3d = fins.finite_span_coefficients(table["angle_deg"], table["re"], 1.25)
    effective = table["angle_deg"] - np.rad2deg(cl3d / (math.pi * 1.25))
    attached = np.abs(effective) <= fins.section_stall_angle(table["re"])
    np.testing.assert_array_equal(table["cl_3d"].notna(), attached)
    np.testing.assert_array_equal(table["cd_3d"].notna(), attached)
    np.testing.assert_allclose(table.loc[attached, "cl_3d"], cl3d[attached], rtol=0, atol=0)
    assert attached[table["angle_deg"] <= 15].all()  # the fin stalls later than its section
    assert not attached[table["angle_deg"] >= 25].any()


def test_force_vs_speed_is_sorted_long_table():
    table = fins.fin_table(sandia_runs(), aspect_ratio=4.0)
    long = fins.force_vs_speed(table)
    assert list(long.columns) == ["angle_deg", "speed_mean", "drag_mean", "lift_mean"]
    assert len(long) == len(table)
    keys = list(zip(long["angle_deg"], long["speed_mean"], strict=True))
    assert keys == sorted(keys)


# --------------------------------------------------------------------------------------------
# Low-Re warnings and control derivatives
# --------------------------------------------------------------------------------------------


def test_low_reynolds_warnings():
    fin_df = pd.DataFrame({"run": [11, 12, 13, 14], "re": [2.0e5, 8.1e4, np.nan, 9.96e4]})
    messages = fins.low_reynolds_warnings(fin_df)
    assert messages == [
        "run 12: Re = 8.1e4 on the chord is below 1e5, where the section data change fast with "
        "Re; the comparison with Sandia is weak.",
        "run 14: Re = 1.0e5 on the chord is below 1e5, where the section data change fast with "
        "Re; the comparison with Sandia is weak.",
    ]
    assert fins.low_reynolds_warnings(fin_df, re_threshold=5e4) == []
    assert fins.low_reynolds_warnings(fin_df, re_threshold=2.5e5)[0].startswith(
        "run 11: Re = 2.0e5 on the chord is below 2.5e5"
    )


def test_control_lift_slope_is_the_mean_linear_range_slope():
    runs = pd.concat([sandia_group([0.0, 2.5, 5.0, 7.5, 10.0, 15.0]),
                      sandia_group([0.0, 2.5, 5.0, 7.5, 10.0, 15.0], re=2.85e5, speed=2.5,
                                   start=10),
                      sandia_group([5.0, 10.0, 15.0], re=1.71e5, speed=1.5, start=20)])
    curves = fins.fin_curves(fins.fin_table(runs, aspect_ratio=1.25), linear_max_deg=8.0)
    slope, source = fins.control_lift_slope(curves, linear_max_deg=8.0)
    by = curves.set_index("speed_group")
    assert math.isnan(by.loc[1.5, "lift_slope"])  # only 5 deg below its 10 deg stall
    assert slope == pytest.approx((by.loc[1.0, "lift_slope"] + by.loc[2.5, "lift_slope"]) / 2)
    assert source == (
        "mean of the measured linear-range lift slopes (|α| ≤ 8°, below stall) of the speed "
        "groups 1.00 m/s (0 2.5 5°), 2.50 m/s (0 2.5 5 7.5°)"
    )
    table = fins.control_derivatives(slope, 0.018, -0.61, 998.6, source)
    assert (table["lift_slope"] == slope).all() and (table["lift_slope_source"] == source).all()


def test_control_derivative_signs_and_values():
    rho, c_la, s_fin, x_fin = 1030.0, 3.12, 0.00665, -0.6827
    table = fins.control_derivatives(c_la, s_fin, x_fin, rho).set_index("symbol")
    assert list(table.index) == ["Y_uudr", "Z_uuds", "M_uuds", "N_uudr"]
    base = rho * c_la * s_fin
    assert table.loc["Y_uudr", "value"] == pytest.approx(base)
    assert table.loc["Z_uuds", "value"] == pytest.approx(-base)
    assert table.loc["M_uuds", "value"] == pytest.approx(base * x_fin)
    assert table.loc["N_uudr", "value"] == pytest.approx(base * x_fin)
    # fins aft (x_fin < 0): Y > 0, Z < 0, M < 0, N < 0 (Prestero's REMUS sign pattern)
    assert table.loc["Y_uudr", "value"] > 0
    assert table.loc["Z_uuds", "value"] < 0
    assert table.loc["M_uuds", "value"] < 0
    assert table.loc["N_uudr", "value"] < 0
    assert table.loc["Y_uudr", "unit"] == "kg/(m*rad)"
    assert table.loc["M_uuds", "unit"] == "kg/rad"
    assert table["convention"].str.contains("Prestero").all()


def test_no_warnings_for_in_range_table():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fins.fin_curves(fins.fin_table(sandia_runs(), aspect_ratio=4.0), aspect_ratio=4.0)


def test_lifting_line_takes_the_attached_root_where_both_exist():
    """Past the section's stall h(α_i) = α_i − C_l,2D(α − α_i)/(π e AR) has a stalled and an
    attached root; at 20° and Re 1.14e5 (AR 1.25) the attached one exists (its effective angle
    is below the section's stall) and is the lifting line's answer, whatever the speed."""
    alpha, ar = 20.0, 1.25
    for re in (1.14e5, 1.7e5, 2.3e5, 2.9e5):
        cl, _ = fins.finite_span_coefficients(alpha, re, ar)
        cl = float(cl)
        alpha_i = cl / (np.pi * ar)
        alpha_eff = alpha - np.rad2deg(alpha_i)
        assert alpha_eff < float(fins.section_stall_angle(re)), re
        cl2d, _ = sandia.section_coefficients(alpha_eff, re)
        assert cl == pytest.approx(float(cl2d), abs=1e-9)  # a root of the lifting line
        assert cl > 0.7, re  # not the stalled root (C_L ≈ 0.26 at the lowest Re)


def test_slopes_of_a_section_not_a_finite_fin_are_named():
    """Issue 16: the fin day's measured slope (6.12 /rad) equals the 2-D section's (6.12)
    while lifting-line theory gives 2.42 for AR 1.25: the report must say the fin behaved
    as a section; a fin whose slopes match the finite span gets no sentence."""
    import pandas as pd

    from towtank.analysis.fins import two_dimensional_warning

    curves = pd.DataFrame({"lift_slope": [6.12, 5.8], "lift_slope_ci_low": [4.8, 4.6],
                           "lift_slope_ci_high": [7.5, 7.0], "lift_slope_sandia_2d": [6.12, 5.8],
                           "lift_slope_3d": [2.42, 2.40]})
    (sentence,) = two_dimensional_warning(curves, 1.25)
    assert "match the 2-D NACA 0015 section" in sentence and "(2.41 /rad)" in sentence
    finite = curves.assign(lift_slope=[2.5, 2.4], lift_slope_ci_low=[2.0, 1.9],
                           lift_slope_ci_high=[3.0, 2.9])
    assert two_dimensional_warning(finite, 1.25) == []
