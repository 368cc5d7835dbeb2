"""Issue 26: the glider's controls, steady glides and spirals (towtank.vehicle.spiral), wings
to 90 deg, `towtank steady` and the glide manoeuvre's roll (docs/method.md, "Steady glide and
steady spiral")."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from towtank.commands.cli import main
from towtank.commands.steady import parse_list
from towtank.errors import ProtocolError
from towtank.ingest.protocol import load_protocol
from towtank.vehicle import glider_controls as gc
from towtank.vehicle.glider import steady_glide
from towtank.vehicle.model import coriolis_added_mass, write_model
from towtank.vehicle.simulate import Dynamics, manoeuvre_metrics, simulate
from towtank.vehicle.spiral import body_rates, solve_state, steady_table
from towtank.vehicle.stage import predict_vehicle
from towtank.vehicle.steady import circle_fit
from towtank.vehicle.wings import lift_slope, wing_coefficients

REPO = Path(__file__).resolve().parents[1]
PROTOCOL = REPO / "protocols" / "glider_parametric.toml"


@pytest.fixture(scope="session")
def model():
    protocol = load_protocol(PROTOCOL, check_paths=False, require_runs=False)
    return predict_vehicle(protocol).model


def _held(model, x):
    """The model with the steady state's travel and roll-mass angle."""
    return dict(model, cg_m=gc.cg_with_controls(model, x[4], x[5]).tolist())


def test_roll_zero_is_the_existing_glide(model):
    for ballast, pitch in ((-300.0, -20.0), (-450.0, -35.0), (250.0, 15.0)):
        x, mdl, note = solve_state(model, ballast, pitch, 0.0)
        assert note == ""
        ref = steady_glide(mdl, gc.net_buoyancy(model, ballast), pitch)
        assert ref["converged"]
        assert x[0] == pytest.approx(ref["u_m_s"], rel=1e-9)
        assert x[2] == pytest.approx(ref["w_m_s"], rel=1e-7, abs=1e-12)
        assert x[1] == 0.0 and x[3] == 0.0 and x[5] == 0.0
        # the moving mass supplies the moment given as trim_moment_Nm in the reference
        mp = model["glider"]["moving_mass_kg"]
        moment = mp * gc.G * x[4] * math.cos(math.radians(pitch))
        assert moment == pytest.approx(-ref["trim_moment_Nm"], rel=1e-6)


@pytest.mark.parametrize(("ballast", "pitch", "roll"),
                         [(-300.0, -20.0, 0.0), (-300.0, -20.0, 10.0), (-450.0, -40.0, -15.0),
                          (300.0, 25.0, 12.0)])
def test_forces_and_moments_balance(model, ballast, pitch, roll):
    """Through the simulator's own right-hand side: M nu_dot at the steady state is at most
    1e-8 of the weight (moments: of the weight times the length)."""
    x, mdl, note = solve_state(model, ballast, pitch, roll)
    assert x is not None, note
    held = _held(mdl, x)
    dyn = Dynamics(held)
    state = np.zeros(12)
    state[3], state[4] = math.radians(roll), math.radians(pitch)
    state[6:9] = x[:3]
    state[9:] = body_rates(x[3], state[3], state[4])
    tau = dyn.m_total @ dyn.rhs(state, 0.0, 0.0, 0.0)[6:]
    w, length = dyn.weight_n, float(model["length_m"])
    assert np.max(np.abs(tau[:3])) < 1e-8 * w
    assert np.max(np.abs(tau[3:])) < 1e-8 * w * length
    # the Euler angles' rates: level turn at constant roll and pitch
    rates = dyn.rhs(state, 0.0, 0.0, 0.0)[3:6]
    assert abs(rates[0]) < 1e-12 and abs(rates[1]) < 1e-12


def test_wings_level_glide_angle_is_drag_over_lift(model):
    table = steady_table(model, [-200.0, -450.0], [-45.0, -30.0, -15.0, -5.0, -2.5])
    assert table["converged"].all()
    for _, row in table.iterrows():
        mdl = gc.ballast_model(model, row["ballast_cc"])
        dyn = Dynamics(mdl)
        nu = np.array([row["u_m_s"], 0.0, row["w_m_s"], 0.0, 0.0, 0.0])
        f = dyn.hydro(nu, 0.0, 0.0)
        e_v = nu[[0, 2]] / np.hypot(nu[0], nu[2])
        drag = -(f[0] * e_v[0] + f[2] * e_v[1])
        lift = -(-f[0] * e_v[1] + f[2] * e_v[0])  # perpendicular, up in the glide plane
        assert math.tan(math.radians(-row["glide_angle_deg"])) == pytest.approx(
            drag / lift, rel=1e-7)


def test_paper_000_trends(model):
    """U proportional to sqrt(net buoyancy) at fixed pitch; W/U (the glide angle) independent of
    the ballast; the flattest glide at a pitch inside the range, not at its ends."""
    pitches = [-50.0, -40.0, -30.0, -20.0, -15.0, -10.0, -7.5, -5.0, -2.5]
    table = steady_table(model, [-200.0, -300.0, -450.0], pitches)
    assert table["converged"].all()
    for p in pitches:
        rows = table[table["pitch_deg"] == p]
        v = rows["speed_m_s"].to_numpy()
        b = -rows["net_buoyancy_N"].to_numpy()
        assert v / np.sqrt(b) == pytest.approx(np.full(3, v[0] / math.sqrt(b[0])), rel=1e-6)
        gam = rows["glide_angle_deg"].to_numpy()
        assert np.ptp(gam) < 1e-6
    glide = table[table["ballast_cc"] == -300.0].set_index("pitch_deg")["glide_angle_deg"]
    flattest = float(glide.idxmax())
    assert pitches[0] < flattest < pitches[-1]


def test_paper_003_larger_roll_smaller_radius_and_period(model):
    for ballast, pitch in ((-300.0, -20.0), (300.0, 20.0)):
        table = steady_table(model, [ballast], [pitch], [5.0, 10.0, 15.0, 20.0])
        assert table["converged"].all(), table["note"].tolist()
        assert np.all(np.diff(table["turn_radius_m"]) < 0)
        assert np.all(np.diff(table["turn_period_s"]) < 0)
        assert np.all(np.diff(np.abs(table["roll_mass_angle_deg"])) > 0)
    # rolled to starboard the glider turns to starboard descending and to port climbing
    assert solve_state(model, -300.0, -20.0, 10.0)[0][3] > 0
    assert solve_state(model, 300.0, 20.0, 10.0)[0][3] < 0


@pytest.mark.heavy
def test_spiral_against_the_time_domain(model):
    """From the steady solution the simulator stays on it; from the straight glide with the
    roll mass turned it converges to it (radius, period, speed within 1 % after 3 turns)."""
    ballast, pitch, roll = -300.0, -20.0, 15.0
    x, mdl, _ = solve_state(model, ballast, pitch, roll)
    row = steady_table(model, [ballast], [pitch], [roll]).iloc[0]
    held = _held(mdl, x)
    th, ph = math.radians(pitch), math.radians(roll)
    s0 = np.zeros(12)
    s0[3], s0[4] = ph, th
    s0[6:9] = x[:3]
    s0[9:] = body_rates(x[3], ph, th)
    period = row["turn_period_s"]
    for start, turns in ((s0, 3), (np.r_[np.zeros(4), th, 0.0, x[0], 0.0, x[2], 0, 0, 0], 6)):
        ts = simulate(held, "glide", float(row["speed_m_s"]), duration_s=turns * period,
                      initial_state=start)
        ts.attrs["turning"] = True
        last = ts["t_s"].to_numpy() > (turns - 1) * period
        radius = circle_fit(ts["x_m"].to_numpy()[last], ts["y_m"].to_numpy()[last])[2]
        speed = np.sqrt(ts["u_m_s"] ** 2 + ts["v_m_s"] ** 2 + ts["w_m_s"] ** 2).iloc[-1]
        assert radius == pytest.approx(row["turn_radius_m"], rel=0.01)
        assert speed == pytest.approx(row["speed_m_s"], rel=0.01)
        metrics = manoeuvre_metrics(ts).set_index("metric")
        assert metrics.loc["turn_period_s", "value"] == pytest.approx(period, rel=0.01)
        assert metrics.loc["steady_turn_radius_m", "value"] == pytest.approx(
            row["turn_radius_m"], rel=0.01)


@pytest.fixture(scope="session")
def trimmed(model):
    """The glider at -300 cc trimmed by the moving mass at -20 deg of pitch, and the start
    state of its straight glide there."""
    x, mdl, _ = solve_state(model, -300.0, -20.0, 0.0)
    start = np.r_[np.zeros(4), math.radians(-20.0), 0.0, x[0], 0.0, x[2], 0.0, 0.0, 0.0]
    return _held(mdl, x), start


@pytest.fixture(scope="session")
def straight_glide(trimmed):
    """300 s of the trimmed glide, no roll, no rudder."""
    held, start = trimmed
    return simulate(held, "glide", 0.6, duration_s=300.0, initial_state=start)


@pytest.mark.heavy
def test_glide_with_roll_deg_spirals(trimmed, straight_glide):
    held, start = trimmed
    ts = simulate(held, "glide", 0.6, roll_deg=8.0, duration_s=2400.0, initial_state=start)
    metrics = manoeuvre_metrics(ts).set_index("metric")
    assert metrics.loc["steady_turn_radius_m", "note"] == ""
    assert 5.0 < metrics.loc["steady_turn_radius_m", "value"] < 500.0
    assert "steady_turn_radius_m" not in set(manoeuvre_metrics(straight_glide)["metric"])


def test_conversions(model):
    mdl = gc.ballast_model(model, -300.0)
    rho = model["rho_kg_m3"]
    assert gc.net_buoyancy(model, -300.0) == pytest.approx(
        model["buoyancy_N"] - model["weight_N"] - rho * gc.G * 300e-6)
    assert mdl["mass_kg"] == pytest.approx(model["mass_kg"] + rho * 300e-6)
    for pitch in (-30.0, -5.0, 12.0):
        travel = gc.travel_for_static_pitch_mm(mdl, pitch)
        assert gc.static_pitch_deg(mdl, travel) == pytest.approx(pitch, abs=1e-9)
    assert gc.static_pitch_deg(mdl, 50.0) < 0  # forward: nose down
    for roll in (3.0, -7.0):
        angle = gc.roll_mass_angle_for_static_roll_deg(mdl, roll)
        assert gc.static_roll_deg(mdl, angle) == pytest.approx(roll, abs=1e-9)
        assert math.copysign(1.0, angle) == math.copysign(1.0, roll)
    with pytest.raises(ValueError, match="at most"):
        gc.roll_mass_angle_for_static_roll_deg(mdl, 80.0)


def test_wings_to_90_degrees():
    ar = 4.0
    cl, cd = wing_coefficients(np.radians([2.0, 90.0, 45.0, -90.0]), ar, 0.0, 0.02)
    assert cl[0] == pytest.approx(lift_slope(ar) * math.radians(2.0), rel=5e-3)  # blend: 0.3 %
    assert cl[1] == pytest.approx(0.0, abs=1e-9)
    assert cd[1] == pytest.approx(0.02 + 1.11 + 0.018 * ar, rel=1e-9)
    assert cl[2] == pytest.approx((1.11 + 0.018 * ar) * 0.5, rel=1e-4)
    assert cl[3] == pytest.approx(0.0, abs=1e-9) and cd[3] == pytest.approx(cd[1])
    alpha = np.radians(np.linspace(-90, 90, 721))
    cl, cd = wing_coefficients(alpha, ar)
    assert np.all(np.isfinite(cl)) and np.all(cd > 0)
    assert np.allclose(cl, -cl[::-1]) and np.allclose(cd, cd[::-1])
    assert lift_slope(ar, 30.0) < lift_slope(ar)


@given(st.lists(st.integers(-999, 999), min_size=1, max_size=8))
def test_parse_list_commas(values):
    assert parse_list(",".join(str(v) for v in values), "--x") == [float(v) for v in values]


@given(st.integers(-90, 90), st.integers(0, 40), st.integers(1, 20))
def test_parse_list_ranges(start, count, step):
    for sign in (1, -1):
        stop = start + sign * count * step
        got = parse_list(f"{start}:{stop}:{sign * step}", "--x")
        assert got == [float(start + sign * k * step) for k in range(count + 1)]


def test_parse_list_examples_and_refusals():
    assert parse_list("-45:-5:5", "--pitch-deg") == [-45.0 + 5 * k for k in range(9)]
    assert parse_list("-200,-300", "--ballast-cc") == [-200.0, -300.0]
    for bad in ("", "a", "1,,2", "-5:-45:5", "1:2:0", "nan", "1e999"):
        with pytest.raises(ProtocolError, match="--x"):
            parse_list(bad, "--x")


def test_steady_command(model, tmp_path, capsys):
    path = write_model(model, tmp_path / "model.json")
    out = tmp_path / "out"
    assert main(["steady", str(path), "--ballast-cc", "-200,-450", "--pitch-deg", "-40:-10:10",
                 "--roll-deg", "0,10", "--out", str(out)]) == 0
    import pandas as pd

    table = pd.read_csv(out / "steady.csv")
    assert list(table.columns)[:4] == ["ballast_cc", "net_buoyancy_N", "pitch_deg", "roll_deg"]
    assert len(table) == 2 * 4 * 2 and (out / "steady.png").stat().st_size > 10000
    glides = table[table["roll_deg"] == 0]
    assert glides["turn_radius_m"].isna().all()
    assert (table[table["roll_deg"] == 10]["turn_radius_m"] > 0).all()
    assert main(["steady", str(path), "--ballast-cc", "-200", "--pitch-deg", "10",
                 "--out", str(tmp_path / "o2")]) == 0
    row = pd.read_csv(tmp_path / "o2" / "steady.csv").iloc[0]
    assert not row["converged"] and "no forward steady glide" in row["note"]
    capsys.readouterr()
    for args, words in ((["--ballast-cc", "-900", "--pitch-deg", "-20"], "ballast range"),
                        (["--ballast-cc", "x", "--pitch-deg", "-20"], "--ballast-cc"),
                        (["--ballast-cc", "-200", "--pitch-deg", "-95"], "--pitch-deg")):
        assert main(["steady", str(path), *args, "--out", str(tmp_path / "o3")]) == 2
        err = capsys.readouterr().err
        assert words in err and len(err.strip().splitlines()) == 1
    bare = dict(model)
    bare.pop("glider")
    assert main(["steady", str(write_model(bare, tmp_path / "bare.json")), "--ballast-cc",
                 "-200", "--pitch-deg", "-20", "--out", str(tmp_path / "o4")]) == 2
    assert "no 'glider' block" in capsys.readouterr().err


def test_bad_glider_sections_refused(tmp_path):
    text = PROTOCOL.read_text(encoding="utf-8")
    for old, new, words in (
            ("moving_mass_kg = 1.0", "moving_mass_kg = -1.0", "'moving_mass_kg'"),
            ("ballast_cc = [-450.0, 450.0]", "ballast_cc = [450.0, -450.0]", "min < max"),
            ("wing_span_m = 0.4", "wing_spam_m = 0.4", "unknown key 'wing_spam_m'"),
            ("roll_mass_radius_m = 0.03", "", "roll mass needs both")):
        bad = tmp_path / "bad.toml"
        bad.write_text(text.replace(old, new), encoding="utf-8")
        with pytest.raises(ProtocolError, match=words.replace("[", r"\[")):
            load_protocol(bad, check_paths=False, require_runs=False)


def test_simulate_roll_option_refusals(model, tmp_path, capsys):
    path = write_model(model, tmp_path / "model.json")
    for args, words in ((["--manoeuvre", "turning", "--roll-deg", "5"], "for --manoeuvre glide"),
                        (["--manoeuvre", "glide", "--roll-deg", "60"], "at most"),
                        (["--manoeuvre", "glide", "--roll-deg", "95"], "+-80")):
        assert main(["simulate", str(path), *args, "--out", str(tmp_path / "o")]) == 2
        err = capsys.readouterr().err
        assert words in err and len(err.strip().splitlines()) == 1
    bare = dict(model)
    bare.pop("glider")
    bare_path = write_model(bare, tmp_path / "bare.json")
    assert main(["simulate", str(bare_path), "--manoeuvre", "glide", "--roll-deg", "5",
                 "--out", str(tmp_path / "o")]) == 2
    assert "no 'glider' block" in capsys.readouterr().err
    finless = dict(model, coefficients={k: v for k, v in model["coefficients"].items()
                                        if "dr" not in k})
    assert main(["simulate", str(write_model(finless, tmp_path / "finless.json")),
                 "--manoeuvre", "glide", "--rudder-deg", "5", "--out", str(tmp_path / "o")]) == 2
    assert "has no rudder" in capsys.readouterr().err


@pytest.mark.heavy
def test_glide_rudder_turns(trimmed, straight_glide):
    """The glide takes the rudder: the glider trimmed at -20 deg turns with 10 deg of rudder
    and goes straight without."""
    held, start = trimmed
    turned = simulate(held, "glide", 0.6, rudder_deg=10.0, duration_s=300.0,
                      initial_state=start)
    assert abs(turned["psi_deg"].iloc[-1]) > 20.0
    assert abs(straight_glide["psi_deg"].iloc[-1]) < 1e-6


def test_simulate_refuses_a_bad_glider_block(model, tmp_path, capsys):
    bad = dict(model, glider=dict(model["glider"], wing_area_m2="big"))
    path = write_model(bad, tmp_path / "bad.json")
    assert main(["simulate", str(path), "--manoeuvre", "turning", "--out",
                 str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "'wing_area_m2'" in err and len(err.strip().splitlines()) == 1


def test_a_spiralling_glide_is_drawn_in_plan_and_a_straight_one_in_the_vertical_plane():
    """manoeuvre.png: the track of a glide that turns through more than 90° is the plan view
    (its radius shows there); a straight glide stays in the vertical plane (x, depth)."""
    import numpy as np
    import pandas as pd

    from towtank.report.manoeuvre_figure import manoeuvre_figure

    t = np.linspace(0.0, 300.0, 301)
    turning = np.radians(t * 2.0)  # 600° of heading
    base = {"t_s": t, "phi_deg": 0 * t, "theta_deg": -20 + 0 * t, "u_m_s": 0.3 + 0 * t,
            "v_m_s": 0 * t, "w_m_s": 0.1 + 0 * t, "p_deg_s": 0 * t, "q_deg_s": 0 * t,
            "r_deg_s": 2 + 0 * t, "rudder_deg": 0 * t, "sternplane_deg": 0 * t,
            "z_m": 0.1 * t}
    spiral = pd.DataFrame({**base, "x_m": 5 * np.sin(turning), "y_m": 5 * (1 - np.cos(turning)),
                           "psi_deg": np.degrees(turning)})
    straight = pd.DataFrame({**base, "x_m": 0.3 * t, "y_m": 0 * t, "psi_deg": 0 * t})
    labels = [manoeuvre_figure(ts, "glide").axes[0].get_xlabel()
              + manoeuvre_figure(ts, "glide").axes[0].get_ylabel() for ts in (spiral, straight)]
    assert "east" in labels[0] and "depth" not in labels[0]
    assert "depth" in labels[1]


def test_a_pitch_beyond_the_moving_mass_names_the_steepest_it_holds(model):
    """At -300 cc a -80 deg glide needs 1207 mm of travel against the mass's 400: its note
    names the steepest pitch the mass holds, and the glide there needs the mass at its end."""
    table = steady_table(model, [-300.0], [-80.0, -45.0])
    steep, held = table.iloc[0], table.iloc[1]
    assert steep["moving_mass_travel_mm"] > 400.0 and "outside its range" in steep["note"]
    said = steep["note"].split("the steepest pitch it holds in a straight glide at -300 cc is ")
    assert len(said) == 2, steep["note"]
    reach = float(said[1].split(" deg")[0])
    assert -80.0 < reach < -45.0
    end = steady_table(model, [-300.0], [reach]).iloc[0]["moving_mass_travel_mm"]
    assert end == pytest.approx(400.0, abs=2.0)  # the sentence's 3 digits of pitch
    assert "steepest" not in str(held["note"]) and held["moving_mass_travel_mm"] < 400.0


def test_the_equilibrium_residual_moves_the_mass_without_moving_the_model(model):
    """spiral.equilibrium_residual at a centre of gravity the moving mass puts elsewhere: the
    residual of a model built with that centre, bit for bit, and the Dynamics it was given
    left as it was (its centre of gravity, its g(eta))."""
    from towtank.vehicle.spiral import equilibrium_residual

    dyn = Dynamics(model)
    before = (dyn.rg.copy(), [row[:] for row in dyn.g_rows])
    rg = gc.cg_with_controls(model, 0.01, math.radians(20.0))
    assert not np.allclose(rg, dyn.rg)
    nu = np.array([0.3, 0.01, 0.05, 0.002, -0.001, 0.01])
    moved = Dynamics(model | {"cg_m": list(np.asarray(rg, dtype=float))})
    got = equilibrium_residual(dyn, nu, 0.1, -0.3, rg)
    want = (moved.hydro(nu, 0.0, 0.0) - moved.coriolis_rb(nu)
            - coriolis_added_mass(moved.ma, nu) - moved.restoring(0.1, -0.3))
    assert got.tolist() == want.tolist()
    assert np.array_equal(dyn.rg, before[0]) and dyn.g_rows == before[1]
