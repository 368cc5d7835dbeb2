"""`towtank identify` (#25): coefficients from a manoeuvre record by the augmented-state
Kalman filter and smoother, checked by output-error least squares.

The paper case: REMUS (towtank's prediction from protocols/remus_vehicle.toml, Prestero's
geometry), a sinusoidal rudder of 10 deg and 10 s at 1.5 m/s, the paper's measured states
``u, v, r, psi, x, y`` with Gaussian noise (u, v 0.01 m/s; r 0.2 deg/s; psi 0.5 deg; x, y
0.05 m); N_ur (yaw damping, the paper's N_r = N_ur u), N_rdot and N_uudr (the paper's N_delta_r
= N_uudr u^2) from zero starting values.
"""

from __future__ import annotations

import json
import math
from functools import partial
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from towtank.api import identify
from towtank.commands.cli import main
from towtank.vehicle.identify import IDENTIFIABLE_RATIO, BatchModel, rts_smooth
from towtank.vehicle.identify_log import LogError, log_from_frame, read_log
from towtank.vehicle.simulate import Dynamics, read_schedule, simulate

REPO = Path(__file__).resolve().parents[1]
PAPER = ["N_ur", "N_rdot", "N_uudr"]
NOISE = {"u_m_s": 0.01, "v_m_s": 0.01, "r_deg_s": 0.2, "psi_deg": 0.5, "x_m": 0.05, "y_m": 0.05}
KEEP = ["t_s", "x_m", "y_m", "psi_deg", "u_m_s", "v_m_s", "r_deg_s", "rudder_deg",
        "sternplane_deg"]


@pytest.fixture(scope="session")
def remus(tmp_path_factory) -> dict:
    """REMUS predicted from the shipped protocol, neutrally buoyant (weight = buoyancy)."""
    out = tmp_path_factory.mktemp("remus")
    assert main(["predict", str(REPO / "protocols" / "remus_vehicle.toml"), "--out",
                 str(out / "p")]) == 0
    model = json.loads((out / "p" / "model.json").read_text())
    model["buoyancy_N"] = model["weight_N"]
    return model


@pytest.fixture(scope="session")
def sine_clean(remus) -> pd.DataFrame:
    return simulate(remus, "sine", 1.5, rudder_deg=10.0, period_s=10.0, duration_s=60.0,
                    sample_hz=20.0)


def _noisy(clean: pd.DataFrame, seed: int, keep: list[str] | None = KEEP) -> pd.DataFrame:
    """``clean``'s columns ``keep`` (every one: None), white noise added to those of NOISE."""
    rng = np.random.default_rng(seed)
    df = (clean if keep is None else clean[keep]).copy()
    for col, sd in NOISE.items():
        df[col] = df[col] + rng.normal(0.0, sd, len(df))
    return df


def test_batch_model_is_the_simulators_dynamics(remus):
    rng = np.random.default_rng(3)
    dyn = Dynamics(remus)
    for est in (PAPER, ["N_ur", "M_uq"], ["Y_vdot", "N_vdot", "X_u|u|"]):
        bm = BatchModel(remus, est, 1.5)
        beta = np.array([[remus["coefficients"].get(s, 0.0) for s in est]])
        for _ in range(5):
            s = rng.normal(size=12) * 0.3
            s[6] += 1.5
            a = dyn.rhs(s, 0.1, -0.05, -dyn.x_uu * 1.5 ** 2)
            b = bm.rhs(np.vstack([s, s]), np.vstack([beta, beta]), 0.1, -0.05)
            np.testing.assert_allclose(b[0], a, rtol=1e-12, atol=1e-12)
            np.testing.assert_allclose(b[1], a, rtol=1e-12, atol=1e-12)


def test_rts_smoother_equals_filterpys():
    """The smoother over the stored predictions gives filterpy's UKF.rts_smoother."""
    from filterpy.kalman import MerweScaledSigmaPoints
    from filterpy.kalman import UnscentedKalmanFilter as UKF

    def fx(x, dt):
        return np.array([x[0] + dt * x[1], x[1] - dt * (0.5 * x[1] + math.sin(x[0]))])

    def hx(x):
        return x[:1]

    pts = MerweScaledSigmaPoints(2, alpha=0.3, beta=2.0, kappa=0.0)
    ukf = UKF(dim_x=2, dim_z=1, dt=0.1, hx=hx, fx=fx, points=pts)
    ukf.x, ukf.P, ukf.R, ukf.Q = np.array([1.0, 0.0]), np.eye(2) * 0.1, np.eye(1) * 0.01, \
        np.eye(2) * 1e-3
    rng = np.random.default_rng(0)
    zs = np.cos(np.arange(40) * 0.1)[:, None] + rng.normal(0, 0.1, (40, 1))
    n = len(zs)
    xs, ps = np.zeros((n, 2)), np.zeros((n, 2, 2))
    xp, pp, cross = np.zeros((n, 2)), np.zeros((n, 2, 2)), np.zeros((n, 2, 2))
    for k, z in enumerate(zs):
        if k:
            sig = pts.sigma_points(ukf.x, ukf.P)
            x_before = ukf.x.copy()
            ukf.predict()
            f = np.array([fx(s, 0.1) for s in sig])
            cross[k] = (pts.Wc[:, None] * (sig - x_before)).T @ (f - ukf.x)
            xp[k], pp[k] = ukf.x, ukf.P
        ukf.update(z)
        xs[k], ps[k] = ukf.x, ukf.P
    mine, mine_p = rts_smooth(xs, ps, xp, pp, cross)
    ref, ref_p, _ = ukf.rts_smoother(xs, ps)
    np.testing.assert_allclose(mine, ref, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(mine_p, ref_p, rtol=1e-7, atol=1e-12)
    assert np.abs(mine - xs).max() > 1e-3  # the smoother did change the estimates


@pytest.mark.heavy
def test_paper_case_from_zero_starts(remus, sine_clean, tmp_path, capsys, monkeypatch):
    """N_ur, N_rdot, N_uudr from zero within 5 % and inside their 95 % intervals, by the
    command line (simulate's CSV columns, the paper's measured states); UKF and least squares
    agree; model.json gains the values, sources 'identified' and their covariance."""
    (tmp_path / "m").mkdir()
    model_path = tmp_path / "m" / "model.json"
    model_path.write_text(json.dumps(remus))
    log = tmp_path / "sine.csv"
    _noisy(sine_clean, 7).to_csv(log, index=False)
    before = log.read_bytes()
    out = tmp_path / "id"
    import towtank.commands.identify as command
    import towtank.vehicle.identify as ident

    # the estimates, intervals and outputs are tested, not whether the record fits (that is
    # test_identify_adequacy's): identify without the adequacy refit
    monkeypatch.setattr(command, "identify", partial(ident.identify, adequacy=False))
    assert main(["identify", str(model_path), str(log), "--estimate", ",".join(PAPER),
                 "--start", "zero", "--out", str(out)]) == 0
    assert log.read_bytes() == before  # the record is never modified
    said = capsys.readouterr().out
    tab = pd.read_csv(out / "identified.csv")
    assert list(tab.columns[:7]) == ["symbol", "start", "value", "ci_low", "ci_high",
                                     "method", "unit"]
    for method in ("ukf", "ls"):
        rows = tab[tab["method"] == method].set_index("symbol")
        for sym in PAPER:
            truth = remus["coefficients"][sym]
            row = rows.loc[sym]
            assert row["start"] == 0.0
            assert abs(row["value"] / truth - 1.0) < 0.05, (method, sym, row["value"], truth)
            assert row["ci_low"] <= truth <= row["ci_high"], (method, sym)
            assert row["verdict"] == "identifiable"
            assert row["agree"] == "yes"
            assert f"{sym}: identifiable" in said
    new = json.loads((out / "model.json").read_text())
    for sym in PAPER:
        assert new["sources"][sym] == "identified"
        ukf = tab[(tab["method"] == "ukf") & (tab["symbol"] == sym)]["value"].iloc[0]
        assert new["coefficients"][sym] == pytest.approx(ukf, rel=1e-5)
    cov = new["covariance"]
    assert set(PAPER) <= set(cov["symbols"])
    i = cov["symbols"].index("N_ur")
    row = tab[(tab["method"] == "ukf") & (tab["symbol"] == "N_ur")].iloc[0]
    assert math.sqrt(cov["matrix"][i][i]) == pytest.approx(
        (row["ci_high"] - row["ci_low"]) / (2 * 1.959964), rel=1e-3)
    assert (out / "identify.png").stat().st_size > 10_000
    from towtank.vehicle.model import read_model

    assert read_model(out / "model.json")["coefficients"]["N_ur"] == new["coefficients"]["N_ur"]
    assert json.loads(model_path.read_text()) == remus  # the input model is untouched


@pytest.mark.heavy
def test_a_pitch_term_from_a_flat_turn_is_not_identifiable(remus, sine_clean):
    """M_uq (pitch damping) from the horizontal sine: reported not identifiable, its
    interval about as wide as the prior; N_ur beside it still identified."""
    log = log_from_frame(_noisy(sine_clean, 11), "flat")
    res = identify(remus, log, ["N_ur", "M_uq"], start="model", check=False, adequacy=False)
    ok = dict(zip(res.symbols, res.identifiable(), strict=True))
    assert ok == {"N_ur": True, "M_uq": False}
    ci = res.conf_int().loc["M_uq"]
    assert ci["upper"] - ci["lower"] > 2 * abs(remus["coefficients"]["M_uq"])
    assert any("M_uq: NOT identifiable" in line for line in res.verdicts())


@pytest.mark.heavy
def test_model_json_keeps_the_models_value_of_what_is_not_identifiable(
        remus, sine_clean, tmp_path, capsys, monkeypatch):
    """N_ur and M_uq from the horizontal sine by the command line: N_ur identified goes into
    model.json (source 'identified', its covariance); M_uq, NOT identifiable, keeps the
    model's value and source, and the note names it. It was written as 'identified' (M_q|q|
    from such a record went from −8.63 to −25.3, which simulate then used)."""
    import towtank.commands.identify as command
    import towtank.vehicle.identify as ident

    (tmp_path / "m").mkdir()
    model_path = tmp_path / "m" / "model.json"
    model_path.write_text(json.dumps(remus))
    log = tmp_path / "flat.csv"
    _noisy(sine_clean, 11).to_csv(log, index=False)
    monkeypatch.setattr(command, "identify", partial(ident.identify, adequacy=False,
                                                     check=False))
    out = tmp_path / "id"
    assert main(["identify", str(model_path), str(log), "--estimate", "N_ur,M_uq",
                 "--out", str(out)]) == 0
    assert "M_uq: NOT identifiable" in capsys.readouterr().out
    new = json.loads((out / "model.json").read_text())
    assert new["sources"]["N_ur"] == "identified"
    assert new["coefficients"]["M_uq"] == remus["coefficients"]["M_uq"]
    assert new["sources"].get("M_uq") == remus.get("sources", {}).get("M_uq")
    assert "N_ur" in new["covariance"]["symbols"]
    assert "M_uq" not in new["covariance"]["symbols"]
    assert "M_uq kept at the model's values: not identifiable from it" in \
        new["notes"]["identified"]


@pytest.mark.heavy
@pytest.mark.parametrize(("slip", "said"), [
    ("radians", "times the model's 21.26: is the rudder's angle in radians under its _deg "
                "column?"),
    ("reversed", "has the opposite sign of the model's 21.26: is the rudder's sign "
                 "convention reversed in the record?"),
])
def test_a_rudder_in_radians_or_reversed_is_named_against_the_model(remus, sine_clean, slip,
                                                                    said):
    """The sine record's rudder logged in radians under rudder_deg, or with its sign
    reversed: Y_uudr and N_uudr come out 57 times the model's (1200 for 21.3) or with their
    signs flipped, each interval tight, and went into model.json without a word. Each is now
    named against the model's value in one sentence."""
    frame = _noisy(sine_clean, 3)
    frame["rudder_deg"] = (np.radians(frame["rudder_deg"]) if slip == "radians"
                           else -frame["rudder_deg"])
    log = log_from_frame(frame, slip)
    res = identify(remus, log, ["Y_uudr", "N_uudr"], start="model", check=False,
                   adequacy=False)
    warned = res.against_model(remus["coefficients"])
    assert len(warned) == 2, warned
    assert warned[0].startswith("Y_uudr = ") and said in warned[0], warned
    clean = identify(remus, log_from_frame(_noisy(sine_clean, 3), "sine"), ["Y_uudr"],
                     start="model", check=False, adequacy=False)
    assert clean.against_model(remus["coefficients"]) == []


@pytest.mark.heavy
def test_a_coefficient_far_below_1_si_whose_sign_the_record_leaves_open(remus, sine_clean):
    """K_p|p| (roll damping, −0.0055 kg·m² on REMUS) from the horizontal sine with its roll
    recorded: its sd, 0.074, is 2.5 % of the prior's 3·max(|v|, 1) = 3, which alone called it
    identifiable, yet its 95 % interval, ±0.15, is five times its size and holds zero. Now
    it is not identifiable, said as a sign the record does not fix; N_ur (sd ≪ its size)
    from the same kind of record stays identifiable (test above)."""
    log = log_from_frame(_noisy(sine_clean, 5, keep=None), "sine")
    res = identify(remus, log, ["K_p|p|"], start="model", check=False, adequacy=False)
    assert res.sd[0] < IDENTIFIABLE_RATIO * res.prior_sd[0]  # the prior's test alone passes
    assert not res.identifiable()[0]
    (line,) = res.verdicts()
    assert line.startswith("K_p|p|: NOT identifiable") and "does not fix its sign" in line


@pytest.mark.heavy
def test_the_extended_filter_from_zero(remus, sine_clean):
    """--method ekf (the paper's filter): the same three coefficients from zero, within 5 %
    and inside the 95 % intervals."""
    log = log_from_frame(_noisy(sine_clean, 2), "sine")
    res = identify(remus, log, PAPER, method="ekf", start="zero", check=False,
                   adequacy=False)
    truth = np.array([remus["coefficients"][s] for s in PAPER])
    ci = res.conf_int()
    assert np.all(np.abs(res.value / truth - 1) < 0.05)
    assert np.all((ci["lower"].to_numpy() <= truth) & (truth <= ci["upper"].to_numpy()))
    assert res.identifiable().all()


@pytest.mark.heavy
@pytest.mark.parametrize("seed", [1034, 1050])
def test_seed_1034_from_zero_converges_with_the_added_mass_bound(remus, sine_clean, seed):
    """Records 1034 and 1050 from zero converge, within 5 % of the truth and inside the 95 %
    intervals. On 1034 an unbounded UKF stops at t = 0.2 s (a sigma point of N_rdot at
    +3.4 kg m^2 against I_zz = 3.45 kg m^2: a singular mass matrix), so the added mass is bounded
    to the physical side in the process model (DOT_BOUND); on 1050 the bound without the
    projection of the estimate leaves N_rdot stuck at +27.5 kg m^2."""
    from towtank.vehicle.identify import DOT_BOUND

    dyn = BatchModel(remus, PAPER, 1.5)
    izz = remus["inertia_kg_m2"][2]
    assert dyn.upper[1] == pytest.approx(DOT_BOUND * izz)  # N_rdot <= I_zz / 2
    assert np.isinf(dyn.upper[[0, 2]]).all()  # N_ur, N_uudr: no bound
    log = log_from_frame(_noisy(sine_clean, seed), "sine")
    res = identify(remus, log, PAPER, start="zero", check=False, adequacy=False)
    truth = np.array([remus["coefficients"][s] for s in PAPER])
    ci = res.conf_int()
    assert np.all(np.abs(res.value / truth - 1) < 0.05), res.value
    assert np.all((ci["lower"].to_numpy() <= truth) & (truth <= ci["upper"].to_numpy()))
    assert res.value[1] < 0  # the estimate itself is not clipped; it is physical on its own


def test_a_filter_that_still_breaks_down_is_one_sentence_and_exit_2(remus, sine_clean,
                                                                   tmp_path, capsys,
                                                                   monkeypatch):
    """Without the bound the same record breaks the UKF down; that stays one sentence and
    exit 2 with nothing written (the bound is what makes the difference, nothing hides it)."""
    import towtank.vehicle.identify as ident

    monkeypatch.setattr(ident, "DOT_BOUND", math.inf)
    model_path = tmp_path / "model.json"
    model_path.write_text(json.dumps(remus))
    log = tmp_path / "sine.csv"
    _noisy(sine_clean, 1034).to_csv(log, index=False)
    out = tmp_path / "id"
    assert main(["identify", str(model_path), str(log), "--estimate", ",".join(PAPER),
                 "--start", "zero", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "positive definite at t = 0." in err
    assert not (out / "identified.csv").exists()


@pytest.mark.heavy
def test_least_squares_alone_and_the_result_api(remus, sine_clean):
    log = log_from_frame(_noisy(sine_clean, 5), "sine")
    res = identify(remus, log, ["N_ur", "N_uudr"], method="ls", start="zero", adequacy=False)
    truth = np.array([remus["coefficients"][s] for s in ("N_ur", "N_uudr")])
    assert np.all(np.abs(res.value / truth - 1) < 0.05)
    ci90, ci99 = res.conf_int(0.10), res.conf_int(0.01)
    assert np.all(ci99["lower"] < ci90["lower"]) and np.all(ci99["upper"] > ci90["upper"])
    assert "N_uudr" in str(res.summary())


def _write(path: Path, df: pd.DataFrame) -> Path:
    df.to_csv(path, index=False)
    return path


@pytest.mark.parametrize(("mangle", "words"), [
    (lambda d: d.drop(columns=["rudder_deg"]), "rudder_deg is missing"),
    (lambda d: d.assign(t_s=d["t_s"].where(d.index != 50, 1.0)), "time goes back"),
    (lambda d: d.assign(rudder_deg=5.0), "stay at 5 and 0 deg"),
    (lambda d: d[["t_s", "rudder_deg", "sternplane_deg"]], "no state column"),
    (lambda d: d.head(5), "fewer than the 20"),
])
def test_a_bad_log_is_one_sentence_and_exit_2(remus, sine_clean, tmp_path, capsys, mangle,
                                              words):
    model = tmp_path / "model.json"
    model.write_text(json.dumps(remus))
    log = _write(tmp_path / "bad.csv", mangle(_noisy(sine_clean, 1)))
    before = log.read_bytes()
    assert main(["identify", str(model), str(log), "--estimate", "N_ur",
                 "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip()
    assert words in err and "bad.csv" in err and "Traceback" not in err
    assert len(err.splitlines()) == 1
    assert log.read_bytes() == before
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize(("estimate", "words"), [
    ("Q_zz", "not model.json coefficient symbols"),
    ("N_ur,N_ur", "twice"),
    (",", "names no coefficient"),
])
def test_a_bad_estimate_is_one_sentence_and_exit_2(remus, sine_clean, tmp_path, capsys,
                                                   estimate, words):
    model = tmp_path / "model.json"
    model.write_text(json.dumps(remus))
    log = _write(tmp_path / "s.csv", _noisy(sine_clean, 1))
    assert main(["identify", str(model), str(log), "--estimate", estimate,
                 "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert words in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "o").exists()


@pytest.mark.heavy
def test_a_million_rows_are_refused_in_one_sentence(remus, tmp_path, capsys):
    model = tmp_path / "model.json"
    model.write_text(json.dumps(remus))
    log = tmp_path / "huge.csv"
    with open(log, "w") as fh:
        fh.write("t_s,r_deg_s,rudder_deg,sternplane_deg\n")
        fh.write("".join(f"{k * 0.001},0,{k % 7},0\n" for k in range(1_000_000)))
    assert main(["identify", str(model), str(log), "--estimate", "N_ur"]) == 2
    err = capsys.readouterr().err
    assert "1000000 rows" in err and "resample" in err


@pytest.mark.heavy
def test_gaps_nan_and_irregular_sampling_are_handled(remus, sine_clean):
    """Drop a 3 s gap, blank 5 % of the values, jitter the sampling: N_ur still within 5 %."""
    rng = np.random.default_rng(2)
    df = _noisy(sine_clean, 3)
    df = df[(df["t_s"] < 20) | (df["t_s"] > 23)]
    df = df[rng.random(len(df)) > 0.2].copy()  # irregular sampling
    for col in NOISE:
        df.loc[rng.random(len(df)) < 0.05, col] = np.nan
    log = log_from_frame(df, "holes")
    assert any("gap" in n for n in log.notes)
    res = identify(remus, log, ["N_ur"], start="zero", check=False, adequacy=False)
    assert abs(res.value[0] / remus["coefficients"]["N_ur"] - 1) < 0.05


@pytest.mark.heavy
def test_protocol_channels_map_other_names(remus, sine_clean, tmp_path, monkeypatch):
    import towtank.commands.identify as command
    import towtank.vehicle.identify as ident

    # the channels are what is tested, not the record's fit: identify without the adequacy refit
    monkeypatch.setattr(command, "identify", partial(ident.identify, adequacy=False))
    # the first 30 s of the record: N_ur from the model's value needs no more
    df = _noisy(sine_clean, 4).head(601).rename(columns={"r_deg_s": "yaw_rate_rad_s"})
    df["yaw_rate_rad_s"] = np.radians(df["yaw_rate_rad_s"])
    (tmp_path / "p.toml").write_text(
        '[channels]\nr_deg_s = { column = "yaw_rate_rad_s", gain = 57.29577951308232 }\n')
    log_path = _write(tmp_path / "lab.csv", df)
    model = tmp_path / "model.json"
    model.write_text(json.dumps(remus))
    assert main(["identify", str(model), str(log_path), "--estimate", "N_ur", "--method", "ls",
                 "--protocol", str(tmp_path / "p.toml"), "--out", str(tmp_path / "o")]) == 0
    got = pd.read_csv(tmp_path / "o" / "identified.csv")["value"].iloc[0]
    assert abs(got / remus["coefficients"]["N_ur"] - 1) < 0.05


def test_identify_never_writes_over_its_input_model(remus, tmp_path, capsys, sine_clean):
    model = tmp_path / "model.json"
    model.write_text(json.dumps(remus))
    log = _write(tmp_path / "s.csv", _noisy(sine_clean, 1))
    assert main(["identify", str(model), str(log), "--estimate", "N_ur",
                 "--out", str(tmp_path)]) == 2
    assert "never writes over its input" in capsys.readouterr().err
    assert json.loads(model.read_text()) == remus


_COLS = ["t_s", "x_m", "psi_deg", "r_deg_s", "rudder_deg", "sternplane_deg", "junk"]


@pytest.mark.heavy
@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.lists(st.one_of(st.floats(allow_nan=True, allow_infinity=True),
                                   st.text(max_size=4), st.none()),
                         min_size=len(_COLS), max_size=len(_COLS)), max_size=40),
       st.sets(st.sampled_from(_COLS)))
def test_the_log_reader_never_raises_anything_but_its_sentence(rows, drop):
    df = pd.DataFrame(rows, columns=_COLS).drop(columns=sorted(drop))
    try:
        log = log_from_frame(df.astype(str), "fuzz")
    except LogError as exc:
        assert str(exc).startswith("fuzz: ") and "\n" not in str(exc)
    else:
        assert np.all(np.diff(log.t) > 0) and log.measured


def test_read_log_on_garbage_bytes(tmp_path):
    p = tmp_path / "g.csv"
    p.write_bytes(b"\x00\xff\xfe garbage")
    with pytest.raises(LogError, match="g.csv"):
        read_log(p)
    p.write_text('t_s,rudder_deg\n"unclosed,1\n')
    with pytest.raises(LogError):
        read_log(p)


@pytest.mark.heavy
def test_simulate_sine_schedule_and_noise(remus, tmp_path, capsys, monkeypatch):
    """The sine rudder is A sin(2 pi t/T); a schedule is followed (interpolated); --noise has
    the asked standard deviation and the same seed gives the same record."""
    import towtank.commands.simulate as command

    # manoeuvre.csv is tested, not the figure: an empty manoeuvre.png in its place
    monkeypatch.setattr(command, "_figure", lambda ts, metrics, manoeuvre, path, name:
                        Path(path).touch())
    model = tmp_path / "model.json"
    model.write_text(json.dumps(remus))
    args = ["simulate", str(model), "--manoeuvre", "sine", "--rudder-deg", "8", "--period-s",
            "6", "--duration-s", "30", "--sample-hz", "10"]
    assert main(args + ["--out", str(tmp_path / "a")]) == 0
    ts = pd.read_csv(tmp_path / "a" / "manoeuvre.csv")
    assert np.diff(ts["t_s"]).max() == pytest.approx(0.1)
    np.testing.assert_allclose(ts["rudder_deg"], 8 * np.sin(2 * np.pi * ts["t_s"] / 6),
                               atol=1e-4)
    noisy = args + ["--noise", "r=0.5,x=0.1", "--seed", "4"]
    assert main(noisy + ["--out", str(tmp_path / "b")]) == 0
    assert main(noisy + ["--out", str(tmp_path / "c")]) == 0
    b = pd.read_csv(tmp_path / "b" / "manoeuvre.csv")
    assert (tmp_path / "b" / "manoeuvre.csv").read_bytes() == (
        tmp_path / "c" / "manoeuvre.csv").read_bytes()
    assert np.std(b["r_deg_s"] - ts["r_deg_s"]) == pytest.approx(0.5, rel=0.15)
    assert np.std(b["x_m"] - ts["x_m"]) == pytest.approx(0.1, rel=0.15)
    assert (b["u_m_s"] == ts["u_m_s"]).all()
    (tmp_path / "s.csv").write_text("t_s,rudder_deg,sternplane_deg\n0,0,0\n5,10,0\n10,10,-4\n")
    assert main(["simulate", str(model), "--manoeuvre", "schedule", "--schedule",
                 str(tmp_path / "s.csv"), "--sample-hz", "4", "--out", str(tmp_path / "d")]) == 0
    d = pd.read_csv(tmp_path / "d" / "manoeuvre.csv")
    assert d["t_s"].iloc[-1] == pytest.approx(10.0)
    np.testing.assert_allclose(d["rudder_deg"], np.interp(d["t_s"], [0, 5, 10], [0, 10, 10]),
                               atol=1e-6)
    np.testing.assert_allclose(d["sternplane_deg"], np.interp(d["t_s"], [0, 5, 10], [0, 0, -4]),
                               atol=1e-6)
    capsys.readouterr()


@pytest.mark.parametrize(("text", "words"), [
    ("t_s,rudder_deg\n0,0\n0,1\n", "must increase"),
    ("time,rudder\n0,0\n", "needs the columns t_s"),
    ("t_s,rudder_deg\n0,0\n1,x\n", "row 3"),
    ("t_s,rudder_deg\n0,0\n1,60\n", "within ±45"),
])
def test_a_bad_schedule_is_one_sentence_and_exit_2(remus, tmp_path, capsys, text, words):
    model = tmp_path / "model.json"
    model.write_text(json.dumps(remus))
    (tmp_path / "s.csv").write_text(text)
    with pytest.raises(ValueError, match=words):
        read_schedule(tmp_path / "s.csv")
    assert main(["simulate", str(model), "--manoeuvre", "schedule", "--schedule",
                 str(tmp_path / "s.csv"), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert words in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "o").exists()


@pytest.mark.slow
def test_intervals_hold_the_truth_93_to_98_percent_of_the_time(remus, sine_clean):
    """100 records with independent noise: each method's 95 % interval of N_ur, N_rdot,
    N_uudr holds the truth 93-98 % of the time within the binomial sampling error (the
    Clopper-Pearson 95 % interval of the observed rate overlaps [0.93, 0.98])."""
    from scipy.stats import binomtest

    truth = np.array([remus["coefficients"][s] for s in PAPER])
    hits: dict[str, list] = {"ukf": [], "ls": []}
    for seed in range(100):
        res = identify(remus, log_from_frame(_noisy(sine_clean, 1000 + seed), "c"), PAPER,
                       start="zero")
        for method in hits:
            ci = res.conf_int(0.05, method)
            hits[method].append((ci["lower"].to_numpy() <= truth)
                                & (truth <= ci["upper"].to_numpy()))
    counts = {(method, sym): int(np.sum([row[j] for row in h]))
              for method, h in hits.items() for j, sym in enumerate(PAPER)}
    print("coverage of 100 records:", counts)
    for (method, sym), k in counts.items():
        ci = binomtest(k, 100).proportion_ci(0.95)
        assert ci.low <= 0.98 and ci.high >= 0.93, (method, sym, k)
