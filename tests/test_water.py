"""Water properties against the ITTC 7.5-02-01-03 (2011) tables."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from towtank.reference.water import (
    WaterProperties,
    WaterPropertyWarning,
    density,
    kinematic_viscosity,
    water_properties,
)


@pytest.mark.parametrize(
    ("temperature_C", "rho", "nu"),
    [(15.0, 999.10, 1.1386e-6), (20.0, 998.21, 1.0034e-6)],
)
def test_fresh_water_matches_ittc_table(temperature_C, rho, nu):
    props = water_properties(temperature_C)
    assert isinstance(props, WaterProperties)
    assert props.rho == pytest.approx(rho, rel=2e-5)
    assert props.nu == pytest.approx(nu, rel=1e-3)
    assert props.mu == pytest.approx(props.nu * props.rho, rel=1e-12)
    assert props.water_type == "fresh"
    assert props.salinity_g_kg == 0.0
    assert props.temperature_C == temperature_C


def test_sea_water_matches_ittc_table():
    props = water_properties(15.0, "sea", 35.165)
    assert props.rho == pytest.approx(1025.98, rel=5e-4)
    assert props.nu == pytest.approx(1.1893e-6, rel=5e-3)
    assert props.salinity_g_kg == 35.165


def test_sea_water_default_salinity_is_standard():
    assert water_properties(15.0, "sea").salinity_g_kg == 35.165
    assert density(15.0, "sea") == density(15.0, "sea", 35.165)


def test_helpers_agree_with_water_properties():
    props = water_properties(18.3, "sea", 30.0)
    assert density(18.3, "sea", 30.0) == props.rho
    assert kinematic_viscosity(18.3, "sea", 30.0) == props.nu


def test_arrays_are_accepted_elementwise():
    temps = np.array([[5.0, 15.0], [20.0, 25.0]])
    props = water_properties(temps, "fresh")
    assert props.rho.shape == temps.shape
    assert props.nu.shape == temps.shape
    for idx in np.ndindex(temps.shape):
        assert props.rho[idx] == water_properties(float(temps[idx])).rho
        assert props.nu[idx] == water_properties(float(temps[idx])).nu
    assert kinematic_viscosity([15.0, 20.0]) == pytest.approx([1.1386e-6, 1.0034e-6], rel=1e-3)


def test_scalar_input_gives_floats():
    props = water_properties(15)
    assert isinstance(props.rho, float)
    assert isinstance(props.nu, float)


@pytest.mark.parametrize("temperature_C", [-1.0, 41.0, 60.0])
def test_warns_outside_temperature_range(temperature_C):
    with pytest.warns(WaterPropertyWarning, match="outside"):
        props = water_properties(temperature_C)
    assert 950.0 < props.rho < 1001.0


def test_warns_outside_temperature_range_for_arrays():
    with pytest.warns(WaterPropertyWarning):
        water_properties(np.array([10.0, 45.0]), "sea")


@pytest.mark.parametrize("salinity", [45.0, 60.0])
def test_warns_outside_salinity_range(salinity):
    with pytest.warns(WaterPropertyWarning, match="Salinity"):
        water_properties(15.0, "sea", salinity)


def test_no_warning_inside_ranges():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        water_properties(0.0)
        water_properties(40.0, "sea", 42.0)
        water_properties(10.0, "sea", 0.0)


def test_warning_category_is_a_user_warning():
    assert issubclass(WaterPropertyWarning, UserWarning)


def test_unknown_water_type_names_valid_ones():
    with pytest.raises(ValueError, match="'fresh'.*'sea'"):
        water_properties(15.0, "brackish")


def test_invalid_inputs_raise():
    with pytest.raises(ValueError, match="fresh water"):
        water_properties(15.0, "fresh", 35.0)
    with pytest.raises(ValueError, match="Salinity"):
        water_properties(15.0, "sea", -1.0)
    with pytest.raises(ValueError, match="finite"):
        water_properties(float("nan"))
    with pytest.raises(ValueError, match="not liquid"):
        with pytest.warns(WaterPropertyWarning):
            water_properties(120.0)


def test_zero_salinity_sea_water_is_fresh_water():
    assert density(12.0, "sea", 0.0) == pytest.approx(density(12.0), rel=1e-9)
    assert kinematic_viscosity(12.0, "sea", 0.0) == pytest.approx(kinematic_viscosity(12.0))


pairs_above_4C = st.tuples(
    st.floats(min_value=4.1, max_value=39.9), st.floats(min_value=0.01, max_value=35.0)
).map(lambda p: (p[0], min(p[0] + p[1], 40.0)))

pairs_0_to_40C = st.tuples(
    st.floats(min_value=0.0, max_value=39.99), st.floats(min_value=0.01, max_value=40.0)
).map(lambda p: (p[0], min(p[0] + p[1], 40.0)))


@settings(max_examples=40, deadline=None)
@given(pairs_above_4C)
def test_fresh_density_decreases_with_temperature_above_4C(pair):
    t1, t2 = pair
    assert density(t2) < density(t1)


@settings(max_examples=40, deadline=None)
@given(pairs_0_to_40C, st.sampled_from(["fresh", "sea"]))
def test_viscosity_decreases_with_temperature(pair, water_type):
    t1, t2 = pair
    assert kinematic_viscosity(t2, water_type) < kinematic_viscosity(t1, water_type)


@settings(max_examples=40, deadline=None)
@given(st.floats(min_value=0.0, max_value=40.0), st.floats(min_value=1.0, max_value=42.0))
def test_sea_water_denser_than_fresh(temperature_C, salinity):
    assert density(temperature_C, "sea", salinity) > density(temperature_C)


# ------------------------------------------------------------- the medium of a protocol section
def test_water_at_gives_the_ittc_water_and_the_cipm_air():
    """water_at: fresh water at 15 °C is the ITTC table's (999.10 kg/m³, 1.1386e-6 m²/s), sea
    water denser, air the CIPM-2007 density at the given pressure and humidity; outside the
    ITTC range it says nothing (the protocol's checks do)."""
    from towtank.reference.air import air_properties
    from towtank.reference.water import water_at

    rho, nu = water_at(15.0, "fresh", None)
    assert rho == pytest.approx(999.10, rel=2e-5) and nu == pytest.approx(1.1386e-6, rel=1e-3)
    assert water_at(15.0, "sea", None)[0] == pytest.approx(1025.98, rel=2e-5)
    air = air_properties(20.0, 90_000.0, 30.0)
    assert water_at(20.0, "air", None, 90_000.0, 30.0) == (float(air.rho), float(air.nu))
    assert water_at(20.0, "air", None)[0] > water_at(20.0, "air", None, 90_000.0)[0]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert water_at(45.0, "fresh", None)[0] < rho  # no WaterPropertyWarning


def test_medium_at_reads_the_section_and_a_runs_temperature():
    from towtank.analysis.similarity import medium_at
    from towtank.ingest.protocol_types import Water
    from towtank.reference.water import water_at

    sea = Water(type="sea", temperature_C=10.0, salinity_g_kg=30.0)
    assert medium_at(sea) == water_at(10.0, "sea", 30.0)
    assert medium_at(sea, 20.0) == water_at(20.0, "sea", 30.0)
    assert medium_at(sea, 20.0)[1] < medium_at(sea)[1]  # warmer water, thinner
