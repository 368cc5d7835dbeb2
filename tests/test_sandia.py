"""Tests of towtank.reference.sandia: the Sheldahl & Klimas (1981) NACA 0015 table and its
interpolation."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from towtank.reference import sandia
from towtank.reference.sandia import SandiaRangeWarning, section_coefficients


def _value(re: float, alpha: float, column: str) -> float:
    t = sandia.table()
    row = t[(t["reynolds"] == re) & (t["alpha_deg"] == alpha)]
    assert len(row) == 1
    return float(row[column].iloc[0])


def test_table_is_a_complete_grid():
    t = sandia.table()
    assert list(t.columns) == ["reynolds", "alpha_deg", "cl", "cd"]
    assert len(t) == 11 * 59
    assert t.groupby("reynolds")["alpha_deg"].count().eq(59).all()
    assert t["alpha_deg"].min() == 0 and t["alpha_deg"].max() == 180


def test_reynolds_numbers():
    re = sandia.reynolds_numbers()
    np.testing.assert_array_equal(
        re, [1e4, 2e4, 4e4, 8e4, 1.6e5, 3.6e5, 7e5, 1e6, 2e6, 5e6, 1e7]
    )


def test_source_names_the_report():
    text = sandia.source()
    assert "SAND80-2114" in text
    assert "Sheldahl" in text
    assert not any(line.startswith("#") for line in text.splitlines())


def test_table_is_a_copy():
    t = sandia.table()
    t.loc[:, "cl"] = 99.0
    assert sandia.table()["cl"].max() < 99.0


def test_every_tabulated_point_is_reproduced_exactly():
    t = sandia.table()
    alpha = t["alpha_deg"].to_numpy()
    re = t["reynolds"].to_numpy()
    cl, cd = section_coefficients(alpha, re)
    np.testing.assert_array_equal(cl, t["cl"].to_numpy())
    np.testing.assert_array_equal(cd, t["cd"].to_numpy())
    # and the mirrored negative angles
    cl_neg, cd_neg = section_coefficients(-alpha, re)
    np.testing.assert_array_equal(cl_neg, -t["cl"].to_numpy())
    np.testing.assert_array_equal(cd_neg, t["cd"].to_numpy())


def test_log_linear_interpolation_in_reynolds_midpoint():
    # Re = sqrt(1e6 * 2e6) is halfway between the two in log10(Re): the plain mean.
    cl, cd = section_coefficients(12.0, math.sqrt(1e6 * 2e6))
    assert float(cl) == pytest.approx((1.0971 + 1.1667) / 2, rel=1e-12)
    assert float(cd) == pytest.approx(
        (_value(1e6, 12, "cd") + _value(2e6, 12, "cd")) / 2, rel=1e-12
    )


def test_log_linear_interpolation_in_reynolds_quarter():
    # Re = 1e4 * 2**0.25 is a quarter of the way from 1e4 to 2e4 in log10(Re).
    # Hand-computed: 0.75 * 0.0162 + 0.25 * 0.3359 = 0.096125 at alpha = 5 deg.
    cl, _ = section_coefficients(5.0, 1e4 * 2**0.25)
    assert float(cl) == pytest.approx(0.096125, rel=1e-12)
    # not linear in Re itself: that would give 0.0162 + 0.1892 * (2**0.25 - 1) = 0.0512...
    assert abs(float(cl) - (0.0162 + (0.3359 - 0.0162) * (2**0.25 - 1))) > 0.01


def test_linear_in_alpha_between_integer_degrees():
    # Re = 1e6: C_L(12) = 1.0971, C_L(13) = 1.0957 -> C_L(12.3) = 1.0971 - 0.3 * 0.0014.
    cl, cd = section_coefficients([12.3, -12.3], 1e6)
    np.testing.assert_allclose(cl, [1.09668, -1.09668], rtol=1e-12)
    expected_cd = 0.7 * _value(1e6, 12, "cd") + 0.3 * _value(1e6, 13, "cd")
    np.testing.assert_allclose(cd, [expected_cd, expected_cd], rtol=1e-12)


def test_linear_in_alpha_on_the_coarse_part_of_the_table():
    cl, _ = section_coefficients(32.0, 1e6)
    expected = 0.6 * _value(1e6, 30, "cl") + 0.4 * _value(1e6, 35, "cl")
    assert float(cl) == pytest.approx(expected, rel=1e-12)


def test_bilinear_alpha_then_log_re():
    re = math.sqrt(1e6 * 2e6)
    at_1e6 = 0.7 * _value(1e6, 12, "cl") + 0.3 * _value(1e6, 13, "cl")
    at_2e6 = 0.7 * _value(2e6, 12, "cl") + 0.3 * _value(2e6, 13, "cl")
    cl, _ = section_coefficients(12.3, re)
    assert float(cl) == pytest.approx(0.5 * (at_1e6 + at_2e6), rel=1e-12)


def test_broadcasting():
    alpha = np.array([[0.0], [5.0], [-5.0]])
    re = np.array([1e5, 1e6, 3e6, 1e7])
    cl, cd = section_coefficients(alpha, re)
    assert cl.shape == cd.shape == (3, 4)
    np.testing.assert_array_equal(cl[1], -cl[2])


@settings(deadline=None, max_examples=300)
@given(
    alpha=st.floats(-180.0, 180.0, allow_nan=False),
    log_re=st.floats(4.0, 7.0, allow_nan=False),
)
def test_symmetry_in_alpha(alpha, log_re):
    re = 10.0**log_re
    cl_p, cd_p = section_coefficients(alpha, re)
    cl_m, cd_m = section_coefficients(-alpha, re)
    assert float(cl_m) == -float(cl_p)
    assert float(cd_m) == float(cd_p)
    assert np.isfinite(cl_p) and float(cd_p) > 0


@settings(deadline=None, max_examples=200)
@given(
    alpha=st.floats(0.0, 180.0, allow_nan=False),
    log_re=st.floats(4.0, 7.0, allow_nan=False),
)
def test_interpolant_stays_within_its_corner_values(alpha, log_re):
    t = sandia.table()
    grid_a = np.unique(t["alpha_deg"])
    grid_r = sandia.reynolds_numbers()
    j = min(np.searchsorted(grid_a, alpha, side="right") - 1, grid_a.size - 2)
    i = min(np.searchsorted(np.log10(grid_r), log_re, side="right") - 1, grid_r.size - 2)
    corners = [
        _value(grid_r[ii], grid_a[jj], "cl") for ii in (i, i + 1) for jj in (j, j + 1)
    ]
    cl, _ = section_coefficients(alpha, 10.0**log_re)
    assert min(corners) - 1e-12 <= float(cl) <= max(corners) + 1e-12


def test_reynolds_below_range_is_clamped_with_warning():
    with pytest.warns(SandiaRangeWarning, match=r"5\.0e3 is below .*lowest Re = 1\.0e4"):
        cl, cd = section_coefficients(5.0, 5e3)
    ref = section_coefficients(5.0, 1e4)
    assert float(cl) == float(ref[0]) and float(cd) == float(ref[1])


def test_reynolds_above_range_is_clamped_with_warning():
    with pytest.warns(SandiaRangeWarning, match=r"2\.0e7 is above .*highest Re = 1\.0e7"):
        cl, cd = section_coefficients(12.0, 2e7)
    assert float(cl) == _value(1e7, 12, "cl")
    assert float(cd) == _value(1e7, 12, "cd")


def test_no_warning_inside_range():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        section_coefficients([0.0, 90.0, -180.0], [1e4, 1e7, 3e5])


def test_out_of_range_nan_and_raise():
    cl, cd = section_coefficients([5.0, 5.0], [5e3, 1e6], out_of_range="nan")
    assert np.isnan(cl[0]) and np.isnan(cd[0])
    assert np.isfinite(cl[1])
    with pytest.raises(ValueError, match="outside"):
        section_coefficients(5.0, 5e3, out_of_range="raise")
    with pytest.raises(ValueError, match="out_of_range"):
        section_coefficients(5.0, 1e6, out_of_range="extrapolate")  # type: ignore[arg-type]


@pytest.mark.parametrize("alpha", [180.5, -181.0, 360.0, np.inf])
def test_angle_beyond_180_raises_naming_it(alpha):
    with pytest.raises(ValueError, match=f"{alpha:g}"):
        section_coefficients([10.0, alpha], 1e6)


def test_plus_minus_180_is_allowed():
    cl, cd = section_coefficients([180.0, -180.0], 1e6)
    np.testing.assert_array_equal(cl, [0.0, 0.0])
    np.testing.assert_array_equal(cd, [_value(1e6, 180, "cd")] * 2)


def test_non_positive_reynolds_raises():
    with pytest.raises(ValueError, match="not positive"):
        section_coefficients(5.0, 0.0)


def test_nan_propagates_without_warning():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        cl, cd = section_coefficients([np.nan, 5.0, 5.0], [1e6, np.nan, 1e6])
    assert np.isnan(cl[:2]).all() and np.isnan(cd[:2]).all()
    assert cl[2] == pytest.approx(0.55)
