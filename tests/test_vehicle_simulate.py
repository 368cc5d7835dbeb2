"""The 6-DOF simulator against analytic solutions (sway-yaw, straight runs, energy, steps)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from towtank.vehicle.fossen import restoring_matrix
from towtank.vehicle.model import added_mass_matrix, coriolis_added_mass, lumped_to_fossen
from towtank.vehicle.simulate import Dynamics, manoeuvre_metrics, simulate

MASS, IZZ, U = 30.48, 3.45, 1.5
LINEAR = {"X_u|u|": -1.62, "Y_uv": -28.6, "Y_ur": 5.22, "N_uv": 4.0, "N_ur": -2.0,
          "Y_uudr": 9.64, "N_uudr": -6.15, "Z_uw": -28.6, "Z_uq": -5.22, "M_uw": -4.0,
          "M_uq": -2.0}


def _model(coefficients, mass=MASS, buoyancy=None, cg=(0.0, 0.0, 0.0)):
    weight = mass * 9.80665
    return {"name": "test", "rho_kg_m3": 1030.0, "mass_kg": mass, "weight_N": weight,
            "buoyancy_N": weight if buoyancy is None else buoyancy, "cg_m": list(cg),
            "cb_m": [0.0, 0.0, 0.0], "inertia_kg_m2": [0.177, IZZ, IZZ],
            "coefficients": dict(coefficients), "length_m": 1.33}


def _linear_radius(delta):
    """Steady turn of the linear sway-yaw equations (no added mass):
    [Y_v, Y_r - m U; N_v, N_r] [v, r] = -[Y_d, N_d] delta, with Y_v = Y_uv U ... Y_d = Y_uudr U^2.
    R = U / |r| (independent of U)."""
    a = np.array([[LINEAR["Y_uv"] * U, LINEAR["Y_ur"] * U - MASS * U],
                  [LINEAR["N_uv"] * U, LINEAR["N_ur"] * U]])
    b = -np.array([LINEAR["Y_uudr"], LINEAR["N_uudr"]]) * U**2 * delta
    v, r = np.linalg.solve(a, b)
    return U / abs(r)


def test_steady_turn_radius_equals_the_linear_sway_yaw_solution():
    delta = math.radians(1.0)
    ts = simulate(_model(LINEAR), "turning", U, rudder_deg=1.0, duration_s=400.0)
    radius = manoeuvre_metrics(ts).set_index("metric").loc["steady_turn_radius_m", "value"]
    assert radius == pytest.approx(_linear_radius(delta), rel=0.01)


def test_a_straight_run_holds_its_speed_and_stays_straight_and_level():
    # neutrally buoyant, zero rudder, centre of gravity under the centre of buoyancy
    coeffs = LINEAR | {"X_udot": -0.93, "Y_vdot": -35.5, "Z_wdot": -35.5, "N_rdot": -4.88,
                       "M_qdot": -4.88, "Y_v|v|": -131.0, "Z_w|w|": -131.0}
    ts = simulate(_model(coeffs, cg=(0.0, 0.0, 0.02)), "turning", U, rudder_deg=0.0,
                  duration_s=60.0)
    assert np.abs(ts["u_m_s"] - U).max() < 1e-6 * U
    for col in ("y_m", "z_m", "phi_deg", "theta_deg", "psi_deg", "v_m_s", "w_m_s"):
        assert np.abs(ts[col]).max() < 1e-6, col
    assert ts["x_m"].iloc[-1] == pytest.approx(U * 60.0, rel=1e-6)


def test_unforced_motion_conserves_kinetic_energy():
    # no damping, thrust or restoring: C_RB and C_A are skew-symmetric, so 1/2 nu' M nu holds
    coeffs = {"X_udot": -0.93, "Y_vdot": -35.5, "Z_wdot": -35.5, "Y_rdot": 1.93,
              "Z_qdot": -1.93, "N_rdot": -4.88, "M_qdot": -4.88, "K_pdot": -0.0141}
    model = _model(coeffs, cg=(0.01, 0.0, 0.0))
    model["weight_N"] = model["buoyancy_N"] = 0.0
    dyn = Dynamics(model)
    from scipy.integrate import solve_ivp

    y0 = np.zeros(12)
    y0[6:] = [1.0, 0.2, -0.1, 0.3, 0.1, -0.2]
    sol = solve_ivp(lambda t, y: dyn.rhs(y, 0.0, 0.0, 0.0), (0, 20), y0, rtol=1e-10, atol=1e-12)
    energy = [0.5 * y[6:] @ dyn.m_total @ y[6:] for y in sol.y.T]
    assert np.ptp(energy) < 1e-6 * energy[0]


def test_turning_metrics_converge_under_a_halved_step():
    model = _model(LINEAR | {"Y_v|v|": -131.0, "N_r|r|": -9.4, "Y_vdot": -35.5,
                             "N_rdot": -4.88, "X_udot": -0.93})
    a = manoeuvre_metrics(simulate(model, "turning", U, 10.0, duration_s=120, max_step_s=0.1))
    b = manoeuvre_metrics(simulate(model, "turning", U, 10.0, duration_s=120, max_step_s=0.05))
    for va, vb in zip(a["value"], b["value"], strict=True):
        assert va == pytest.approx(vb, rel=1e-4, abs=1e-6)


def test_added_mass_coriolis_reproduces_prestero_terms():
    c = {"X_udot": -0.93, "Y_vdot": -35.5, "Z_wdot": -35.5, "Y_rdot": 1.93, "Z_qdot": -1.93,
         "N_rdot": -4.88, "M_qdot": -4.88}
    ma = added_mass_matrix(c)
    force = -coriolis_added_mass(ma, np.array([0, 1.0, 0, 0, 0, 1.0]))
    assert force[0] == pytest.approx(35.5 - 1.93)  # Prestero's X_vr = -Y_vdot, X_rr = -Y_rdot
    fossen = lumped_to_fossen(c | {"N_uv": -24.0, "Y_ur": 5.22, "N_ur": -2.0, "M_uw": 24.0})
    assert fossen["N_uv"] == pytest.approx(-24.0 - (-35.5 + 0.93))  # Munk moment taken out
    assert fossen["M_uw"] == pytest.approx(24.0 + (-35.5 + 0.93))
    assert fossen["Y_ur"] == pytest.approx(5.22 + 0.93)
    assert fossen["N_ur"] == pytest.approx(-2.0 - 1.93)


def test_zigzag_switches_at_the_check_angle_and_overshoots():
    # a directionally stable vehicle (no Munk moment): the rudder checks every swing
    model = _model(LINEAR | {"Y_v|v|": -131.0, "N_r|r|": -9.4})
    ts = simulate(model, "zigzag", U, rudder_deg=20.0, duration_s=60.0)
    met = manoeuvre_metrics(ts).set_index("metric")["value"]
    assert met["overshoot_1_deg"] > 0 and met["period_s"] > 0
    switch = np.nonzero(np.diff(ts["rudder_deg"].to_numpy()) != 0)[0] + 1
    assert ts["psi_deg"].iloc[switch[0]] == pytest.approx(20.0, abs=0.05)
    assert ts["psi_deg"].iloc[switch[1]] == pytest.approx(-20.0, abs=0.05)


def test_simulated_glide_settles_on_the_steady_glide_solution():
    from towtank.vehicle.glider import glide_table, steady_glide

    # a heavy glider trimmed nose down by its centre of gravity forward of the buoyancy's
    model = _model(LINEAR | {"M_uq": -20.0, "Z_w|w|": -131.0, "M_q|q|": -9.4,
                             "Z_wdot": -35.5, "M_qdot": -4.88, "X_udot": -0.93},
                   cg=(0.01, 0.0, 0.02))
    ts = simulate(model, "glide", 0.5, net_buoyancy_n=-5.0, duration_s=300.0)
    met = manoeuvre_metrics(ts).set_index("metric")["value"]
    assert met["depth_rate_m_s"] > 0 and met["glide_angle_deg"] < -5  # down, forward
    steady = steady_glide(model, -5.0, met["steady_pitch_deg"])
    assert steady["converged"]
    assert steady["speed_m_s"] == pytest.approx(met["speed_m_s"], rel=1e-4)
    assert steady["glide_angle_deg"] == pytest.approx(met["glide_angle_deg"], abs=0.01)
    assert steady["depth_rate_m_s"] == pytest.approx(met["depth_rate_m_s"], rel=1e-4)
    assert abs(steady["trim_moment_Nm"]) < 1e-6  # the pitch the vehicle chose is its trim
    table = glide_table(model, [-2.0, -5.0], [-10.0, -20.0, 10.0])
    ok = table[table["converged"]]
    assert len(ok) == 4 and table.loc[~table["converged"], "pitch_deg"].tolist() == [10.0, 10.0]
    # more net weight, faster glide at the same pitch
    fast = ok.set_index(["net_buoyancy_N", "pitch_deg"])["speed_m_s"]
    assert fast[(-5.0, -20.0)] > fast[(-2.0, -20.0)]


def _write(path, model):
    import json

    path.write_text(json.dumps(model))
    return path


def test_bad_model_files_stop_with_one_sentence_and_exit_2(tmp_path, capsys):
    from towtank.commands.cli import main

    good = _model(LINEAR)
    cases = {
        "missing": (None, "cannot be read"),
        "text": ("not json", "cannot be read"),
        "nokey": ({k: v for k, v in good.items() if k != "mass_kg"}, "lacks the key 'mass_kg'"),
        "symbol": (good | {"coefficients": {"Y_foo": 1.0}}, "'Y_foo' is not a coefficient"),
        "nan": (good | {"coefficients": {"Y_uv": float("nan")}}, "not a finite number"),
        "cg": (good | {"cg_m": [0, 0]}, "three numbers"),
    }
    for name, (content, message) in cases.items():
        path = tmp_path / f"{name}.json"
        if isinstance(content, dict):
            _write(path, content)
        elif content is not None:
            path.write_text(content)
        out = tmp_path / f"out_{name}"
        assert main(["simulate", str(path), "--manoeuvre", "turning", "--out", str(out)]) == 2
        err = capsys.readouterr().err
        assert message in err and err.count("\n") == 1, (name, err)
        assert not out.exists()


def test_a_diverging_model_is_refused_not_crashed(tmp_path, capsys):
    from towtank.commands.cli import main

    bad = _model(LINEAR | {"X_u|u|": 50.0, "Y_uv": 500.0, "N_ur": 300.0})  # wrong signs
    path = _write(tmp_path / "bad.json", bad)
    code = main(["simulate", str(path), "--manoeuvre", "turning", "--duration-s", "200",
                 "--out", str(tmp_path / "o")])
    assert code == 2
    assert "diverges" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


@pytest.mark.heavy
@pytest.mark.usefixtures("no_command_figures")  # asserts on the words, not the figure
def test_a_coefficient_of_the_wrong_sign_is_named(tmp_path, capsys):
    """model.json edited by hand with X_udot and K_pdot positive (their signs reversed):
    simulate ran it with exit 0 and no word; it still runs, with one warning per coefficient
    that is negative for any vehicle. The right signs give none."""
    from towtank.commands.cli import main

    good = _write(tmp_path / "good.json", _model(LINEAR | {"X_udot": -0.94, "K_pdot": -0.0127}))
    bad = _write(tmp_path / "bad.json", _model(LINEAR | {"X_udot": 0.94, "K_pdot": 0.0127}))
    for path, said in ((good, []), (bad, ["X_udot = +0.94 is positive", "K_pdot = +0.0127"])):
        assert main(["simulate", str(path), "--manoeuvre", "turning", "--duration-s", "5",
                     "--out", str(tmp_path / path.stem)]) == 0
        err = [line for line in capsys.readouterr().err.splitlines() if "is positive" in line]
        assert len(err) == len(said), err
        for line, words in zip(err, said, strict=True):
            assert words in line and line.endswith("is its sign reversed?"), line


@pytest.mark.heavy
@pytest.mark.usefixtures("no_command_figures")  # asserts on the numbers, not the figure
def test_shipped_remus_protocol_predicts_and_turns(tmp_path, capsys):
    """protocols/remus_vehicle.toml: predict, then a 10 deg turn at 1.25 m/s (the MATLAB
    tool's Table 6 case; its 150 kg vehicles turn 3-8 times wider, docs/method.md)."""
    import json
    from pathlib import Path

    from towtank.commands.cli import main

    proto = Path(__file__).resolve().parents[1] / "protocols" / "remus_vehicle.toml"
    assert main(["predict", str(proto), "--out", str(tmp_path / "p")]) == 0
    model = json.loads((tmp_path / "p" / "model.json").read_text())
    assert model["length_m"] == pytest.approx(1.33, abs=0.005)
    assert main(["simulate", str(tmp_path / "p" / "model.json"), "--manoeuvre", "turning",
                 "--rudder-deg", "10", "--speed", "1.25", "--out", str(tmp_path / "t")]) == 0
    met = pd_read(tmp_path / "t" / "metrics.csv")
    radius, td = met["steady_turn_radius_m"], met["tactical_diameter_m"]
    assert 0.5 * td < met["advance_m"] < 2 * td and met["transfer_m"] < td
    assert 1.5 * radius < td < 3 * radius  # the turn tightens as the speed falls
    assert 2.0 < td / model["length_m"] < 5.0  # 3.2 L (docs/method.md)


def pd_read(path):
    import pandas as pd

    return pd.read_csv(path).set_index("metric")["value"]


def test_a_turn_without_a_rudder_is_refused_in_one_sentence(tmp_path, capsys):
    """The sample hull day's model.json has no fins: a turning run printed an infinite radius
    and NaN metrics; it must say that the model has no rudder (exit 2, nothing written)."""
    import json

    from towtank.commands.cli import main

    model = tmp_path / "model.json"
    data = {"name": "bare hull", "rho_kg_m3": 1000.0, "mass_kg": 1.0, "weight_N": 9.81,
            "buoyancy_N": 9.81, "cg_m": [0, 0, 0], "cb_m": [0, 0, 0],
            "inertia_kg_m2": [0.01, 0.1, 0.1],
            "coefficients": {"X_udot": -0.02, "Y_vdot": -0.7, "X_u|u|": -0.2}}
    model.write_text(json.dumps(data), encoding="utf-8")
    out = tmp_path / "sim"
    assert main(["simulate", str(model), "--manoeuvre", "turning", "--out", str(out)]) == 2
    assert "has no rudder" in capsys.readouterr().err
    assert not out.exists()


@pytest.mark.heavy
@pytest.mark.usefixtures("no_command_figures")  # asserts on the numbers, not the figure
def test_simulate_and_predict_never_replace_a_users_file(tmp_path, capsys):
    """Issue 14's rule for the vehicle commands: a file of the user's named metrics.csv or
    model.json stops them (exit 2) and is left as it was; their own files are replaced."""
    from towtank.commands.cli import main

    root = Path(__file__).resolve().parents[1]
    out = tmp_path / "pred"
    out.mkdir()
    (out / "model.json").write_text("mine", encoding="utf-8")
    protocol = root / "protocols" / "remus_vehicle.toml"
    assert main(["predict", str(protocol), "--out", str(out)]) == 2
    assert (out / "model.json").read_text(encoding="utf-8") == "mine"
    (out / "model.json").unlink()
    assert main(["predict", str(protocol), "--out", str(out)]) == 0
    assert main(["predict", str(protocol), "--out", str(out)]) == 0  # its own: replaced
    sim = tmp_path / "sim"
    sim.mkdir()
    (sim / "metrics.csv").write_text("mine", encoding="utf-8")
    assert main(["simulate", str(out / "model.json"), "--manoeuvre", "turning",
                 "--out", str(sim)]) == 2
    assert (sim / "metrics.csv").read_text(encoding="utf-8") == "mine"
    assert "did not write" in capsys.readouterr().err


def _fossen_4_6(w, b, rg, rb, phi, theta):
    """g(eta) written out as Fossen (2011) prints eq. 4.6."""
    (xg, yg, zg), (xb, yb, zb) = rg, rb
    sth, cth, sph, cph = math.sin(theta), math.cos(theta), math.sin(phi), math.cos(phi)
    return [
        (w - b) * sth,
        -(w - b) * cth * sph,
        -(w - b) * cth * cph,
        -(yg * w - yb * b) * cth * cph + (zg * w - zb * b) * cth * sph,
        (zg * w - zb * b) * sth + (xg * w - xb * b) * cth * cph,
        -(xg * w - xb * b) * cth * sph - (yg * w - yb * b) * sth,
    ]


_finite = dict(allow_nan=False, allow_infinity=False)


@pytest.mark.heavy
@settings(max_examples=200)
@given(w=st.floats(1.0, 1e5), b=st.floats(1.0, 1e5),
       rg=st.tuples(*[st.floats(-2.0, 2.0, **_finite)] * 3),
       rb=st.tuples(*[st.floats(-2.0, 2.0, **_finite)] * 3),
       phi=st.floats(-math.pi, math.pi), theta=st.floats(-math.pi / 2, math.pi / 2))
def test_the_restoring_forces_are_fossen_4_6_in_the_simulator_and_the_filter(w, b, rg, rb,
                                                                               phi, theta):
    """One G (towtank.vehicle.fossen.restoring_matrix) for the simulator's g(eta), bit for bit
    the equation as printed, and the identification's batched G [sin theta, cos theta sin phi,
    cos theta cos phi]."""
    model = _model({}, mass=w / 9.80665, buoyancy=b, cg=rg)
    model["weight_N"], model["cb_m"] = w, list(rb)
    want = _fossen_4_6(w, b, rg, rb, phi, theta)
    assert Dynamics(model).restoring(phi, theta).tolist() == want
    g = restoring_matrix(w, b, np.array(rg), np.array(rb))
    trig = np.array([math.sin(theta), math.cos(theta) * math.sin(phi),
                     math.cos(theta) * math.cos(phi)])
    scale = max(abs(w), abs(b)) * (1.0 + max(map(abs, (*rg, *rb))))
    np.testing.assert_allclose(g @ trig, want, rtol=0, atol=1e-12 * scale)


def test_a_bottom_heavy_vehicle_is_righted_in_roll_and_pitch():
    """Neutral, the centre of gravity 2 cm below the centre of buoyancy (z down): rolled to
    starboard or pitched nose up, the moment on the vehicle (-g(eta)) turns it back."""
    model = _model({}, cg=(0.0, 0.0, 0.02))
    dyn = Dynamics(model)
    assert -dyn.restoring(0.2, 0.0)[3] < 0 < -dyn.restoring(-0.2, 0.0)[3]
    assert -dyn.restoring(0.0, 0.2)[4] < 0 < -dyn.restoring(0.0, -0.2)[4]
    assert np.allclose(dyn.restoring(0.0, 0.0), 0.0)
    top_heavy = Dynamics(_model({}, cg=(0.0, 0.0, -0.02)))  # above: it capsizes
    assert -top_heavy.restoring(0.2, 0.0)[3] > 0 and -top_heavy.restoring(0.0, 0.2)[4] > 0
