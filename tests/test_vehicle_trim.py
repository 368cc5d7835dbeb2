"""Issue 21: trim and mass properties as stated, steady metrics that mean what they say, dive
to a commanded pitch angle (docs/formats.md §6, docs/method.md "Trim check")."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
REMUS = ROOT / "protocols" / "remus_vehicle.toml"


@pytest.fixture(scope="session")
def remus(tmp_path_factory):
    """model.json of the shipped REMUS protocol (Prestero's W, B, CG and CB)."""
    from towtank.commands.cli import main

    out = tmp_path_factory.mktemp("remus")
    assert main(["predict", str(REMUS), "--out", str(out)]) == 0
    return json.loads((out / "model.json").read_text(encoding="utf-8"))


def _predict(tmp_path, text):
    from towtank.commands.cli import main

    proto = tmp_path / "v.toml"
    proto.write_text(text, encoding="utf-8")
    code = main(["predict", str(proto), "--out", str(tmp_path / "p")])
    model = (json.loads((tmp_path / "p" / "model.json").read_text(encoding="utf-8"))
             if code == 0 else None)
    return code, model


# ---------------------------------------------------------------------------------------------
# 1. trim and mass properties as the user states them


def test_remus_protocol_carries_prestero_weight_buoyancy_and_centres(remus):
    assert remus["weight_N"] == 299.0 and remus["buoyancy_N"] == 306.0
    assert remus["cg_m"] == [0.0, 0.0, 0.0196] and remus["cb_m"] == [0.0, 0.0, 0.0]
    assert remus["mass_kg"] == 30.48 and remus["inertia_kg_m2"] == [0.177, 3.45, 3.45]
    for key in ("mass_kg", "weight_N", "buoyancy_N", "cg_m", "cb_m", "inertia_kg_m2"):
        assert remus["sources"][key] == "given"


def test_a_given_zero_cb_is_used_and_computed_values_say_so(tmp_path):
    """``cb_m = [0, 0, 0]`` is used as given, not replaced by the hull's centre of buoyancy;
    what is computed from the hull says so in ``sources``."""
    text = REMUS.read_text(encoding="utf-8")
    text = text.replace("origin_m = 0.611", "origin_m = 0.6")  # the hull's CB: 0.6058 m
    code, model = _predict(tmp_path, text)
    assert code == 0
    assert model["cb_m"] == [0.0, 0.0, 0.0] and model["sources"]["cb_m"] == "given"
    bare = "\n".join(line for line in text.splitlines()
                     if not line.startswith(("cb_m", "buoyancy_N", "weight_N", "cg_m")))
    (tmp_path / "b").mkdir()
    code, model = _predict(tmp_path / "b", bare)
    assert code == 0
    assert model["sources"]["cb_m"] == "hull centre of buoyancy"
    assert model["cb_m"][0] == pytest.approx(0.6 - 0.6058, abs=0.0005)
    assert model["sources"]["buoyancy_N"] == "hull volume"
    assert model["sources"]["weight_N"] == "mass_kg x g"
    assert model["sources"]["cg_m"] == "centre of buoyancy"
    assert model["cg_m"] == model["cb_m"]


def test_volume_gives_the_buoyancy_and_weight_gives_the_mass(tmp_path):
    text = REMUS.read_text(encoding="utf-8").replace("buoyancy_N = 306.0", "volume_m3 = 0.03")
    text = text.replace("mass_kg = 30.48\n", "")
    code, model = _predict(tmp_path, text)
    assert code == 0
    assert model["buoyancy_N"] == pytest.approx(model["rho_kg_m3"] * 9.80665 * 0.03)
    assert model["sources"]["buoyancy_N"] == "rho g volume_m3"
    assert model["mass_kg"] == pytest.approx(299.0 / 9.80665)
    assert model["sources"]["mass_kg"] == "weight_N / g"


@pytest.mark.parametrize("old,new,words", [
    ("buoyancy_N = 306.0", "buoyancy_N = 306.0\nvolume_m3 = 0.03", "both 'buoyancy_N'"),
    ("weight_N = 299.0", "weight_N = 350.0", "'weight_N'"),
    ("buoyancy_N = 306.0", "buoyancy_N = -306.0", "'buoyancy_N'"),
])
def test_contradictory_or_impossible_mass_properties_are_refused(tmp_path, capsys, old, new,
                                                                 words):
    code, _ = _predict(tmp_path, REMUS.read_text(encoding="utf-8").replace(old, new))
    assert code == 2
    assert words in capsys.readouterr().err


def test_remus_without_net_buoyancy_holds_depth_and_pitch_with_zero_controls(remus):
    """Zero controls and --net-buoyancy-N 0: CG below CB holds depth and pitch (with the CB
    replaced by the hull's, 5 mm ahead of the CG, the model would climb at 14.7 deg of
    pitch)."""
    from towtank.vehicle.simulate import simulate

    ts = simulate(remus, "dive", 1.5, sternplane_deg=0.0, net_buoyancy_n=0.0, duration_s=60.0)
    assert ts["t_s"].iloc[-1] == pytest.approx(60.0)
    assert np.abs(ts["z_m"]).max() < 0.1
    assert np.abs(ts["theta_deg"]).max() < 0.5


def test_remus_with_prestero_7N_buoyancy_settles_as_the_hand_calculation(remus):
    """Prestero's REMUS is 7 N buoyant (B - W = 306 - 299 N). Hand calculation of the steady
    straight run with zero controls (q = 0, constant u, w, theta; body axes, z down):

    - surge: T + X_u|u| u^2 - (W - B) sin(theta) = 0, T = -X_u|u| U^2 (U = 1.5 m/s);
    - heave: Z_uw u w + Z_w|w| w|w| + (W - B) cos(theta) = 0;
    - pitch: (M_uw + M_uwa) u w + M_w|w| w|w| - z_g W sin(theta) = 0, with
      M_uwa = -(Z_wdot - X_udot) the Munk moment that C_A(nu) gives (Fossen 2011 eq. 6.43);
    - depth rate z_dot = -u sin(theta) + w cos(theta).

    With the heave damping alone at theta = 0 and u = U (Z_uw U w + Z_w|w| w|w| = -7 N) the
    vehicle would rise at w = -0.090 m/s; but M_uw + M_uwa = +13.8 kg > 0 (statically unstable
    in pitch): the rise through the water (w < 0) pitches the nose down until the
    metacentric moment z_g W sin(theta) balances it, at theta = -16.0 deg, and the thrust then
    drives the vehicle down at +0.210 m/s (u = 1.134 m/s, w = -0.106 m/s). The simulation
    must settle there, and the trim check must say so.
    """
    from scipy.optimize import brentq

    from towtank.vehicle.simulate import simulate, trim_state, trim_warning

    c = remus["coefficients"]
    w_, b_ = remus["weight_N"], remus["buoyancy_N"]
    zg = remus["cg_m"][2]
    big_u = 1.5
    # heave damping alone, theta = 0, u = U
    w_heave = brentq(lambda w: c["Z_uw"] * big_u * w + c["Z_w|w|"] * w * abs(w) + (w_ - b_),
                     -2.0, 2.0)
    assert w_heave == pytest.approx(-0.090, abs=0.002)
    m_uw = c["M_uw"] - (c["Z_wdot"] - c["X_udot"])
    assert m_uw > 0

    def speeds(theta):  # u from the surge balance, then w from the pitch balance
        u = math.sqrt(big_u**2 - (w_ - b_) * math.sin(theta) / -c["X_u|u|"])
        w = brentq(lambda w: m_uw * u * w + c["M_w|w|"] * w * abs(w)
                   - zg * w_ * math.sin(theta), -1.0, 1.0)
        return u, w

    def heave(theta):
        u, w = speeds(theta)
        return c["Z_uw"] * u * w + c["Z_w|w|"] * w * abs(w) + (w_ - b_) * math.cos(theta)

    theta = brentq(heave, math.radians(-30), math.radians(-0.1))
    u, w = speeds(theta)
    zdot = -u * math.sin(theta) + w * math.cos(theta)
    ts = simulate(remus, "dive", big_u, sternplane_deg=0.0, duration_s=120.0)
    end = ts["t_s"] >= 100.0
    sim_zdot = np.polyfit(ts["t_s"][end], ts["z_m"][end], 1)[0]
    assert math.degrees(theta) == pytest.approx(-15.96, abs=0.05)
    assert ts["theta_deg"].iloc[-1] == pytest.approx(math.degrees(theta), abs=0.05)
    assert sim_zdot == pytest.approx(zdot, rel=0.01)
    assert ts["w_m_s"].iloc[-1] == pytest.approx(w, rel=0.01)
    st = trim_state(remus, big_u)
    assert st["pitch_deg"] == pytest.approx(math.degrees(theta), abs=0.01)
    assert st["depth_rate_m_s"] == pytest.approx(zdot, rel=1e-3)
    assert "out of trim" in trim_warning(remus, big_u)
    assert trim_warning(remus, big_u, 0.0) is None


@pytest.mark.usefixtures("no_command_figures")  # asserts on the numbers, not the figure
def test_simulate_warns_in_one_sentence_when_out_of_trim(tmp_path, capsys, remus):
    from towtank.commands.cli import main

    path = tmp_path / "model.json"
    path.write_text(json.dumps(remus), encoding="utf-8")
    args = ["simulate", str(path), "--manoeuvre", "dive", "--sternplane-deg", "0",
            "--duration-s", "20"]
    assert main(args + ["--out", str(tmp_path / "a")]) == 0
    err = capsys.readouterr().err
    assert "out of trim" in err and "-16.0 deg" in err and len(err.strip().splitlines()) == 1
    assert main(args + ["--net-buoyancy-N", "0", "--out", str(tmp_path / "b")]) == 0
    assert "out of trim" not in capsys.readouterr().err


# ---------------------------------------------------------------------------------------------
# 2. steady metrics that mean what they say


def _geometric_circle(x, y):
    """Radius of the geometric least-squares circle (distances, not Kasa's algebra)."""
    from scipy.optimize import least_squares

    fit = least_squares(lambda p: np.hypot(x - p[0], y - p[1]) - p[2],
                        [x.mean() + 0.1, y.mean(), np.ptp(x) / 2 + 0.1])
    return fit.x[2]


@pytest.mark.parametrize("manoeuvre,kwargs", [
    ("turning", dict(rudder_deg=10.0)),  # level
    ("spiral", dict(rudder_deg=20.0, sternplane_deg=15.0)),  # diving at 13 deg of pitch
])
@pytest.mark.heavy
def test_turn_radius_is_the_circle_of_the_plan_track(remus, manoeuvre, kwargs):
    """The old V cos(theta)/|psi_dot| over the last quarter was 0.3 % (level) and 1.3 %
    (diving spiral: V counts the heave and sway, theta is not the path angle) off the track."""
    from towtank.vehicle.simulate import manoeuvre_metrics, simulate

    ts = simulate(remus, manoeuvre, 1.5, net_buoyancy_n=0.0, **kwargs)
    met = manoeuvre_metrics(ts).set_index("metric")
    last = ts["t_s"] >= 0.8 * ts["t_s"].iloc[-1]
    radius = _geometric_circle(ts["x_m"][last].to_numpy(), ts["y_m"][last].to_numpy())
    assert met.loc["steady_turn_radius_m", "note"] == ""
    assert met.loc["steady_turn_radius_m", "value"] == pytest.approx(radius, rel=1e-3)
    t = ts["t_s"].to_numpy()
    vh = np.hypot(np.gradient(ts["x_m"], t), np.gradient(ts["y_m"], t))[last]
    psi_dot = np.radians(np.gradient(ts["psi_deg"], t))[last]
    assert met.loc["steady_turn_radius_m", "value"] == pytest.approx(
        np.mean(vh / np.abs(psi_dot)), rel=1e-3)


def test_circle_fit_is_exact_on_an_arc():
    from towtank.vehicle.steady import circle_fit

    a = np.linspace(0.3, 1.9, 50)
    xc, yc, r = circle_fit(3.0 + 2.5 * np.cos(a), -1.0 + 2.5 * np.sin(a))
    assert (xc, yc, r) == pytest.approx((3.0, -1.0, 2.5), abs=1e-9)


@pytest.mark.usefixtures("no_command_figures")  # asserts on the numbers, not the figure
def test_a_looping_dive_reports_no_steady_pitch_and_says_why(tmp_path, remus):
    """REMUS with -5 deg of stern plane pitches up over the vertical (theta from 0 past 360
    deg): no steady_pitch_deg (such as 384.4) is reported, and the metrics say why."""
    import pandas as pd

    from towtank.commands.cli import main

    path = tmp_path / "model.json"
    path.write_text(json.dumps(remus), encoding="utf-8")
    assert main(["simulate", str(path), "--manoeuvre", "dive", "--sternplane-deg", "-5",
                 "--out", str(tmp_path / "d")]) == 0
    ts = pd.read_csv(tmp_path / "d" / "manoeuvre.csv")
    assert ts["theta_deg"].max() > 360.0
    met = pd.read_csv(tmp_path / "d" / "metrics.csv", keep_default_na=False,
                      na_values=[""]).set_index("metric")
    assert list(met.columns) == ["value", "unit", "note"]
    for name in ("steady_pitch_deg", "depth_rate_m_s", "speed_m_s", "glide_angle_deg"):
        assert math.isnan(met.loc[name, "value"])
        assert met.loc[name, "note"].startswith("looping")


def _series(theta_deg, manoeuvre="glide", t_end=200.0):
    import pandas as pd

    n = len(theta_deg)
    t = np.linspace(0.0, t_end, n)
    th = np.radians(theta_deg)
    u = np.full(n, 0.5)
    ts = pd.DataFrame({"t_s": t, "x_m": np.cumsum(u * np.cos(th)) * (t[1] - t[0]),
                       "y_m": 0.0, "z_m": -np.cumsum(u * np.sin(th)) * (t[1] - t[0]),
                       "phi_deg": 0.0, "theta_deg": theta_deg, "psi_deg": 0.0,
                       "u_m_s": u, "v_m_s": 0.0, "w_m_s": 0.0, "p_deg_s": 0.0,
                       "q_deg_s": np.gradient(theta_deg, t), "r_deg_s": 0.0,
                       "rudder_deg": 0.0, "sternplane_deg": 0.0})
    ts.attrs["manoeuvre"] = manoeuvre
    return ts


def test_an_oscillating_glider_gets_no_steady_pitch():
    """A glider whose pitch swings between -33 and -6 deg has no steady pitch (not the mean
    over the last fifth, -19.5 deg)."""
    from towtank.vehicle.simulate import manoeuvre_metrics

    t = np.linspace(0.0, 200.0, 4001)
    met = manoeuvre_metrics(_series(-19.5 + 13.5 * np.sin(2 * np.pi * t / 25.0)))
    met = met.set_index("metric")
    assert math.isnan(met.loc["steady_pitch_deg", "value"])
    assert met.loc["steady_pitch_deg", "note"].startswith("pitch oscillating")


def test_angles_are_wrapped_a_looped_pitch_is_looping_and_a_drifting_one_not_settled():
    from towtank.vehicle.simulate import manoeuvre_metrics
    from towtank.vehicle.steady import wrap_deg

    assert wrap_deg(384.4) == pytest.approx(24.4) and wrap_deg(-190.0) == pytest.approx(170.0)
    met = manoeuvre_metrics(_series(np.full(2001, 356.0), "dive")).set_index("metric")
    assert math.isnan(met.loc["steady_pitch_deg", "value"])  # steady, but after a loop
    assert met.loc["steady_pitch_deg", "note"].startswith("looping")
    met = manoeuvre_metrics(_series(np.full(2001, -4.0), "dive")).set_index("metric")
    assert met.loc["steady_pitch_deg", "value"] == pytest.approx(-4.0)
    met = manoeuvre_metrics(_series(np.linspace(-5.0, -25.0, 2001), "dive")).set_index("metric")
    assert math.isnan(met.loc["steady_pitch_deg", "value"])
    assert met.loc["steady_pitch_deg", "note"].startswith("pitch not yet settled")


# ---------------------------------------------------------------------------------------------
# 7. dive to a commanded angle


@pytest.mark.usefixtures("no_command_figures")  # asserts on the numbers, not the figure
@pytest.mark.parametrize("net_buoyancy", ["0", None])
def test_dive_to_30_deg_closes_the_loop_on_pitch(tmp_path, remus, net_buoyancy):
    """--dive-angle-deg 30: the PD law delta_s = Kp (theta - theta_cmd) + Kd q (theta_cmd =
    -30 deg, Kp = 10, Kd = 3 s, saturated at the model's fin_limit_deg = 20 deg; M_uuds < 0, so
    a positive stern plane pitches the nose down). The trimmed REMUS (--net-buoyancy-N 0) holds
    30 +- 1 deg; the 7 N buoyant one reaches it too (its PD steady error is larger). The
    overshoot and time to angle of metrics.csv are those of the time series."""
    import pandas as pd

    from towtank.commands.cli import main
    from towtank.vehicle.simulate import PITCH_KD, PITCH_KP

    assert remus["coefficients"]["M_uuds"] < 0 and remus["fin_limit_deg"] == 20.0
    path = tmp_path / "model.json"
    path.write_text(json.dumps(remus), encoding="utf-8")
    args = ["simulate", str(path), "--manoeuvre", "dive", "--dive-angle-deg", "30",
            "--out", str(tmp_path / "d")]
    assert main(args + (["--net-buoyancy-N", net_buoyancy] if net_buoyancy else [])) == 0
    ts = pd.read_csv(tmp_path / "d" / "manoeuvre.csv")
    met = pd.read_csv(tmp_path / "d" / "metrics.csv", keep_default_na=False,
                      na_values=[""]).set_index("metric")
    dive = -ts["theta_deg"].to_numpy()
    assert dive.max() == pytest.approx(30.0, abs=1.0)
    if net_buoyancy == "0":
        assert -met.loc["steady_pitch_deg", "value"] == pytest.approx(30.0, abs=1.0)
        assert abs(dive[-1] - 30.0) < 1.0
    # the stern plane follows the stated law, saturated at 20 deg, nose down first
    law = np.clip(PITCH_KP * (ts["theta_deg"] + 30.0) + PITCH_KD * ts["q_deg_s"], -20.0, 20.0)
    assert ts["sternplane_deg"].to_numpy() == pytest.approx(law.to_numpy(), abs=1e-3)
    assert ts["sternplane_deg"].iloc[0] == pytest.approx(20.0) and ts["theta_deg"].iloc[5] < 0
    # metrics consistent with the time series
    assert met.loc["dive_angle_deg", "value"] == 30.0
    over = met.loc["dive_angle_overshoot_deg", "value"]
    assert over == pytest.approx(max(0.0, dive.max() - 30.0), abs=1e-4)
    t_reach = met.loc["time_to_dive_angle_s", "value"]
    first = int(np.argmax(dive >= 27.0))
    assert ts["t_s"][first - 1] <= t_reach <= ts["t_s"][first]
    assert 0.0 < t_reach < 10.0


def test_dive_angle_is_checked(tmp_path, capsys, remus):
    from towtank.commands.cli import main

    path = tmp_path / "model.json"
    path.write_text(json.dumps(remus), encoding="utf-8")
    for manoeuvre, angle, words in (("turning", "30", "is for --manoeuvre dive"),
                                    ("dive", "95", "within +-80 deg"),
                                    ("dive", "nan", "within +-80 deg")):
        assert main(["simulate", str(path), "--manoeuvre", manoeuvre, "--dive-angle-deg", angle,
                     "--out", str(tmp_path / "x")]) == 2
        assert words in capsys.readouterr().err
    assert not (tmp_path / "x").exists()
