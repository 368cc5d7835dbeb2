"""Issue 36 items 5-6: the vehicle stage states what it assumes (model.json ``assumptions``,
the neutral-buoyancy check, the speed lost in a turn) and ``steady`` says where the glider's
actuators run out of reach."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from towtank.commands.cli import main
from towtank.commands.steady import parse_list
from towtank.errors import ProtocolError
from towtank.ingest.protocol import load_protocol
from towtank.vehicle import glider_controls as gc
from towtank.vehicle.assumptions import SOURCES, check_assumptions, guessed
from towtank.vehicle.model import read_model, write_model
from towtank.vehicle.schema import ModelError
from towtank.vehicle.simulate import Dynamics
from towtank.vehicle.spiral import body_rates, solve_state, steady_table
from towtank.vehicle.stage import predict_vehicle

REPO = Path(__file__).resolve().parents[1]
PROTOCOLS = REPO / "protocols"


def _predicted(name: str):
    protocol = load_protocol(PROTOCOLS / name, check_paths=False, require_runs=False)
    return predict_vehicle(protocol)


@pytest.fixture(scope="session")
def glider():
    return _predicted("glider_parametric.toml").model


# ---- item 6: steady beyond the actuators' reach


def test_a_roll_past_the_roll_mass_reach_is_one_note_with_the_largest_roll(glider):
    """At -300 cc and 20 deg nose down the roll mass holds at most about 24.6 deg (turned to
    about 114.6 deg, the mass level across the glider: gamma = phi + 90 deg); 25 and 30 deg
    are rows without values whose note names the roll and that reach (not "continuation
    failed"), on either side."""
    table = steady_table(glider, [-300.0], [-20.0], [0.0, 20.0, 24.0, 25.0, 30.0, -30.0])
    rows = table.set_index("roll_deg")
    assert rows.loc[[0.0, 20.0, 24.0], "converged"].all()
    for roll in (25.0, 30.0, -30.0):
        note = rows.loc[roll, "note"]
        assert not rows.loc[roll, "converged"]
        assert "continuation" not in note
        assert f"a roll of {roll:g} deg is beyond the roll mass's reach" in note
        largest = float(note.split("at most ")[1].split(" deg")[0])
        turned = float(note.split("turned to ")[1].split(" deg")[0])
        assert 24.0 < largest < 25.0
        assert largest + 85.0 < turned < largest + 95.0


def test_the_reach_is_the_largest_roll_the_spirals_reach(glider):
    """The stated reach is the peak: a roll just under it converges, with the roll mass
    turned less than the stated angle, and just over it does not."""
    note = steady_table(glider, [-300.0], [-20.0], [26.0]).iloc[0]["note"]
    largest = float(note.split("at most ")[1].split(" deg")[0])
    turned = float(note.split("turned to ")[1].split(" deg")[0])
    x, mdl, why = solve_state(glider, -300.0, -20.0, largest - 0.05)
    assert x is not None, why
    assert math.degrees(x[5]) < turned
    x, mdl, why = solve_state(glider, -300.0, -20.0, largest + 0.05)
    assert x is None


def test_the_steady_rows_below_the_reach_are_stable(glider):
    """Every converged spiral up to the reach is a stable equilibrium of the simulator with the
    controls held (the linearised roll, pitch and velocity dynamics' eigenvalues all have
    negative real parts): none of the reported rows is on the far side of the peak."""
    idx = [3, 4, 6, 7, 8, 9, 10, 11]
    for roll in (10.0, 24.0):
        x, mdl, _ = solve_state(glider, -300.0, -20.0, roll)
        dyn = Dynamics(mdl)
        dyn.rg = gc.cg_with_controls(mdl, x[4], x[5])
        theta, phi = math.radians(-20.0), math.radians(roll)
        s0 = np.zeros(12)
        s0[3], s0[4] = phi, theta
        s0[6:] = np.concatenate((x[:3], body_rates(x[3], phi, theta)))
        jac = np.zeros((8, 8))
        for j, i in enumerate(idx):
            up, down = s0.copy(), s0.copy()
            up[i] += 1e-6
            down[i] -= 1e-6
            jac[:, j] = (dyn.rhs(up, 0, 0, 0)[idx] - dyn.rhs(down, 0, 0, 0)[idx]) / 2e-6
        assert np.linalg.eigvals(jac).real.max() < 0


def test_a_range_written_start_step_stop_says_how_to_write_it():
    with pytest.raises(ProtocolError) as err:
        parse_list("-200:-50:-450", "--ballast-cc")
    assert "-200:-450:-50" in str(err.value)
    assert parse_list("-200:-450:-50", "--ballast-cc") == [-200.0, -250.0, -300.0, -350.0,
                                                         -400.0, -450.0]


# ---- item 5: assumptions in every vehicle output


def test_the_shipped_protocols_list_every_input_and_its_source():
    """REMUS (Prestero's inertia given, its propeller guessed), Series 58 (design tool: fins,
    CG guessed, inertia a default) and the glider (the paper's Table 6 wings, its CG, tail and
    roll mass guessed)."""
    expect = {"remus_vehicle.toml": {"propeller"},
              "series58_vehicle.toml": {"cg_m", "fins", "inertia_kg_m2"},
              "glider_parametric.toml": {"cg_m", "fins", "inertia_kg_m2", "buoyancy_N",
                                         "glider.wing_area_m2", "glider.roll_mass_kg"}}
    for name, guesses in expect.items():
        model = _predicted(name).model
        rows = model["assumptions"]
        assert {r["source"] for r in rows} <= set(SOURCES)
        assert {"mass_kg", "weight_N", "buoyancy_N", "cg_m", "cb_m", "inertia_kg_m2", "hull",
                "fins"} <= {r["input"] for r in rows}
        named = {r["input"] for r in guessed(rows)}
        assert guesses <= named and (guesses or not named), (name, named)
        assert check_assumptions(rows, name) == []
    glider = {r["input"]: r for r in _predicted("glider_parametric.toml").model["assumptions"]}
    assert "Table 6" in glider["glider.wing_area_m2"]["note"]


def test_a_neutral_glider_whose_hull_displaces_more_is_one_warning():
    glider = _predicted("glider_parametric.toml")
    assert len(glider.warnings) == 1
    assert "27.5" in glider.warnings[0] and "20.5 kg" in glider.warnings[0]
    assert _predicted("series58_vehicle.toml").warnings == ()  # 149.4 kg against 150 kg
    assert _predicted("remus_vehicle.toml").warnings == ()  # 7 N buoyant: not declared neutral


def test_model_json_assumptions_are_checked_and_old_files_still_read(tmp_path):
    model = _predicted("series58_vehicle.toml").model
    write_model(model, tmp_path / "model.json")
    assert read_model(tmp_path / "model.json")["assumptions"] == model["assumptions"]
    old = {k: v for k, v in model.items() if k != "assumptions"}
    write_model(old, tmp_path / "old.json")
    assert "assumptions" not in read_model(tmp_path / "old.json")
    bad = dict(model, assumptions=[{"input": "cg_m", "value": 0, "source": "guess",
                                    "note": ""}])
    write_model(bad, tmp_path / "bad.json")
    with pytest.raises(ModelError, match="'assumptions' entry 1"):
        read_model(tmp_path / "bad.json")


@pytest.mark.heavy
def test_predict_simulate_steady_print_the_guessed_inputs_and_the_turn_speed_loss(
        tmp_path, capsys, series58_turn):
    # predict and simulate --manoeuvre turning --rudder-deg 10: conftest's series58_turn
    assert "assumed, not measured (model.json 'assumptions'): cg_m, inertia_kg_m2, fins" \
        in series58_turn.predict_out
    assert "assumed, not measured" in series58_turn.simulate_out
    metrics = pd.read_csv(series58_turn.turn / "metrics.csv").fillna("")
    names = list(metrics["metric"])
    assert names.index("speed_loss_percent") == names.index("steady_turn_radius_m") + 1
    rows = metrics.set_index("metric")
    start = 1.25
    loss = rows.loc["speed_loss_percent", "value"]
    assert loss == pytest.approx(100 * (1 - rows.loc["steady_speed_m_s", "value"] / start),
                                 rel=1e-4)
    assert 20 < loss < 80  # constant thrust: the turn's drag slows it
    assert "model.json 'assumptions'" in rows.loc["steady_turn_radius_m", "note"]
    assert main(["predict", str(PROTOCOLS / "glider_parametric.toml"), "--out",
                 str(tmp_path / "g")]) == 0
    assert "declared neutrally buoyant" in capsys.readouterr().err
    assert main(["steady", str(tmp_path / "g" / "model.json"), "--ballast-cc", "-300",
                 "--pitch-deg", "-20", "--out", str(tmp_path / "st")]) == 0
    assert "glider.wing_area_m2" in capsys.readouterr().out
    note = pd.read_csv(tmp_path / "st" / "steady.csv")["note"][0]
    assert "glider.wing_area_m2" in note


def _vehicle_page_text(model: dict) -> str:
    """The text of the report's "Vehicle" page (pdf.vehicle_pages) of a day whose model is
    ``model``, drawn to a one-page PDF and read back with pypdf."""
    import io
    from types import SimpleNamespace

    from pypdf import PdfReader

    from towtank.report.pdf import vehicle_pages

    coefficients = pd.DataFrame({"symbol": ["X_u|u|", "Y_uv"], "prime": [-3.3e-3, -3.3e-3],
                                 "predicted": [-2.6e-3, -24e-3],
                                 "prime_ci_low": [-3.5e-3, -3.5e-3],
                                 "prime_ci_high": [-3.1e-3, -3.1e-3]})
    day = SimpleNamespace(coefficients=coefficients, vehicle=SimpleNamespace(model=model))
    (page,) = vehicle_pages(day)
    buf = io.BytesIO()
    page.payload[1](page=True).savefig(buf, format="pdf")
    return " ".join(PdfReader(buf).pages[0].extract_text().split())


def test_the_pdf_vehicle_page_lists_the_guessed_inputs():
    """Every default and assumed input of the model, with its value, source and note, in a
    table on the vehicle page; the given ones are not listed."""
    model = _predicted("series58_vehicle.toml").model
    text = _vehicle_page_text(model)
    assert "Assumed, not measured" in text
    rows = guessed(model["assumptions"])
    assert {r["input"] for r in rows} >= {"cg_m", "inertia_kg_m2", "fins"}
    for row in rows:
        assert row["input"] in text
        assert ("assumed" if row["note"].startswith("assumed") else row["source"]) in text
        assert row["note"].removeprefix("assumed: ")[:20] in text
    inertia = next(r for r in rows if r["input"] == "inertia_kg_m2")["value"]
    assert f"{inertia[1]:.3g}" in text
    assert "mass_kg" not in text.split("Assumed, not measured")[1]  # given: not a guess
    bare = _vehicle_page_text({k: v for k, v in model.items() if k != "assumptions"})
    assert "Assumed, not measured" not in bare  # an old model.json: the page as before
