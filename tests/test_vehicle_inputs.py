"""Issue 20, items 7 and 10: the vehicle stage checks its inputs.

``towtank simulate`` is given inputs that could hang it (NaN or inf in model.json, --duration-s
1e6, NaN covariance), crash it (coefficients as a list, a speed as text, deep nesting, --samples
1e9) or pass for a vehicle when no vehicle is so (mass 0, negative density, zero inertia, a
covariance that is not one); ``towtank predict`` a hull table of 1e300 or 1e-300. Every case here
must end with exit 2 and one sentence per problem, within a hang bound (an alarm turns a hang into a
failure; the bounds say nothing about speed).
"""

from __future__ import annotations

import errno
import json
import math
import os
import time
from pathlib import Path

import numpy as np
import pytest

from towtank.commands.cli import main
from towtank.testing.hang import hang_bound as bound
from towtank.vehicle import schema
from towtank.vehicle.model import G, read_model

#: Longest any one command or example may take before it counts as a hang [s]. Not a speed
#: requirement: the commands below answer in a second or two.
HANG_S = 90.0

ROOT = Path(__file__).resolve().parents[1]
MASS = 30.48
COEFFICIENTS = {
    "X_udot": -0.93, "Y_vdot": -35.5, "Z_wdot": -35.5, "Y_rdot": 1.93, "N_vdot": 1.93,
    "Z_qdot": -1.93, "M_wdot": -1.93, "N_rdot": -4.88, "M_qdot": -4.88, "K_pdot": -0.0141,
    "X_u|u|": -1.62, "Y_uv": -28.6, "Y_ur": 5.22, "N_uv": 4.0, "N_ur": -2.0, "Y_v|v|": -131.0,
    "N_r|r|": -9.4, "Z_uw": -28.6, "Z_uq": -5.22, "M_uw": -4.0, "M_uq": -2.0, "Z_w|w|": -131.0,
    "M_q|q|": -9.4, "K_p|p|": -0.013, "Y_uudr": 9.64, "N_uudr": -6.15, "Z_uuds": -9.64,
    "M_uuds": -6.15,
}


def good_model(**changes):
    """A REMUS-like model.json that passes every check (with a measured covariance)."""
    model = {
        "name": "test vehicle", "rho_kg_m3": 1030.0, "mass_kg": MASS, "weight_N": MASS * G,
        "buoyancy_N": MASS * G * 1.01, "cg_m": [0.0, 0.0, 0.0196], "cb_m": [0.0, 0.0, 0.0],
        "inertia_kg_m2": [0.177, 3.45, 3.45], "coefficients": dict(COEFFICIENTS),
        "sources": {s: "predicted" for s in COEFFICIENTS},
        "covariance": {"symbols": ["Y_uv", "N_uv"], "matrix": [[4.0, 0.5], [0.5, 1.0]]},
        "design_speed_m_s": 1.5, "length_m": 1.33, "notes": {"missing": "zero"},
    }
    model.update(changes)
    return model


def hang_bound(seconds: float = HANG_S):
    """:func:`towtank.testing.hang.hang_bound` with this file's bound."""
    return bound(seconds)


def write_json(path: Path, model) -> Path:
    path.write_text(json.dumps(model), encoding="utf-8")  # NaN and Infinity as JSON5 writes
    return path


@pytest.fixture
def run(capsys):
    """``run(args)``: main(args) in-process within the hang bound; (exit code, stderr)."""

    def call(args):
        capsys.readouterr()
        with hang_bound():
            code = main([str(a) for a in args])
        return code, capsys.readouterr().err

    return call


def simulate_args(path, out, *extra, manoeuvre="turning"):
    return ["simulate", path, "--manoeuvre", manoeuvre, "--duration-s", "2", "--out", out,
            *extra]


def refused(code, err, out, *words, lines=1):
    """Exit 2, ``lines`` sentences naming ``words``, nothing written."""
    assert code == 2, err
    assert err.count("\n") == lines, err
    for word in words:
        assert word in err, (word, err)
    assert "internal error" not in err
    assert not Path(out).exists()


@pytest.mark.usefixtures("no_command_figures")  # asserts on metrics.csv; the figure is drawn
def test_the_good_model_simulates(tmp_path, run):  # by the storage-error test below
    path = write_json(tmp_path / "model.json", good_model())
    assert read_model(path)["name"] == "test vehicle"
    code, err = run(simulate_args(path, tmp_path / "out"))
    assert code == 0, err
    assert (tmp_path / "out" / "metrics.csv").is_file()


@pytest.mark.usefixtures("no_command_figures")
@pytest.mark.parametrize("speed", ["1e-300", "1e-200"])
def test_a_speed_whose_square_underflows_simulates_from_that_speed(tmp_path, run, speed):
    """A neutrally buoyant turn at a speed whose square is below the smallest float (the
    property test below found it in CI, a model whose design speed was 1.5e-300 m/s): the
    speed at the start is the speed given, not 0, and the speed loss is a number. Before,
    |nu| = sqrt(u^2 + v^2 + w^2) gave 0 and the speed loss divided by it: exit 3."""
    import pandas as pd

    path = write_json(tmp_path / "model.json", good_model())
    out = tmp_path / "out"
    code, err = run(simulate_args(path, out, f"--speed={speed}", "--net-buoyancy-N=0",
                                  "--rudder-deg=10"))
    assert code == 0, err
    metrics = pd.read_csv(out / "metrics.csv").set_index("metric")
    assert f"of the {float(speed):.3g} m/s at the start" in metrics.loc["speed_loss_percent",
                                                                           "note"]
    assert abs(metrics.loc["speed_loss_percent", "value"]) < 1e-6


def test_the_speed_is_the_norm_of_the_velocities_at_every_magnitude():
    """speed_magnitude is sqrt(u^2 + v^2 + w^2) to 2 ulp wherever the squares are normal
    floats, and where they are not (below 1e-154 or above 1e154 m/s) it is still the norm:
    the largest component's magnitude at most, sqrt(3) times it at most; exactly |x| with
    the other two 0."""
    from hypothesis import given
    from hypothesis import strategies as st

    from towtank.vehicle.steady import speed_magnitude

    speeds = st.floats(-1e300, 1e300, allow_nan=False, allow_subnormal=True)

    @given(speeds, speeds, speeds)
    def check(u, v, w):
        got = float(speed_magnitude(np.array([u]), np.array([v]), np.array([w]))[0])
        top = max(abs(u), abs(v), abs(w))
        assert top <= got <= math.sqrt(3.0) * top * (1 + 1e-15)
        if all(x == 0.0 or 1e-150 < abs(x) < 1e150 for x in (u, v, w)):  # normal squares
            assert got == pytest.approx(math.sqrt(u * u + v * v + w * w), rel=4.5e-16, abs=0.0)
        for x in (u, v, w):
            assert float(speed_magnitude(np.array([x]), np.zeros(1), np.zeros(1))[0]) == abs(x)

    check()


def test_a_start_at_rest_has_no_speed_loss_and_says_why():
    from towtank.vehicle.simulate import _speed_loss

    metric, value, unit, note = _speed_loss(("steady_speed_m_s", 1.2, "m/s", ""), 0.0)
    assert (metric, unit) == ("speed_loss_percent", "%") and math.isnan(value)
    assert note == "no speed at the start (0 m/s) to lose speed from"
    # a turn that is not steady keeps its own note
    assert _speed_loss(("steady_speed_m_s", math.nan, "m/s", "not steady"), 0.0)[3] == \
        "not steady"


# ---------------------------------------------------------------------------------------------
# simulate: inputs that could make the integration run for ever


@pytest.mark.parametrize("key,value", [
    ("mass_kg", math.nan), ("mass_kg", math.inf), ("weight_N", math.nan),
    ("weight_N", -math.inf), ("cg_m", [math.inf, 0.0, 0.0]), ("cg_m", [0.0, math.nan, 0.0]),
])
def test_non_finite_mass_properties_stop_at_once(tmp_path, run, key, value):
    path = write_json(tmp_path / "model.json", good_model(**{key: value}))
    code, err = run(simulate_args(path, tmp_path / "out"))
    refused(code, err, tmp_path / "out", f"'{key}'", "model.json")


@pytest.mark.parametrize("duration", ["nan", "inf", "1e6", "-5", "0"])
def test_duration_must_be_finite_positive_and_bounded(tmp_path, run, duration):
    path = write_json(tmp_path / "model.json", good_model())
    out = tmp_path / "out"
    code, err = run(["simulate", path, "--manoeuvre", "zigzag", "--duration-s", duration,
                     "--out", out])
    refused(code, err, out, "--duration-s", "3600 s")


def test_a_default_duration_beyond_the_bound_is_refused(tmp_path, run):
    # a 1000 m vehicle at 1 cm/s: 120 lengths take 1.2e7 s
    path = write_json(tmp_path / "model.json", good_model(length_m=1000.0, cg_m=[0, 0, 0.02]))
    out = tmp_path / "out"
    code, err = run(["simulate", path, "--manoeuvre", "turning", "--speed", "0.01",
                     "--out", out])
    refused(code, err, out, "default simulated time", "3600 s", "--duration-s")


@pytest.mark.parametrize("net", ["nan", "1e30", "-1e30", "inf"])
def test_net_buoyancy_must_be_finite_and_plausible(tmp_path, run, net):
    path = write_json(tmp_path / "model.json", good_model())
    out = tmp_path / "out"
    code, err = run(simulate_args(path, out, f"--net-buoyancy-N={net}", manoeuvre="glide"))
    refused(code, err, out, "--net-buoyancy-N")
    if net != "nan" and net != "inf":
        assert "weight_N" in err


def test_net_buoyancy_that_leaves_no_weight_is_refused(tmp_path, run):
    heavy = good_model(buoyancy_N=MASS * G * 0.9)  # buoyancy 269 N
    path = write_json(tmp_path / "model.json", heavy)
    out = tmp_path / "out"
    code, err = run(simulate_args(path, out, "--net-buoyancy-N", "280", manoeuvre="glide"))
    refused(code, err, out, "--net-buoyancy-N 280", "no weight")


def test_a_nan_covariance_is_refused(tmp_path, run):
    cov = {"symbols": ["Y_uv", "N_uv"], "matrix": [[math.nan, 0.0], [0.0, 1.0]]}
    path = write_json(tmp_path / "model.json", good_model(covariance=cov))
    out = tmp_path / "out"
    code, err = run(simulate_args(path, out, "--samples", "3"))
    refused(code, err, out, "'covariance'", "finite", "NaN")


def test_a_stiff_model_is_stopped_by_the_step_budget():
    """A roll damping 1e8 times REMUS's against a roll inertia of 0.18 kg m^2: explicit
    integration creeps; the budget stops it with one sentence instead of running for ever."""
    from towtank.vehicle.simulate import simulate

    model = good_model()
    model["coefficients"]["K_p|p|"] = -1e6
    start = time.monotonic()
    with hang_bound(), pytest.raises(ValueError, match="integration steps"):
        simulate(model, "turning", 1.5, rudder_deg=15.0, duration_s=100.0, max_steps=3000)
    assert time.monotonic() - start < HANG_S


def test_the_step_budget_bounds_a_zigzag_over_all_its_legs():
    from towtank.vehicle.simulate import simulate

    ts = simulate(good_model(), "zigzag", 1.5, rudder_deg=20.0, duration_s=60.0)
    assert (np.diff(ts["rudder_deg"]) != 0).sum() >= 1  # two legs at least
    with pytest.raises(ValueError, match="integration steps"):
        simulate(good_model(), "zigzag", 1.5, rudder_deg=20.0, duration_s=60.0,
                 max_steps=len(ts) // 2)


def test_a_nan_in_the_dynamics_stops_at_once_not_for_ever():
    """simulate() itself, without the checks of read_model: NaN forces made RK45's step NaN,
    which it retried for ever."""
    from towtank.vehicle.simulate import simulate

    model = good_model()
    model["mass_kg"] = math.nan
    with hang_bound(), pytest.raises(ValueError, match="no longer finite"):
        simulate(model, "turning", 1.5, rudder_deg=15.0, duration_s=10.0)


# ---------------------------------------------------------------------------------------------
# simulate: inputs of the wrong type or size (refused, not an internal error)


@pytest.mark.parametrize("change,words", [
    ({"coefficients": [1.0, 2.0]}, ["'coefficients'", "[1.0, 2.0]"]),
    ({"coefficients": None}, ["'coefficients'", "null"]),
    ({"design_speed_m_s": "fast"}, ["'design_speed_m_s'", '"fast"']),
    ({"mass_kg": 10**400}, ["'mass_kg'"]),
    ({"cb_m": "0, 0, 0"}, ["'cb_m'", "three numbers"]),
    ({"covariance": [1, 2]}, ["'covariance'"]),
    ({"covariance": {"symbols": ["Y_uv"], "matrix": [[1.0, 0.0]]}}, ["'matrix'", "1 x 1"]),
    ({"name": {"first": "REMUS"}}, ["'name'"]),
])
def test_wrong_types_are_exit_2_not_3(tmp_path, run, change, words):
    path = write_json(tmp_path / "model.json", good_model(**change))
    code, err = run(simulate_args(path, tmp_path / "out"))
    refused(code, err, tmp_path / "out", *words)


def test_deeply_nested_json_is_refused(tmp_path, run):
    text = json.dumps(good_model())
    path = tmp_path / "model.json"
    path.write_text(text[:-1] + ', "extra": ' + "[" * 100_000 + "]" * 100_000 + "}")
    code, err = run(simulate_args(path, tmp_path / "out"))
    refused(code, err, tmp_path / "out", f"deeper than the {schema.MAX_DEPTH} levels")
    path.write_text(text[:-1] + ', "extra": ' + "[" * 40 + "]" * 40 + "}")
    code, err = run(simulate_args(path, tmp_path / "out"))
    refused(code, err, tmp_path / "out", f"deeper than the {schema.MAX_DEPTH} levels")


@pytest.mark.parametrize("samples", ["1000000000", "-1", str(schema.MAX_SAMPLES + 1)])
def test_samples_are_bounded(tmp_path, run, samples):
    path = write_json(tmp_path / "model.json", good_model())
    code, err = run(simulate_args(path, tmp_path / "out", "--samples", samples))
    refused(code, err, tmp_path / "out", "--samples", f"0 to {schema.MAX_SAMPLES}")


def test_samples_without_a_covariance_are_refused_before_simulating(tmp_path, run,
                                                                    monkeypatch):
    import towtank.vehicle.simulate as sim

    def no_simulation(*args, **kwargs):
        raise AssertionError("simulated before refusing --samples")

    monkeypatch.setattr(sim, "simulate", no_simulation)
    path = write_json(tmp_path / "model.json",
                      good_model(covariance={"symbols": [], "matrix": []}))
    code, err = run(simulate_args(path, tmp_path / "out", "--samples", "5"))
    refused(code, err, tmp_path / "out", "no covariance of measured coefficients")


# ---------------------------------------------------------------------------------------------
# simulate: values no vehicle has


@pytest.mark.parametrize("change,words", [
    ({"mass_kg": 0}, ["'mass_kg'", "> 0"]),
    ({"rho_kg_m3": -1000.0}, ["'rho_kg_m3'", "900 to 1300"]),
    ({"rho_kg_m3": 1.2}, ["'rho_kg_m3'", "1.2"]),
    ({"inertia_kg_m2": [0.0, 0.0, 0.0]}, ["'inertia_kg_m2'", "> 0"]),
    ({"inertia_kg_m2": [0.177, -3.45, 3.45]}, ["'inertia_kg_m2'"]),
    ({"length_m": 0.0}, ["'length_m'"]),
    ({"design_speed_m_s": -1.5}, ["'design_speed_m_s'"]),
    ({"weight_N": 250.0, "buoyancy_N": 250.0}, ["'weight_N'", "mass_kg x g"]),
    ({"buoyancy_N": 10 * MASS * G}, ["'buoyancy_N'", "weight"]),
    ({"cg_m": [5.0, 0.0, 0.0]}, ["'cg_m'", "length_m"]),
    ({"cg_m": [0.0, 0.0, 19.6]}, ["'cg_m'", "length_m (1.33 m)", "[0.0, 0.0, 19.6]",
                                  "was it given in mm for m?"]),
])
def test_what_no_vehicle_is_refused(tmp_path, run, change, words):
    path = write_json(tmp_path / "model.json", good_model(**change))
    code, err = run(simulate_args(path, tmp_path / "out"))
    refused(code, err, tmp_path / "out", *words)


def test_a_covariance_that_is_not_one_draws_no_bands(tmp_path, run):
    for matrix, word in (([[1.0, 2.0], [2.0, 1.0]], "positive semi-definite"),
                         ([[1.0, 0.5], [0.0, 1.0]], "symmetric"),
                         ([[-1.0, 0.0], [0.0, 1.0]], "positive semi-definite")):
        cov = {"symbols": ["Y_uv", "N_uv"], "matrix": matrix}
        path = write_json(tmp_path / "model.json", good_model(covariance=cov))
        code, err = run(simulate_args(path, tmp_path / "out", "--samples", "3"))
        refused(code, err, tmp_path / "out", "'covariance'", word)


def test_a_covariance_psd_within_rounding_is_accepted():
    # eigenvalues 0 and 2, one of them -4e-17 after rounding
    cov = {"symbols": ["Y_uv", "N_uv"], "matrix": [[1.0, 1.0], [1.0, 1.0 - 1e-16]]}
    assert schema.check_covariance(cov) == []
    assert schema.check_covariance({"symbols": [], "matrix": []}) == []
    assert schema.check_covariance({"symbols": ["Y_uv", "Y_uv"], "matrix": [[1, 0], [0, 1]]})


def test_a_negative_mass_is_named_not_blamed_on_the_damping(tmp_path, run):
    path = write_json(tmp_path / "model.json", good_model(mass_kg=-30.48, weight_N=-298.9))
    code, err = run(simulate_args(path, tmp_path / "out"))
    refused(code, err, tmp_path / "out", "'mass_kg'", "-30.48", "'weight_N'", lines=2)
    assert "damping" not in err


def test_added_masses_of_the_wrong_sign_are_named(tmp_path, run):
    model = good_model()
    model["coefficients"]["Y_vdot"] = 100.0  # M_22 = 30.5 - 100 < 0
    path = write_json(tmp_path / "model.json", model)
    code, err = run(simulate_args(path, tmp_path / "out"))
    refused(code, err, tmp_path / "out", "mass matrix", "positive definite")


def test_every_problem_is_listed_one_sentence_each(tmp_path, run):
    model = good_model(mass_kg=math.nan, rho_kg_m3="sea", cg_m=[0, 0])
    model["coefficients"]["N_foo"] = 1.0
    model["coefficients"]["Y_uv"] = math.inf
    path = write_json(tmp_path / "model.json", model)
    out = tmp_path / "out"
    code, err = run(["simulate", path, "--manoeuvre", "turning", "--duration-s", "1e9",
                     "--samples", "-2", "--rudder-deg", "90", "--out", out])
    refused(code, err, out, "'mass_kg'", "'rho_kg_m3'", "'cg_m'", "'N_foo'", "Y_uv",
            "--duration-s", "--samples", "--rudder-deg", lines=8)
    assert all(line.endswith(".") for line in err.splitlines())


def test_only_a_regular_file_is_read(tmp_path, run):
    fifo = tmp_path / "model.json"
    os.mkfifo(fifo)  # open() of a pipe without a writer would block for ever
    code, err = run(simulate_args(fifo, tmp_path / "out"))
    refused(code, err, tmp_path / "out", "not a regular file")
    code, err = run(simulate_args(tmp_path, tmp_path / "out"))
    refused(code, err, tmp_path / "out", "not a regular file")


def test_an_oversized_model_file_is_refused(tmp_path, run):
    model = good_model(notes={"padding": "x" * (schema.MAX_MODEL_BYTES + 10)})
    path = write_json(tmp_path / "model.json", model)
    code, err = run(simulate_args(path, tmp_path / "out"))
    refused(code, err, tmp_path / "out", f"{schema.MAX_MODEL_BYTES}")


def test_too_many_coefficients_or_factors_are_refused(tmp_path, run):
    model = good_model()
    model["coefficients"] = {f"Y_{'u' * 7}": 1.0}
    path = write_json(tmp_path / "model.json", model)
    code, err = run(simulate_args(path, tmp_path / "out"))
    refused(code, err, tmp_path / "out", "more than 6 factors")
    many = {f"Y_{'uvwpqr'[i % 6]}{'uvwpqr'[i // 6 % 6]}{'uvwpqr'[i // 36 % 6]}"
            f"{'uvwpqr'[i // 216 % 6]}{'uvwpqr'[i // 1296]}": 0.0 for i in range(1500)}
    assert len(many) > schema.MAX_COEFFICIENTS
    path = write_json(tmp_path / "model.json", good_model(coefficients=many))
    code, err = run(simulate_args(path, tmp_path / "out"))
    refused(code, err, tmp_path / "out", f"more than the {schema.MAX_COEFFICIENTS}")


def test_json_depth():
    assert schema.json_depth(1.0) == 0
    assert schema.json_depth([1]) == 1
    assert schema.json_depth([]) == 1
    assert schema.json_depth({"a": [1, {"b": []}]}) == 4
    assert schema.json_depth(good_model()) == 4  # covariance, matrix, row
    deep: list = []
    for _ in range(10_000):
        deep = [deep]
    assert schema.json_depth(deep) == schema.MAX_DEPTH + 1  # counted no further


# ---------------------------------------------------------------------------------------------
# predict: absurd hull tables


PROTOCOL = """[campaign]
name = "table hull"
[water]
type = "fresh"
temperature_C = 15.0
[vehicle]
name = "table"
hull = "table"
hull_table = "hull.csv"
"""


@pytest.mark.parametrize("table,words", [
    ("0,0\n1e300,1\n2e300,0\n", ["hull.csv", "length", "1000 m"]),
    ("0,0\n1e-300,1e-300\n2e-300,0\n", ["hull.csv", "length", "0.01"]),
    ("0,0\n1,1e-300\n2,0\n", ["hull.csv", "fineness ratio"]),
    ("0,0\n1,1e300\n2,0\n", ["hull.csv", "fineness ratio"]),
    ("0,0\n1,nan\n2,0\n", ["hull.csv", "numbers"]),
    ("0,0\n1,inf\n2,0\n", ["hull.csv", "numbers"]),
    ("0,0\n1,-0.1\n2,0\n", ["hull.csv", ">= 0"]),
    ("0,0\n1,0.1\n0.5,0\n", ["hull.csv", "increase strictly"]),
])
def test_predict_refuses_an_absurd_hull_table(tmp_path, run, table, words):
    (tmp_path / "hull.csv").write_text("x_m,r_m\n" + table, encoding="utf-8")
    proto = tmp_path / "p.toml"
    proto.write_text(PROTOCOL, encoding="utf-8")
    code, err = run(["predict", proto, "--out", tmp_path / "out"])
    refused(code, err, tmp_path / "out", *words)


@pytest.mark.parametrize("scale", ["1e300", "1e-300"])
def test_predict_refuses_a_scale_no_vehicle_has(tmp_path, run, scale):
    proto = tmp_path / "p.toml"
    proto.write_text(PROTOCOL.replace('hull = "table"\nhull_table = "hull.csv"',
                                      f'hull = "suboff"\nscale = {scale}'), encoding="utf-8")
    code, err = run(["predict", proto, "--out", tmp_path / "out"])
    refused(code, err, tmp_path / "out", "[vehicle]", "length")


def test_check_hull_accepts_real_hulls():
    from towtank.vehicle.hull import myring_profile, suboff_profile

    for p in (suboff_profile(), myring_profile(0.191, 0.654, 0.541, 2.0, 25.0, 0.191),
              suboff_profile(0.5), suboff_profile(400.0)):
        assert schema.check_hull(p.x_m, p.r_m, p.name) == []


# ---------------------------------------------------------------------------------------------
# predict and simulate: a full disk, a quota, a read-only file system, a refused permission


STORAGE = [errno.ENOSPC, errno.EDQUOT, errno.EROFS, errno.EACCES]


def _fail(code):
    def writer(*args, **kwargs):
        raise OSError(code, os.strerror(code))

    return writer


@pytest.mark.parametrize("code", STORAGE)
def test_predict_on_a_storage_error_leaves_the_folder_as_it_was(tmp_path, run, monkeypatch,
                                                                code):
    import towtank.vehicle.model as vmodel

    monkeypatch.setattr(vmodel, "write_model", _fail(code))
    protocol = ROOT / "protocols" / "remus_vehicle.toml"
    fresh = tmp_path / "fresh"
    status, err = run(["predict", protocol, "--out", fresh])
    refused(status, err, fresh, "could not be written", "as it was", os.strerror(code))
    kept = tmp_path / "kept"
    kept.mkdir()
    (kept / "mine.txt").write_text("mine", encoding="utf-8")
    status, err = run(["predict", protocol, "--out", kept])
    assert status == 2 and "as it was" in err and err.count("\n") == 1
    assert sorted(p.name for p in kept.iterdir()) == ["mine.txt"]


# one errno: simulate and predict share the storage-error path, which the predict test above
# drives with each of STORAGE
@pytest.mark.heavy
@pytest.mark.parametrize("code", STORAGE[:1])
def test_simulate_on_a_storage_error_leaves_the_folder_as_it_was(tmp_path, run, monkeypatch,
                                                                 code):
    import towtank.commands.simulate as sim

    # neutrally buoyant, in trim: the 1 % buoyant model's out-of-trim warning (issue 21)
    # would be a second line beside the one sentence of the storage error
    path = write_json(tmp_path / "model.json", good_model(buoyancy_N=MASS * G))
    out = tmp_path / "sim"
    assert run(simulate_args(path, out))[0] == 0
    before = {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()}
    monkeypatch.setattr(sim, "_figure", _fail(code))  # the last file written
    status, err = run(simulate_args(path, out, "--rudder-deg", "10"))
    assert status == 2, err
    assert "could not be written" in err and "as it was" in err and err.count("\n") == 1
    assert {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()} == before
    assert sorted(p.name for p in out.iterdir()) == sorted(before)
    status, err = run(simulate_args(path, tmp_path / "fresh"))
    refused(status, err, tmp_path / "fresh", "as it was")


def test_another_os_error_is_still_a_bug(tmp_path, run, monkeypatch):
    import towtank.commands.simulate as sim

    monkeypatch.setattr(sim, "_figure", _fail(errno.EBADF))
    path = write_json(tmp_path / "model.json", good_model())
    code, err = run(simulate_args(path, tmp_path / "out"))
    assert code == 3 and "internal error" in err


# ---------------------------------------------------------------------------------------------
# property-based: whatever model.json holds, exit 0 or 2 within the hang bound


def _json_values():
    from hypothesis import strategies as st

    leaves = st.one_of(
        st.none(), st.booleans(), st.integers(-(10**30), 10**30),
        st.floats(allow_nan=True, allow_infinity=True), st.text(max_size=6),
        st.sampled_from([0, -1, 1e-300, 1e300, -1e300, 1e308, 10**400, "1.5", "NaN"]))
    return st.recursive(leaves, lambda kids: st.lists(kids, max_size=3)
                        | st.dictionaries(st.text(max_size=6), kids, max_size=3),
                        max_leaves=8)


def _models():
    """model.json contents: mostly the good model with a few changes, some of which keep it
    usable (a coefficient or a mass property scaled, a valid covariance) and some not (a key
    replaced by random JSON or removed, a coefficient NaN, huge or text...); now and then
    random JSON as the whole file."""
    from hypothesis import strategies as st

    values = _json_values()
    keys = st.sampled_from(sorted(good_model()) + ["extra"])
    symbols = st.sampled_from(sorted(COEFFICIENTS) + ["Y_foo", "N_", "X_uuuuuuuuu", ""])
    factors = st.one_of(st.floats(0.5, 2.0), st.floats(-3.0, 3.0),
                        st.sampled_from([0.0, -1.0, 1e-300, 1e300, 1e6, 1e-6]))
    numbers = st.one_of(st.floats(-1e3, 1e3), st.floats(allow_nan=True, allow_infinity=True))
    changes = st.sampled_from(["key", "delete", "coefficient", "number", "number", "scale",
                               "scale", "covariance", "covariance"])

    @st.composite
    def changed(draw):
        model = good_model()
        coefficients = model["coefficients"] = dict(model["coefficients"])
        for _ in range(draw(st.integers(0, 3))):
            change = draw(changes)
            if change == "key":
                model[draw(keys)] = draw(values)
            elif change == "delete":
                model.pop(draw(keys), None)
            elif change == "coefficient":
                coefficients[draw(symbols)] = draw(values)
            elif change == "number":
                coefficients[draw(symbols)] = draw(numbers)
            elif change == "scale":  # a plausible number times a factor
                key = draw(st.sampled_from(["mass_kg", "weight_N", "buoyancy_N", "rho_kg_m3",
                                            "length_m", "design_speed_m_s", "coefficient"]))
                if key == "coefficient":
                    sym = draw(st.sampled_from(sorted(COEFFICIENTS)))
                    coefficients[sym] = COEFFICIENTS[sym] * draw(factors)
                elif isinstance(model.get(key), float):
                    model[key] = model[key] * draw(factors)
            else:
                n = draw(st.integers(0, 3))
                syms = draw(st.lists(symbols, min_size=n, max_size=n))
                if draw(st.booleans()):  # a valid diagonal covariance
                    diag = draw(st.lists(st.floats(0.0, 10.0), min_size=n, max_size=n))
                    matrix = [[diag[i] if i == j else 0.0 for j in range(n)] for i in range(n)]
                else:
                    matrix = draw(st.lists(st.lists(st.one_of(st.floats(-2, 2), values),
                                                    min_size=n, max_size=n),
                                           min_size=n, max_size=n))
                model["covariance"] = {"symbols": syms, "matrix": matrix}
        return model

    return st.one_of(changed(), changed(), changed(), changed(), changed(), changed(),
                     changed(), values)


def test_the_model_loader_raises_only_its_one_sentence_errors(tmp_path_factory):
    from hypothesis import HealthCheck, given, settings

    folder = tmp_path_factory.mktemp("loader")

    @settings(max_examples=120, deadline=None,
              suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
    @given(_models())
    def check(model):
        path = folder / "model.json"
        path.write_text(json.dumps(model), encoding="utf-8")
        start = time.monotonic()
        with hang_bound():
            try:
                loaded = read_model(path)
            except schema.ModelError as exc:
                assert exc.problems and all(p.count("\n") == 0 for p in exc.problems)
                assert all(p.startswith("model.json: ") for p in exc.problems)
            else:
                assert isinstance(loaded, dict) and isinstance(loaded["coefficients"], dict)
                assert all(np.isfinite(v) for v in loaded["coefficients"].values())
        assert time.monotonic() - start < HANG_S

    check()


@pytest.mark.heavy
def test_simulate_answers_0_or_2_for_any_model_file(tmp_path_factory, capsys):
    from hypothesis import HealthCheck, given, settings
    from hypothesis import strategies as st

    folder = tmp_path_factory.mktemp("simulate")
    options = st.fixed_dictionaries({}, optional={
        "--duration-s": st.sampled_from(["0.5", "1", "nan", "inf", "-1", "0", "1e6", "1e-6"]),
        "--net-buoyancy-N": st.sampled_from(["-5", "2", "nan", "1e30", "-300", "0"]),
        "--samples": st.sampled_from(["0", "2", "-1", "1000000000"]),
        "--speed": st.sampled_from(["1.5", "0.3", "nan", "1e300", "-1"]),
        "--rudder-deg": st.sampled_from(["10", "-20", "nan", "90"]),
    })
    manoeuvres = st.sampled_from(["turning", "zigzag", "dive", "spiral", "glide"])

    # 25 examples: each valid one is a whole simulation (2000 steps and a figure); the
    # model's changes are covered 120 times by the loader's property above, so these examples
    # cover what the command adds: each manoeuvre and each option with a changed model
    @settings(max_examples=25, deadline=None,
              suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
    @given(_models(), manoeuvres, options)
    def check(model, manoeuvre, opts):
        path = folder / "model.json"
        path.write_text(json.dumps(model), encoding="utf-8")
        out = folder / "out"
        opts = {"--duration-s": "1"} | opts  # a valid run stays short
        args = ["simulate", str(path), "--manoeuvre", manoeuvre, "--out", str(out)]
        args += [f"{key}={value}" for key, value in opts.items()]  # "=": -1e30 is no option
        start = time.monotonic()
        with hang_bound():
            code = main(args)
        err = capsys.readouterr().err
        assert code in (0, 2), (args, model, err)
        assert "internal error" not in err
        assert time.monotonic() - start < HANG_S

    check()
