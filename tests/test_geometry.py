"""Myring hull profile and its integrals."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate

from towtank.reference.geometry import HullGeometry, myring_geometry, myring_radius

SUT2_MODEL = dict(a=0.05875, b=0.1765, c=0.11775, n=2.0, theta_deg=25.0, d=0.05)
# Prestero (2001), REMUS Myring hull parameters
REMUS = dict(
    a=0.191, b=0.654, c=0.541, n=2.0, theta_deg=25.0, d=0.191, a_offset=0.0165, c_offset=0.0368
)


def test_cylinder_alone():
    d, b = 0.05, 0.2
    geo = myring_geometry(a=0.0, b=b, c=0.0, n=2.0, theta_deg=0.0, d=d)
    assert isinstance(geo, HullGeometry)
    assert geo.length == pytest.approx(b)
    assert geo.volume == pytest.approx(math.pi * d**2 * b / 4.0, rel=1e-12)
    assert geo.wetted_area == pytest.approx(math.pi * d * b, rel=1e-12)
    assert geo.lateral_area == pytest.approx(d * b, rel=1e-12)
    assert geo.x_buoyancy == pytest.approx(b / 2.0)
    assert geo.nose_radius == geo.tail_radius == pytest.approx(d / 2.0)


@pytest.mark.parametrize("b", [0.0, 0.3])
def test_hemispherical_nose(b):
    d = 0.05
    r = d / 2.0
    geo = myring_geometry(a=r, b=b, c=0.0, n=2.0, theta_deg=0.0, d=d)
    nose_volume = geo.volume - math.pi * r**2 * b
    nose_area = geo.wetted_area - math.pi * d * b
    assert nose_volume == pytest.approx(2.0 / 3.0 * math.pi * r**3, rel=1e-4)
    assert nose_area == pytest.approx(2.0 * math.pi * r**2, rel=1e-4)
    assert geo.lateral_area - d * b == pytest.approx(math.pi * r**2 / 2.0, rel=1e-4)
    assert geo.nose_radius == 0.0


def test_sut2_model_principal_dimensions():
    geo = myring_geometry(**SUT2_MODEL)
    assert geo.length == pytest.approx(0.353, rel=1e-12)
    assert geo.max_diameter == 0.05
    assert geo.frontal_area == pytest.approx(math.pi * 0.05**2 / 4.0, rel=1e-12)
    d, a, b = 0.05, 0.05875, 0.1765
    area = math.pi * d**2 / 4.0
    inscribed = area * (b + a / 3.0)  # midbody plus a cone on the nose
    circumscribed = area * geo.length
    assert inscribed < geo.volume < circumscribed
    assert d * b < geo.lateral_area < d * geo.length
    assert math.pi * d * b < geo.wetted_area < math.pi * d * geo.length
    assert 0.0 < geo.x_buoyancy < geo.length
    assert geo.tail_radius == pytest.approx(0.0, abs=1e-12)


def test_remus_projected_area_matches_prestero():
    geo = myring_geometry(**REMUS)
    # Prestero (2001): l_f = 0.828 m, l = 1.33 m, hull projected area A_p = 0.226 m^2
    assert geo.length == pytest.approx(1.33, abs=0.005)
    assert geo.lateral_area == pytest.approx(0.226, rel=5e-3)
    assert geo.frontal_area == pytest.approx(0.0285, rel=1e-2)
    assert geo.nose_radius > 0.0
    assert geo.tail_radius > 0.0


def test_radius_profile_sections():
    p = SUT2_MODEL
    r = myring_radius(np.array([-0.01, 0.0, 0.05875, 0.1, 0.23525, 0.353, 0.4]), **p)
    assert r[0] == 0.0 and r[-1] == 0.0
    assert r[1] == pytest.approx(0.0, abs=1e-15)
    assert r[2] == r[3] == r[4] == 0.025
    assert r[5] == pytest.approx(0.0, abs=1e-12)
    assert isinstance(myring_radius(0.1, **p), float)
    # nose: elliptical for n = 2
    x = 0.02
    expected = 0.025 * math.sqrt(1.0 - ((x - 0.05875) / 0.05875) ** 2)
    assert myring_radius(x, **p) == pytest.approx(expected, rel=1e-12)
    # tail: cubic with slope -tan(theta) at the end
    h = 1e-7
    slope = (myring_radius(0.353 - h, **p) - myring_radius(0.353 - 2 * h, **p)) / h
    assert slope == pytest.approx(-math.tan(math.radians(25.0)), rel=1e-4)


def test_offsets_convention():
    p = REMUS
    l_f = p["a"] - p["a_offset"] + p["b"]
    assert l_f == pytest.approx(0.828, abs=1e-3)
    half = p["d"] / 2.0
    nose_face = half * (1.0 - ((p["a_offset"] - p["a"]) / p["a"]) ** 2) ** 0.5
    assert myring_radius(0.0, **p) == pytest.approx(nose_face, rel=1e-12)
    assert myring_radius(l_f, **p) == half
    assert myring_radius(l_f + 1e-9, **p) == pytest.approx(half)


@pytest.mark.parametrize("n", [0.7, 1.0, 2.0, 3.0, 5.0])
@pytest.mark.parametrize("a_offset", [0.0, 0.02])
def test_integrals_agree_with_dense_polyline(n, a_offset):
    p = dict(a=0.2, b=0.5, c=0.3, n=n, theta_deg=20.0, d=0.1, a_offset=a_offset, c_offset=0.03)
    geo = myring_geometry(**p)
    # cluster points near the nose tip, where the slope may be infinite
    nose_end = p["a"] - a_offset
    s = np.linspace(0.0, 1.0, 40001)
    x = np.concatenate([nose_end * s**4, np.linspace(nose_end, geo.length, 40001)[1:]])
    r = myring_radius(x, **p)
    volume = integrate.trapezoid(math.pi * r**2, x)
    frustum = math.pi * (r[1:] + r[:-1]) * np.hypot(np.diff(x), np.diff(r))
    assert geo.volume == pytest.approx(volume, rel=1e-5)
    assert geo.wetted_area == pytest.approx(frustum.sum(), rel=1e-5)
    assert geo.lateral_area == pytest.approx(integrate.trapezoid(2.0 * r, x), rel=1e-5)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        (dict(d=0.0), "diameter"),
        (dict(n=0.0), "exponent"),
        (dict(b=-0.1), "length b"),
        (dict(a_offset=0.1), "a_offset"),
        (dict(c_offset=0.2), "c_offset"),
        (dict(theta_deg=40.0), "bulge"),
    ],
)
def test_invalid_parameters_raise(kwargs, match):
    with pytest.raises(ValueError, match=match):
        myring_geometry(**(SUT2_MODEL | kwargs))
