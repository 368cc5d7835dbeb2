"""Hull families (#21 item 4): Gertler's Series 58 and the design tool's Table 6 turning.

Sources: Gertler (1950), DTMB Report 789, and Landweber & Gertler (1950), DTMB Report 719 (the
sixth-degree polynomial and its six conditions); the AUV concept-design tool [D] (docs/method.md
references), whose Table 6 prints each hull family's length and diameter at 150 kg.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from scipy.integrate import quad

from towtank.vehicle.hull import (
    SERIES58_PARENT,
    series58_coefficients,
    series58_profile,
    series58_radius,
)

RHO_SEA = 1025.85  # ITTC sea water at 15 degC, 35 g/kg (the Table 6 protocol's water)


def _series58_integrals(length, diameter, m, r0, r1, cp):
    """Volume, wetted area and centre of buoyancy by adaptive quadrature of the polynomial.

    Independent of the profile's grid: S = integral of 2 pi sqrt(r^2 + (r r')^2) dx, where
    r r' = D^2/(2L) dP/dxi is finite at the ends although r' is not.
    """
    a = series58_coefficients(m, r0, r1, cp)
    p = np.polynomial.Polynomial(np.r_[0.0, a])
    dp = p.deriv()

    def r2(x):
        return max(p(x / length), 0.0) * diameter**2

    def rrp(x):
        return diameter**2 / (2 * length) * dp(x / length)

    vol = quad(lambda x: math.pi * r2(x), 0, length, limit=200)[0]
    mom = quad(lambda x: math.pi * r2(x) * x, 0, length, limit=200)[0]
    area = quad(lambda x: 2 * math.pi * math.sqrt(r2(x) + rrp(x) ** 2), 0, length,
                limit=200)[0]
    return vol, area, mom / vol


def test_series58_polynomial_meets_gertlers_six_conditions():
    m, r0, r1, cp = 0.4, 0.5, 0.1, 0.65
    a = series58_coefficients(m, r0, r1, cp)
    i = np.arange(1, 7)
    assert a[0] == pytest.approx(2 * r0)                    # nose radius R0 = r0 D^2/L
    assert a.sum() == pytest.approx(0.0, abs=1e-12)          # closed tail
    assert (i * a).sum() == pytest.approx(-2 * r1)           # tail radius R1 = r1 D^2/L
    assert (a * m**i).sum() == pytest.approx(0.25)           # (r/D)^2 = 1/4 at x = m L
    assert (i * a * m ** (i - 1)).sum() == pytest.approx(0.0, abs=1e-12)  # largest there
    assert (a / (i + 1)).sum() == pytest.approx(cp / 4)      # prismatic coefficient
    # the radius of curvature at the nose tip of a body L = 2.41 m, D = 0.344 m:
    # r^2 -> 2 R0 x, R0 = r0 D^2 / L
    length, diameter = 2.41, 0.344
    x = 1e-7 * length
    r = diameter * series58_radius(np.array([x / length]), a)[0]
    assert r**2 / (2 * x) == pytest.approx(r0 * diameter**2 / length, rel=1e-5)


def test_series58_table6_hull_against_the_printed_values():
    """[D] Table 6 prints the Series 58 of 150 kg as L = 2.41 m, D = 0.344 m (L/D = 7.0).

    At Gertler's Cp = 0.65 the hull displaces Cp (pi/4) D^2 L = 0.14559 m^3, 149.4 kg of sea
    water at 1025.85 kg/m^3: the printed 150 kg within 1 %. No wetted area is printed for
    it; the profile's is checked against an adaptive quadrature of the polynomial.
    """
    length, diameter = 2.41, 0.344
    hull = series58_profile(length, diameter, **SERIES58_PARENT)
    v_cp = SERIES58_PARENT["cp"] * math.pi / 4 * diameter**2 * length
    assert v_cp == pytest.approx(0.14559, rel=1e-4)
    assert hull.volume == pytest.approx(v_cp, rel=1e-4)
    assert hull.volume * RHO_SEA == pytest.approx(150.0, rel=0.01)     # Table 6: 150 kg
    assert hull.length == pytest.approx(length) and hull.max_diameter == pytest.approx(diameter)
    assert hull.x_m[np.argmax(hull.r_m)] / length == pytest.approx(0.4, abs=1e-3)  # m
    vol, area, xb = _series58_integrals(length, diameter, **SERIES58_PARENT)
    assert hull.volume == pytest.approx(vol, rel=1e-4)
    assert hull.wetted_area == pytest.approx(area, rel=1e-3)
    assert hull.wetted_area == pytest.approx(2.0156, rel=1e-3)  # S/(pi D L) = 0.774
    # centre of buoyancy: L sum(a_i/(i+2)) / sum(a_i/(i+1)) = 0.4644 L aft of the nose
    a = series58_coefficients(**SERIES58_PARENT)
    i = np.arange(1, 7)
    assert (a / (i + 2)).sum() / (a / (i + 1)).sum() == pytest.approx(0.46443, abs=1e-5)
    assert hull.x_buoyancy == pytest.approx(xb, rel=1e-4)
    assert hull.x_buoyancy / length == pytest.approx(0.46443, abs=1e-4)


def test_series58_profiles_are_bodies_and_scale():
    from hypothesis import given, settings
    from hypothesis import strategies as st

    @settings(max_examples=60, deadline=None)
    @given(m=st.floats(0.3, 0.6), r0=st.floats(0.0, 0.8), r1=st.floats(0.0, 0.25),
           cp=st.floats(0.5, 0.75), length=st.floats(0.1, 200.0), ratio=st.floats(3.0, 15.0),
           k=st.floats(0.1, 10.0))
    def check(m, r0, r1, cp, length, ratio, k):
        diameter = length / ratio
        try:
            hull = series58_profile(length, diameter, m, r0, r1, cp)
        except ValueError as exc:  # parameters whose polynomial is no body: one sentence
            text = str(exc)
            assert "no body of revolution" in text and text.count(". ") == 0
            return
        assert np.all(hull.r_m >= 0)
        assert hull.r_m[0] == 0 and hull.r_m[-1] == pytest.approx(0, abs=1e-6 * diameter)
        assert hull.max_diameter == pytest.approx(diameter, rel=1e-6)
        assert hull.volume == pytest.approx(cp * math.pi / 4 * diameter**2 * length, rel=1e-4)
        big = series58_profile(k * length, k * diameter, m, r0, r1, cp)
        assert big.volume == pytest.approx(k**3 * hull.volume, rel=1e-9)
        assert big.wetted_area == pytest.approx(k**2 * hull.wetted_area, rel=1e-9)
        assert big.x_buoyancy == pytest.approx(k * hull.x_buoyancy, rel=1e-9)

    check()


@pytest.mark.parametrize("params,word", [
    ({"m": 1.2}, "m must be"), ({"cp": 0.0}, "cp must be"), ({"r0": -0.1}, "r0 must be"),
    ({"r1": float("nan")}, "r1 must be"), ({"m": 0.2, "cp": 0.75}, "no body of revolution"),
])
def test_series58_impossible_parameters_are_one_sentence(params, word):
    with pytest.raises(ValueError, match=word) as info:
        series58_profile(2.41, 0.344, **{**SERIES58_PARENT, **params})
    assert str(info.value).count(". ") == 0


PROTOCOL = """[campaign]
name = "s58"
output_dir = "out"

[water]
type = "sea"
temperature_C = 15.0
salinity_g_kg = 35.0

[vehicle]
name = "Series 58"
hull = "series58"
mass_kg = 150.0
buoyancy_N = 1471.0
cg_m = [0.0, 0.0, 0.015]
cb_m = [0.0, 0.0, 0.0]
speed_m_s = 1.25
{extra}
[vehicle.series58]
length_m = 2.41
diameter_m = 0.344
{series58}
[[vehicle.fins]]
plane = "rudder"
x_m = -1.05
span_m = 0.14
chord_m = 0.12

[[vehicle.fins]]
plane = "sternplane"
x_m = -1.05
span_m = 0.14
chord_m = 0.12
"""


SHIPPED = Path(__file__).resolve().parents[1] / "protocols" / "series58_vehicle.toml"


def test_predict_and_turn_a_series58_vehicle(series58_turn):
    """protocols/series58_vehicle.toml: predict, then a 10 deg turn at 1.25 m/s (both run once
    for the session by conftest's ``series58_turn``)."""
    out = series58_turn.predicted
    model = json.loads((out / "model.json").read_text())
    assert "Series 58" in model["sources"]["hull"] and "Cp = 0.65" in model["sources"]["hull"]
    assert model["hull"]["name"] == "series58"
    assert model["hull"]["volume_m3"] == pytest.approx(0.14559, rel=1e-3)
    assert model["length_m"] == pytest.approx(2.41)
    sim = series58_turn.turn
    metrics = pd.read_csv(sim / "metrics.csv").set_index("metric")["value"]
    radius = metrics["steady_turn_radius_m"]
    assert 0.5 * 2.41 < radius < 20 * 2.41  # a turn, neither a spin nor a straight run
    assert metrics["tactical_diameter_m"] > 2 * radius * 0.8


@pytest.mark.parametrize("extra,series58,words", [
    ("", "cp = 1.5", ["[vehicle.series58]", "cp must be"]),
    ("", "m = 0.2\ncp = 0.75", ["[vehicle.series58]", "no body of revolution"]),
    ("", "mm = 0.4", ["unknown key 'mm'", "[vehicle.series58]"]),
    ("", "length_m = -1", ["length_m"]),
])
def test_series58_protocol_errors_exit_2(tmp_path, capsys, extra, series58, words):
    from towtank.commands.cli import main

    text = PROTOCOL.format(extra=extra, series58=series58)
    if "length_m = -1" in series58:
        text = text.replace("length_m = 2.41\n", "")
    proto = tmp_path / "s58.toml"
    proto.write_text(text, encoding="utf-8")
    assert main(["predict", str(proto), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert all(w in err for w in words), err
    assert not (tmp_path / "out").exists()


def test_series58_hull_without_its_section_exit_2(tmp_path, capsys):
    from towtank.commands.cli import main

    text = PROTOCOL.format(extra="", series58="")
    text = text.split("[vehicle.series58]")[0] + "[[vehicle.fins]]" + \
        text.split("[[vehicle.fins]]", 1)[1]
    proto = tmp_path / "s58.toml"
    proto.write_text(text, encoding="utf-8")
    assert main(["predict", str(proto), "--out", str(tmp_path / "out")]) == 2
    assert "needs a [vehicle.series58]" in capsys.readouterr().err


#: towtank's Table 6 (docs/method.md, "Hull families"): tactical diameter, advance, transfer
#: and steady radius over the length, with the module's fins and mass properties.
TOWTANK_TABLE6 = {
    "myring": (3.804, 2.873, 1.691, 1.944),
    "suboff": (3.359, 2.765, 1.501, 1.729),
    "series58": (3.226, 2.700, 1.448, 1.662),
}


@pytest.mark.heavy
def test_table6_turning_comparison():
    """The design tool's Table 6 set up with towtank (towtank.vehicle.hull_families).

    What towtank defends: each hull at the table's printed length and diameter displaces the
    printed 150 kg within 1 % (the hull libraries against the table), and its turning metrics
    are those documented in docs/method.md within 3 % (they move if the hull terms or the
    damping change, and the table there must then be redone). The table's order (SUBOFF
    56 % wider than Myring) is *not* reproduced: towtank turns all three within 18 % of each
    other and 2.7 to 4.7 times tighter (docs/method.md says why).
    """
    from towtank.vehicle.hull_families import turning_comparison

    table = turning_comparison().set_index("hull")
    for hull, row in table.iterrows():
        assert row["displaced_kg"] == pytest.approx(150.0, rel=0.01), hull
        got = (row["tactical_diameter_L"], row["advance_L"], row["transfer_L"],
               row["steady_radius_L"])
        assert got == pytest.approx(TOWTANK_TABLE6[hull], rel=0.03), hull
        assert row["tactical_diameter_L"] < row["table6_tactical_diameter_L"] / 2.5, hull


def test_series58_section_never_crashes_the_loader_or_predict(tmp_path_factory):
    """Any [vehicle.series58] either loads and predicts, or is one ProtocolError sentence."""
    from hypothesis import given, settings
    from hypothesis import strategies as st

    from towtank.errors import ProtocolError
    from towtank.ingest.protocol import load_protocol
    from towtank.vehicle.model import vehicle_profile

    values = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.floats(-1, 3),
                       st.integers(-3, 10), st.text(max_size=5), st.booleans())
    keys = st.sampled_from(["length_m", "diameter_m", "m", "r0", "r1", "cp", "l"])
    folder = tmp_path_factory.mktemp("fuzz58")

    def val(v):
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, float):
            return "nan" if v != v else ("inf" if v > 0 else "-inf") if math.isinf(v) \
                else repr(v)
        return json.dumps(v) if isinstance(v, str) else str(v)

    @settings(max_examples=80, deadline=None)
    @given(st.dictionaries(keys, values, max_size=6))
    def check(section):
        lines = ["[campaign]", 'name = "x"', "[water]", "temperature_C = 15.0", "[vehicle]",
                 'hull = "series58"', "[vehicle.series58]"]
        lines += [f"{k} = {val(v)}" for k, v in section.items()]
        path = folder / "p.toml"
        path.write_text("\n".join(lines) + "\n", encoding="utf-8")
        try:
            protocol = load_protocol(path, check_paths=False, require_runs=False)
        except ProtocolError as exc:
            assert str(exc).count("\n") == 0
            return
        try:
            hull = vehicle_profile(protocol.vehicle)
        except ValueError as exc:  # a length or fineness no vehicle has (schema.check_hull)
            assert str(exc).count("\n") == 0
            return
        assert np.all(np.isfinite(hull.r_m)) and hull.volume > 0

    check()


def test_a_drdc_hull_is_refused_naming_the_hulls_towtank_has(tmp_path, capsys):
    """No DRDC hull (its equations were not available): exit 2, the hulls that exist named."""
    from towtank.commands.cli import main

    proto = tmp_path / "d.toml"
    proto.write_text('[campaign]\nname = "d"\n[water]\ntemperature_C = 15.0\n'
                     '[vehicle]\nhull = "drdc"\n', encoding="utf-8")
    assert main(["predict", str(proto), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "'drdc'" in err and "series58" in err and "table" in err
    # one sentence that says how to give the body instead: a radius table x_m, r_m
    assert "hull_table" in err and "x_m, r_m" in err
    assert err.strip().count("\n") == 0 and err.strip().endswith(".")
