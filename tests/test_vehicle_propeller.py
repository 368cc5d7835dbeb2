"""Issue 36 item 5: ``simulate --propeller rps``, the model's B-series propeller at a constant
rate, so that the speed lost in a turn is the propeller's, not a constant thrust's."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from towtank.commands.cli import main
from towtank.ingest.protocol import load_protocol
from towtank.vehicle.model import read_model, write_model
from towtank.vehicle.powering import (
    Propeller,
    bseries_kt_kq,
    kt_polynomial,
    propeller_from,
    propeller_thrust,
    self_propulsion_rps,
)
from towtank.vehicle.schema import ModelError
from towtank.vehicle.simulate import Dynamics, manoeuvre_metrics, propulsion, simulate
from towtank.vehicle.stage import predict_vehicle

REMUS = Path(__file__).resolve().parents[1] / "protocols" / "remus_vehicle.toml"


@pytest.fixture(scope="session")
def remus() -> dict:
    protocol = load_protocol(REMUS, check_paths=False, require_runs=False)
    return predict_vehicle(protocol).model


@settings(max_examples=60, deadline=None)
@given(j=st.floats(0.0, 1.6), pd_ratio=st.floats(0.5, 1.4), ear=st.floats(0.3, 1.05),
       z=st.integers(2, 7))
def test_the_thrust_polynomial_in_j_is_the_b_series(j, pd_ratio, ear, z):
    """K_T as a cubic in J (P/D, A_E/A_0, Z fixed) equals the 39 terms of Oosterveld & van
    Oossanen's Table 1 at any point of the series."""
    coef = kt_polynomial(Propeller(0.1, pd_ratio, ear, z))
    kt, _ = bseries_kt_kq(j, pd_ratio, ear, z)
    assert np.polyval(coef[::-1], j) == pytest.approx(float(kt), abs=1e-12)


def test_the_self_propulsion_rate_gives_the_thrust_that_balances_the_drag():
    """At n of the self-propulsion point T(1 - t) = R at U; a slower u means a smaller J and
    a larger K_T, so more thrust; a negative u is taken as J = 0 (the bollard thrust)."""
    prop = Propeller(0.134, 1.0, 0.5, 3, thrust_deduction=0.031, wake_fraction=0.246)
    n = self_propulsion_rps(3.6, 1.5, prop, 1026.0)
    assert (1 - 0.031) * propeller_thrust(1.5, n, prop, 1026.0) == pytest.approx(3.6, rel=1e-9)
    thrusts = [propeller_thrust(u, n, prop, 1026.0) for u in (1.5, 1.0, 0.5, 0.0)]
    assert np.all(np.diff(thrusts) > 0)
    assert propeller_thrust(-0.5, n, prop, 1026.0) == pytest.approx(thrusts[-1])


def test_the_remus_protocol_gives_its_propeller_and_says_it_is_assumed(remus):
    block = remus["propeller"]
    assert propeller_from(block) == Propeller(0.134, 1.0, 0.5, 3, 0.031, 0.246)
    entry = next(a for a in remus["assumptions"] if a["input"] == "propeller")
    assert entry["value"] == block and entry["note"].startswith("assumed:")


def test_a_straight_run_at_the_self_propulsion_rate_holds_its_speed(remus):
    """Neutral, zero controls: the propeller at n holds the start speed as the constant thrust
    does (the surge forces agree at u = U)."""
    dyn = Dynamics(remus)
    push, n = propulsion(remus, dyn, 1.5, "rps")
    const, none = propulsion(remus, dyn, 1.5, "thrust")
    assert none is None and 5 < n < 20
    assert push(1.5) == pytest.approx(const(1.5), rel=1e-9)
    neutral = dict(remus, weight_N=remus["buoyancy_N"], cg_m=[0.0, 0.0, 0.0196])
    ts = simulate(neutral, "turning", 1.5, rudder_deg=0.0, duration_s=5.0, propeller="rps")
    assert ts["u_m_s"].iloc[-1] == pytest.approx(1.5, abs=1e-6)
    assert ts.attrs["propeller"] == "rps" and ts.attrs["propeller_rps"] == pytest.approx(n)


@pytest.mark.heavy
def test_at_constant_rps_a_turn_loses_less_speed_than_at_constant_thrust(remus):
    """REMUS, 15 deg rudder, the first 12 s of the turn: the same start, then the propeller's
    thrust rises as the vehicle slows (K_T grows as J falls) and the speed falls less."""
    runs = {p: simulate(remus, "turning", 1.5, rudder_deg=15.0, duration_s=12.0, propeller=p)
            for p in ("thrust", "rps")}
    speed = {p: float(np.hypot(ts["u_m_s"], ts["v_m_s"]).iloc[-1]) for p, ts in runs.items()}
    assert speed["thrust"] < 0.8 * 1.5  # a constant thrust loses more than 20 %
    assert speed["rps"] > speed["thrust"] + 0.15
    metrics = manoeuvre_metrics(runs["rps"]).set_index("metric")
    assert metrics.loc["propeller_rps", "value"] == pytest.approx(
        runs["rps"].attrs["propeller_rps"])
    assert "propeller_rps" not in set(manoeuvre_metrics(runs["thrust"])["metric"])


@pytest.mark.usefixtures("no_command_figures")  # asserts on the numbers, not the figure
def test_simulate_propeller_rps_records_the_option_in_metrics(tmp_path, capsys, remus):
    write_model(remus, tmp_path / "model.json")
    assert main(["simulate", str(tmp_path / "model.json"), "--manoeuvre", "turning",
                 "--rudder-deg", "15", "--duration-s", "5", "--propeller", "rps",
                 "--out", str(tmp_path / "rps")]) == 0
    out = capsys.readouterr().out
    assert "assumed, not measured (model.json 'assumptions'): propeller" in out
    rows = pd.read_csv(tmp_path / "rps" / "metrics.csv").set_index("metric")
    assert rows.loc["propeller_rps", "unit"] == "1/s"
    assert "--propeller rps" in rows.loc["propeller_rps", "note"]
    assert main(["simulate", str(tmp_path / "model.json"), "--manoeuvre", "turning",
                 "--rudder-deg", "15", "--duration-s", "5", "--out",
                 str(tmp_path / "thrust")]) == 0
    assert "assumed, not measured" not in capsys.readouterr().out  # the thrust's run: unused
    rows = pd.read_csv(tmp_path / "thrust" / "metrics.csv").set_index("metric")
    assert "propeller_rps" not in rows.index


def test_propeller_rps_without_a_propeller_is_one_sentence_and_nothing_written(
        tmp_path, capsys, remus):
    bare = {k: v for k, v in remus.items() if k != "propeller"}
    write_model(bare, tmp_path / "model.json")
    out = tmp_path / "sim"
    assert main(["simulate", str(tmp_path / "model.json"), "--manoeuvre", "turning",
                 "--propeller", "rps", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "--propeller rps needs the model's propeller" in err and "[vehicle.propeller]" in err
    assert not out.exists()
    write_model(remus, tmp_path / "model.json")
    assert main(["simulate", str(tmp_path / "model.json"), "--manoeuvre", "glide",
                 "--propeller", "rps", "--out", str(out)]) == 2
    assert "a glide has no propulsion" in capsys.readouterr().err
    assert not out.exists()


def test_model_json_propeller_block_is_checked(tmp_path, remus):
    bad = dict(remus, propeller=dict(remus["propeller"], pitch_ratio=3.0))
    (tmp_path / "model.json").write_text(json.dumps(bad), encoding="utf-8")
    with pytest.raises(ModelError, match="'pitch_ratio' in \\[propeller\\] must be a number"):
        read_model(tmp_path / "model.json")
    write_model(remus, tmp_path / "good.json")
    assert read_model(tmp_path / "good.json")["propeller"] == remus["propeller"]
