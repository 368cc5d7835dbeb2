"""Plausibility checks: a lab's slips (grams, mV, a dead channel, a reversed sign, a wake on
the balance after the stop) caught with one sentence naming the likely cause."""

from __future__ import annotations

import gzip
import io
import math

import numpy as np
import pandas as pd
import pytest
from conftest import process, write_hull_protocol

import towtank
import towtank.testing.synthetic as syn
from towtank.analysis import fins
from towtank.analysis.plausibility import fin_plausibility_warnings, plausibility_warnings
from towtank.errors import RunError
from towtank.reduce.run import check_drag_direction
from towtank.reference import sandia
from towtank.reference.geometry import displaced_volume

RHO = 998.6
VOLUME = displaced_volume(0.353, 0.05, None)  # ~5.2e-4 m³: ~0.52 kg of water
FRONTAL = math.pi * 0.05**2 / 4
LATERAL = 0.0152
TRUTH = {"X_udot": -0.0171, "Y_vdot": -0.681, "X_u|u|": -0.2053, "X_uv": -0.0087,
         "X_v|v|": 0.0641, "Y_uv": -0.2053, "Y_v|v|": -5.97}


def _warn(**values: float) -> list[str]:
    table = pd.DataFrame({"symbol": list({**TRUTH, **values}),
                          "value": list({**TRUTH, **values}.values())})
    return plausibility_warnings(table, rho=RHO, volume_m3=VOLUME, frontal_area_m2=FRONTAL,
                                 lateral_area_m2=LATERAL)


def test_the_truth_is_plausible():
    assert _warn() == []


def test_added_mass_of_a_mass_in_grams_is_named():
    """X_udot = +551 kg (mass_kg = 552 typed in grams) for a 0.55 kg-class body."""
    text = " ".join(_warn(X_udot=551.0))
    assert "X_udot = +551 is positive" in text and "mass_kg" in text


def test_added_mass_of_forces_in_mv_is_named():
    """X_udot = −28 kg (drag in mV) is ~50 times the displaced mass: other units."""
    text = " ".join(_warn(X_udot=-27.9))
    assert "times the displaced mass" in text and "mV" in text


def test_cd_of_forces_in_mv_is_named():
    """C_D = 10.5 at α = 0 (drag left in mV): outside 0.05–1.5, with the units hint."""
    text = " ".join(_warn(**{"X_u|u|": -0.2053 * 50}))
    assert "C_D at α = 0 = 10.5" in text and "mV" in text


def test_a_drag_gain_left_out_is_named_as_a_possible_cause():
    """The sample hull with its drag in V (gain 20 N/V left at 1): C_D at α = 0 is 0.0105,
    4.8 times below the range (not the 5 times of the units hint), and X_udot comes out
    +0.52 kg (the small forces beside the weighed mass's inertia). Both sentences name the
    gain, where they named only the reference area, a reversed sign or the mass."""
    text = " ".join(_warn(**{"X_u|u|": -0.2053 * 0.0105 / 0.2094, "X_udot": 0.52}))
    assert "C_D at α = 0 = 0.0105" in text and "drag channel's gain (left out" in text
    assert "X_udot = +0.52 is positive" in text and "its gain left out" in text


@pytest.mark.parametrize("symbol", ["X_udot", "Y_vdot", "X_u|u|", "Y_uv", "Y_v|v|"])
def test_sign_flip_is_named(symbol):
    text = " ".join(_warn(**{symbol: -TRUTH[symbol]}))
    assert f"{symbol} = +" in text and "sign" in text


# ------------------------------------------------------------------------ fin lift slope
FIN_AR = 1.25  # the synthetic fin: span 0.15 m / chord 0.12 m, free tips
FIN_GROUPS = ((1.0, 1.14e5), (2.0, 2.28e5))  # speed [m/s], Re on the chord


def _fin_warn(lift=lambda cl, cd: cl, drag=lambda cl, cd: cd, *, finite_span=False):
    """The fin check on two speed groups at 0-20° whose measured C_L, C_D are ``lift`` and
    ``drag`` of the truth: the Sandia NACA 0015 section at each Re (a fin that behaves as a
    section), or its lifting-line finite span (``finite_span``)."""
    alpha = np.array([0.0, 2.5, 5.0, 7.5, 10.0, 15.0, 20.0])
    runs = []
    for k, (speed, re) in enumerate(FIN_GROUPS):
        if finite_span:
            cl, cd = fins.finite_span_coefficients(alpha, re, FIN_AR)
        else:
            cl, cd = sandia.section_coefficients(alpha, np.full(alpha.shape, re))
        runs.append(pd.DataFrame({
            "run": np.arange(alpha.size) + 1 + 10 * k, "angle_deg": alpha, "speed_mean": speed,
            "re": re, "cl": lift(cl, cd), "cd": drag(cl, cd), "drag_mean": 1.0,
            "lift_mean": 1.0}))
    table = fins.fin_table(pd.concat(runs, ignore_index=True), FIN_AR)
    curves = fins.fin_curves(table, 10.0, aspect_ratio=FIN_AR)
    return fin_plausibility_warnings(curves, table, FIN_AR)


@pytest.mark.parametrize("finite_span", [False, True])
def test_a_fin_as_its_section_or_as_a_finite_span_is_plausible(finite_span):
    """The band holds both ends of what a fin can have: 5.9-6.3 /rad as a section (the
    synthetic days), 2.4 /rad by lifting-line theory with free tips."""
    assert _fin_warn(finite_span=finite_span) == []


@pytest.mark.parametrize("finite_span", [False, True])
def test_swapped_fin_channels_are_named(finite_span):
    """Lift and drag swapped: C_L is the drag (slope ~0.1 /rad), and C_D rises with α as a lift
    does: one sentence for both groups, saying "swapped?"."""
    (text,) = _fin_warn(lambda cl, cd: cd, lambda cl, cd: cl, finite_span=finite_span)
    assert text.startswith("fin lift slope = ") and "at U ≈ 1.00 and 2.00 m/s" in text
    assert "lift and drag channels swapped?" in text
    assert "expected of this fin" in text and "a fin can have" in text


@pytest.mark.parametrize("finite_span", [False, True])
def test_fin_lift_gain_left_out_is_named(finite_span):
    """The lift in V, its 25 N/V left out: 1/25 of the slope, C_D flat: not called a swap."""
    (text,) = _fin_warn(lambda cl, cd: cl / 25.0, finite_span=finite_span)
    assert "a lift gain left out" in text and "another unit" in text
    assert "C_D rises" not in text  # a swap stays among the slips, not said as the one


def test_fin_lift_in_mv_is_named():
    (text,) = _fin_warn(lambda cl, cd: cl * 1000.0)
    assert "smaller unit than N" in text and "mV" in text


def test_fin_lift_of_reversed_sign_is_named():
    """A reversed lift falls from 0° on: no stall there, a negative slope, its sign named."""
    (text,) = _fin_warn(lambda cl, cd: -cl)
    assert "fin lift slope = -" in text and "sign reversed" in text
    assert "gain left out" not in text


# ------------------------------------------------------------------------ on a whole day
PLAN = [
    syn.RunSpec("sting", 0.0, 0.8, 0.5),
    syn.RunSpec("sting", 0.0, 1.6, 0.5),
    syn.RunSpec("sting", 0.0, 1.2, 1.0, test="accel"),
    syn.RunSpec("hull", 0.0, 0.8, 0.5),
    syn.RunSpec("hull", 0.0, 1.2, 0.5),
    syn.RunSpec("hull", 0.0, 1.6, 0.5),
    syn.RunSpec("hull", 0.0, 1.2, 1.0, test="accel"),
    syn.RunSpec("hull", 0.0, 1.2, 0.25, test="accel"),
    syn.RunSpec("hull", 5.0, 1.2, 0.5),
    syn.RunSpec("hull", 10.0, 1.2, 0.5),
    syn.RunSpec("hull", 15.0, 1.2, 0.5),
]


@pytest.fixture(scope="session")
def small_day(tmp_path_factory):
    d = tmp_path_factory.mktemp("plausible")
    syn.make_hull_day(d, seed=5, fs=100.0, runs=PLAN, file_format="csv.gz")
    return d


def _process_with(day_dir, edit=None):
    protocol = write_hull_protocol(day_dir)
    if edit is not None:
        protocol.write_text(edit(protocol.read_text(encoding="utf-8")), encoding="utf-8")
    return process(protocol, jobs=1)


def test_small_day_is_plausible(small_day):
    day = _process_with(small_day)
    assert day.rejected == {}
    assert not any("positive" in w or "displaced mass" in w or "outside the" in w
                   for w in map(str, day.warnings)), day.warnings


def test_drag_in_mv_is_named(small_day):
    """The drag's gain 20 N/V read as N/mV (1000): C_D ≈ 10, a warning naming the units."""
    day = _process_with(small_day, lambda s: s.replace("gain = 20.0", "gain = 1000.0", 1))
    text = " ".join(map(str, day.warnings))
    assert "C_D at α = 0 =" in text and "mV" in text, day.warnings


def test_drag_sign_flip_is_named(small_day):
    """The drag's gain typed −20 N/V: every run's steady drag points along the tow, so every
    run is rejected naming the reversed sign (it gave positive X_u|u| and X_udot, named only
    by the plausibility checks of the coefficients)."""
    day = _process_with(small_day, lambda s: s.replace("gain = 20.0", "gain = -20.0", 1))
    assert set(day.rejected) == set(day.runs["run"][day.runs["status"] != "void"])
    assert all("drag channel's sign reversed" in r.reason for r in day.rejected.values())


def test_dead_drag_channel_rejects_its_run(tmp_path):
    """One run's drag and lift columns all 0.0: that run is rejected ("drag channel shows no
    signal"), the rest of the day is processed."""
    syn.make_hull_day(tmp_path, seed=5, fs=100.0, runs=PLAN, file_format="csv.gz")
    path = tmp_path / "data" / "run_005.csv.gz"
    frame = pd.read_csv(io.BytesIO(gzip.decompress(path.read_bytes())))
    force_cols = [c for c in frame.columns if "load cell" in c]
    assert len(force_cols) == 2
    frame[force_cols] = 0.0
    path.write_bytes(gzip.compress(frame.to_csv(index=False).encode()))
    day = _process_with(tmp_path)
    assert list(day.rejected) == [5]
    assert "drag channel shows no signal" in str(day.rejected[5])
    assert "run_005" in str(day.rejected[5])
    assert np.isfinite(day.coefficients.set_index("symbol").loc["X_u|u|", "value"])


# ------------------------------------------------------- a drag that points along the tow
@pytest.mark.parametrize("edit", ["drag sign reversed", "drag and lift swapped"])
def test_a_drag_along_the_tow_rejects_the_run(trust_day, tmp_path, edit):
    """Run 15 of the trust day (hull, α = 0, 1.6 m/s) with its drag cable's sign reversed,
    or its drag and lift cables swapped: its steady drag points along the tow (−0.75 N; or
    the −0.008 N of lift at α = 0), which no towed body has. Accepted, such a run gave a
    negative C_D and X_udot 7 times off with nothing that named it; now it is rejected in one
    sentence that names the likely slips, while the untouched file reduces (+0.75 N)."""
    src = trust_day.dir / "data" / "run_015.csv"
    frame = pd.read_csv(src)
    drag, lift = "Fx load cell (V)", "Fy load cell (V)"
    if edit == "drag sign reversed":
        frame[drag] = -frame[drag]
    else:
        frame[[drag, lift]] = frame[[lift, drag]].to_numpy()
    path = tmp_path / "run_015.csv"
    frame.to_csv(path, index=False)
    red = towtank.reduce_run(towtank.read_run(src, trust_day.protocol), trust_day.protocol,
                             run=15)
    assert red.drag_mean_raw > 0.5
    with pytest.raises(RunError) as caught:
        towtank.reduce_run(towtank.read_run(path, trust_day.protocol), trust_day.protocol)
    reason = caught.value.reason
    assert reason.startswith("the steady drag is −") or reason.startswith("the steady drag is -")
    assert "on the side of the motion" in reason and "swapped" in reason, reason


def test_drag_direction_by_its_standard_error():
    """A drag opposing the tow passes, forward or backward; one 5 standard errors of its
    block means along the tow is rejected; one within noise of 0 passes."""
    rng = np.random.default_rng(1)
    noise = rng.normal(0.0, 0.1, 4000)
    check_drag_direction(0.5 + noise, 1.0)
    check_drag_direction(-0.5 + noise, -1.0)  # towed backwards: its drag is negative
    check_drag_direction(-0.002 + noise, 1.0)  # 1.3 standard errors: noise
    with pytest.raises(RunError, match="on the side of the motion"):
        check_drag_direction(-0.5 + noise, 1.0)
    with pytest.raises(RunError, match="on the side of the motion"):
        check_drag_direction(0.5 + noise, -1.0)


@pytest.mark.parametrize(("edit", "said"), [
    ("time in minutes", "the file lasts only 0.344 s while the carriage's speed changes at up"),
    ("rows reversed", "run_015.csv: the time runs backwards (it goes back at 4130 of its 4130 "
                      "steps, from t = 20.6500 s to 0.0000 s)"),
])
def test_a_time_on_the_wrong_scale_or_reversed_is_named(trust_day, tmp_path, edit, said):
    """Run 15's file with its time in minutes under "Time (s)", or its rows in reverse order:
    rejected as "no still window before the carriage moves", or as a file of "4131
    segments"; the sentence now names the likely slip."""
    frame = pd.read_csv(trust_day.dir / "data" / "run_015.csv")
    if edit == "time in minutes":
        frame["Time (s)"] = frame["Time (s)"] / 60.0
    else:
        frame["Time (s)"] = frame["Time (s)"].to_numpy()[::-1]
    path = tmp_path / "run_015.csv"
    frame.to_csv(path, index=False)
    with pytest.raises(RunError) as caught:
        towtank.reduce_run(towtank.read_run(path, trust_day.protocol), trust_day.protocol)
    assert said in caught.value.reason, caught.value.reason
