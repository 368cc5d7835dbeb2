"""Issue 33, "Trust, third round", items 7 and 15: identify's time gaps, its bounded work,
progress and row limit; the glider's plausibility checks and identify's ``--noise`` parser.

The cases: a gap of 1e7 s in a record (Runge-Kutta sub-steps without a bound would hang
identify), a bound on the integrator's sub-steps, progress while identify works, a moving-mass
travel of +-40 m on a 1.65 m hull refused by predict and steady, and ``--noise u=0`` or
``u=1,u=2`` refused by the parser.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import given
from hypothesis import strategies as st

from towtank.commands.cli import main
from towtank.commands.identify import noise_option
from towtank.ingest.protocol import load_protocol
from towtank.testing.hang import hang_bound
from towtank.vehicle import identify_log
from towtank.vehicle.identify import MAX_SUBSTEPS, BatchModel, identify
from towtank.vehicle.identify_log import (
    MAX_GAP_S,
    MAX_ROWS,
    STATE_COLUMNS,
    LogError,
    ManoeuvreLog,
    log_from_frame,
)
from towtank.vehicle.model import write_model
from towtank.vehicle.simulate import simulate
from towtank.vehicle.stage import predict_vehicle

REPO = Path(__file__).resolve().parents[1]
GLIDER = REPO / "protocols" / "glider_parametric.toml"
KEEP = ["t_s", "x_m", "y_m", "psi_deg", "u_m_s", "v_m_s", "r_deg_s", "rudder_deg",
        "sternplane_deg"]
#: Bound of a call that must answer at once (an unbounded gap takes hours) [s];
#: a bound on hangs, not on speed.
HANG_S = 60.0


def _predicted(protocol: str) -> dict:
    """The model.json ``towtank predict`` makes of a shipped protocol."""
    path = REPO / "protocols" / protocol
    return predict_vehicle(load_protocol(path, check_paths=False, require_runs=False)).model


@pytest.fixture(scope="session")
def remus() -> dict:
    """REMUS, neutrally buoyant."""
    model = _predicted("remus_vehicle.toml")
    return dict(model, buoyancy_N=model["weight_N"])


@pytest.fixture(scope="session")
def record(remus) -> pd.DataFrame:
    """A 40 s sine manoeuvre at 20 Hz (801 rows), the paper's states with a little noise."""
    ts = simulate(remus, "sine", 1.5, rudder_deg=10.0, period_s=10.0, duration_s=40.0,
                  sample_hz=20.0)
    rng = np.random.default_rng(7)
    df = ts[KEEP].copy()
    for col in KEEP[1:7]:
        df[col] = df[col] + rng.normal(0.0, 0.01, len(df))
    return df


@pytest.fixture
def model_path(remus, tmp_path) -> Path:
    path = tmp_path / "model.json"
    path.write_text(json.dumps(remus))
    return path


def _one_sentence(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert "Traceback" not in err
    return lines[0]


# --- item 7 (a): a gap in the time ---------------------------------------------------------

def test_a_gap_of_1e7_s_is_refused_at_once_naming_the_row_and_the_gap(model_path, record,
                                                                        tmp_path, capsys):
    df = record.copy()
    df.loc[600:, "t_s"] += 1e7
    log = tmp_path / "gap.csv"
    df.to_csv(log, index=False)
    before = log.read_bytes()
    with hang_bound(HANG_S):
        code = main(["identify", str(model_path), str(log), "--estimate", "N_ur",
                     "--out", str(tmp_path / "o")])
    assert code == 2
    line = _one_sentence(capsys.readouterr().err)
    assert "gap.csv" in line and "row 602" in line and "1e+07 s" in line
    assert f"{MAX_GAP_S:g} s" in line
    assert log.read_bytes() == before
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("gap_s", [MAX_GAP_S + 0.5, 60.0, 3600.0])
def test_a_gap_beyond_the_limit_is_a_sentence_one_within_is_predicted_across(record, gap_s):
    df = record.copy()
    df.loc[300:, "t_s"] += gap_s
    with pytest.raises(LogError, match=r"^g: the time jumps by .* at row 302 "):
        log_from_frame(df, "g")
    df = record.copy()
    df.loc[300:, "t_s"] += MAX_GAP_S - 0.15  # a step of 0.05 s + this: MAX_GAP_S - 0.1 s
    log = log_from_frame(df, "g")
    assert any("gap" in note for note in log.notes)


def test_a_time_in_milliseconds_is_named_not_taken_for_a_gap(record):
    """The record's t_s in ms (every step 50 "s"): it was refused as "the time jumps by 50 s
    at row 3 ... split the record at the gap", a gap it does not have; the sentence now asks
    whether t_s is in ms."""
    df = record.copy()
    df["t_s"] = df["t_s"] * 1000.0
    with pytest.raises(LogError, match=r"^g: the time steps by 50 s from row to row "
                                       r"\(median\).*is t_s in ms\?$"):
        log_from_frame(df, "g")


# --- item 7 (b): the integrator's work is bounded ------------------------------------------

@pytest.mark.parametrize("dt", [1e7, MAX_SUBSTEPS * 0.05 + 0.1, math.inf, math.nan])
def test_the_runge_kutta_sub_steps_are_bounded(remus, dt):
    dyn = BatchModel(remus, ["N_ur"], 1.5)
    aug = np.zeros((3, 13))
    aug[:, 6] = 1.5
    with hang_bound(HANG_S), pytest.raises(ValueError, match=f"more than the {MAX_SUBSTEPS} "
                                                       "Runge-Kutta steps"):
        dyn.step(aug, dt, (0.0, 0.0), (0.1, 0.0))
    assert dyn.step(aug, MAX_SUBSTEPS * 0.05, (0.0, 0.0), (0.1, 0.0)).shape == (3, 13)


def test_a_record_built_past_the_reader_stops_at_the_bound(remus, record):
    """A ManoeuvreLog made by hand (no reader checks) with a 1e7 s gap: one sentence, at
    once, from the filter and from least squares."""
    log = log_from_frame(record, "hand")
    t = log.t.copy()
    t[600:] += 1e7
    hand = ManoeuvreLog(t=t, z=log.z, rudder=log.rudder, sternplane=log.sternplane,
                        measured=log.measured, name="hand")
    for method in ("ukf", "ls"):
        with hang_bound(HANG_S), pytest.raises(ValueError, match="Runge-Kutta steps"):
            identify(remus, hand, ["N_ur"], method=method, check=False)


# --- item 7 (c): progress ------------------------------------------------------------------

@pytest.mark.heavy
def test_identify_reports_each_stage_of_its_work(remus, record):
    seen: list[tuple[str, int, int]] = []
    log = log_from_frame(record.head(241), "short")
    identify(remus, log, ["N_ur"], progress=lambda *a: seen.append(a))
    stages = list(dict.fromkeys(s for s, _, _ in seen))
    # the filter's passes, its least-squares cross-check, then the fit's held-out refit
    assert stages[0] == "UKF pass 1 of at most 4" and "least squares" in stages
    assert stages[-1] == "least squares, first 75% of the record"
    for stage in (s for s in stages if s.startswith("UKF")):  # each pass: rows, up to all
        done = [d for s, d, total in seen if s == stage]
        assert done == sorted(done) and done[-1] == len(log.t)
        assert {total for s, _, total in seen if s == stage} == {len(log.t)}
    assert all(0 < d <= total == 60 for s, d, total in seen if s.startswith("least squares"))


@pytest.mark.heavy
@pytest.mark.parametrize(("quiet", "shown"), [([], True), (["--quiet"], False)])
@pytest.mark.usefixtures("no_command_figures")  # asserts on the words printed, not the figure
def test_the_command_shows_progress_on_a_terminal_unless_quiet(model_path, record, tmp_path,
                                                               capsys, monkeypatch, quiet,
                                                               shown):
    log = tmp_path / "short.csv"
    record.head(241).to_csv(log, index=False)
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)
    # the record's noise as it was made: at 0.01 deg of psi, below the sine's second
    # differences at 20 Hz, the noise estimated from the record is twice too large
    noise = "x=0.01,y=0.01,psi=0.01,u=0.01,v=0.01,r=0.01"
    assert main(["identify", str(model_path), str(log), "--estimate", "N_ur", "--noise", noise,
                 "--out", str(tmp_path / "o"), *quiet]) == 0
    err = capsys.readouterr().err
    assert ("UKF pass 1" in err and "least squares" in err) is shown
    assert (err == "") is not shown


# --- item 7 (d): the row limit -------------------------------------------------------------

def test_the_row_limit_sentence_says_the_limit_and_the_time(model_path, tmp_path, capsys):
    log = tmp_path / "long.csv"
    with open(log, "w") as fh:
        fh.write("t_s,r_deg_s,rudder_deg,sternplane_deg\n")
        fh.write("".join(f"{k * 0.05:.2f},0,{k % 7},0\n" for k in range(MAX_ROWS + 1)))
    with hang_bound(HANG_S):
        assert main(["identify", str(model_path), str(log), "--estimate", "N_ur",
                     "--out", str(tmp_path / "o")]) == 2
    line = _one_sentence(capsys.readouterr().err)
    assert f"has {MAX_ROWS + 1} rows, more than the {MAX_ROWS}" in line
    assert f"{identify_log.MAX_ROWS_MINUTES:g} minutes" in line and "resample" in line
    assert not (tmp_path / "o").exists()


# --- item 15: --noise ----------------------------------------------------------------------

SHORT = [c.split("_", 1)[0] for c in STATE_COLUMNS]


@given(st.dictionaries(st.sampled_from(range(12)),
                       st.floats(min_value=1e-9, max_value=1e6, allow_nan=False),
                       max_size=12),
       st.lists(st.booleans(), min_size=12, max_size=12))
def test_noise_reads_back_what_was_written(values, short):
    text = ",".join(f"{SHORT[i] if short[i] else STATE_COLUMNS[i]}={v!r}"
                    for i, v in values.items())
    assert noise_option(text) == {STATE_COLUMNS[i]: v for i, v in values.items()}


@given(st.text(alphabet="uvrpsixyz_m=,.-+0123456789eEnaf ", max_size=40))
def test_noise_is_a_dict_of_positive_numbers_or_the_parsers_one_sentence(text):
    try:
        out = noise_option(text)
    except argparse.ArgumentTypeError as exc:
        assert "\n" not in str(exc) and str(exc).endswith(".")
        return
    assert set(out) <= set(STATE_COLUMNS)
    assert all(math.isfinite(v) and v > 0 for v in out.values())
    named = [p.partition("=")[0].strip() for p in text.split(",") if p.strip()]
    assert len(named) == len(out)  # each state once


@pytest.mark.parametrize(("noise", "words"), [
    ("u=0", "standard deviation of u must be a finite number > 0, not '0'"),
    ("u=-0.1", "> 0, not '-0.1'"),
    ("r=inf", "> 0, not 'inf'"),
    ("u=1,u=2", "names the state u_m_s twice"),
    ("u=1,u_m_s=2", "names the state u_m_s twice"),
    ("speed=1", "'speed' is not a state"),
    ("u", "'u' is not state=sd"),
])
def test_a_bad_noise_is_the_parsers_usage_and_one_sentence(model_path, tmp_path, capsys, noise,
                                                          words):
    with pytest.raises(SystemExit) as stop:
        main(["identify", str(model_path), str(tmp_path / "none.csv"), "--estimate", "N_ur",
              "--noise", noise, "--out", str(tmp_path / "o")])
    assert stop.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith("usage: towtank identify")
    errors = [ln for ln in err.splitlines() if "error:" in ln]
    assert len(errors) == 1 and "argument --noise: " in errors[0] and words in errors[0]
    assert not (tmp_path / "o").exists()


def test_identify_api_refuses_a_zero_or_unknown_noise(remus, record):
    log = log_from_frame(record.head(100), "api")
    for noise, words in (({"u": 0.0}, "> 0"), ({"speed": 1.0}, "not a state")):
        with pytest.raises(ValueError, match=words):
            identify(remus, log, ["N_ur"], method="ls", noise=noise)


# --- item 15: the glider's inputs against its hull -----------------------------------------

def _glider_protocol(tmp_path: Path, key: str, value: str) -> Path:
    lines = GLIDER.read_text().splitlines()
    hit = [i for i, ln in enumerate(lines) if ln.startswith(f"{key} ")]
    assert len(hit) == 1
    lines[hit[0]] = f"{key} = {value}"
    path = tmp_path / "glider.toml"
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.mark.parametrize(("key", "value", "words"), [
    ("moving_mass_travel_mm", "[-40000.0, 40000.0]",
     "travel 80 m, more than the hull's length of 1.65 m"),
    ("moving_mass_travel_mm", "[1000.0, 1700.0]", "travel 1.7 m, more than the hull's length"),
    ("moving_mass_travel_mm", "[-400.0, 900.0]", "outside the hull (x from -0.8786 to 0.7714 m)"),
    ("ballast_cc", "[-100000.0, 450.0]", "more than the hull's volume of 27604.1 cc"),
    ("ballast_x_m", "2.0", "must lie inside the hull (x from -0.8786 to 0.7714 m)"),
    ("wing_x_m", "-1.0", "must lie inside the hull"),
    ("moving_mass_neutral_m", "[0.0, 0.0, 0.3]", "0.3 m from the x axis, more than the hull's "
     "radius of 0.08 m"),
    ("roll_mass_radius_m", "0.5", "0.5 m from the x axis, more than the hull's radius"),
    ("moving_mass_kg", "30.0", "('moving_mass_kg' 30 kg plus 'roll_mass_kg' 2 kg) must be "
     "less than the glider's mass (20.5 kg)"),
])
def test_a_glider_input_outside_its_hull_stops_predict(tmp_path, capsys, key, value, words):
    protocol = _glider_protocol(tmp_path, key, value)
    assert main(["predict", str(protocol), "--out", str(tmp_path / "o")]) == 2
    line = _one_sentence(capsys.readouterr().err)
    assert line.startswith("towtank: glider.toml: ") and f"'{key}'" in line
    assert words in line
    assert not (tmp_path / "o").exists()


@pytest.fixture(scope="session")
def glider_model() -> dict:
    return _predicted(GLIDER.name)


@pytest.mark.parametrize("command", [
    ["steady", "--ballast-cc", "-300", "--pitch-deg", "-20"],
    ["simulate", "--manoeuvre", "glide", "--duration-s", "5"],
])
def test_a_model_glider_block_outside_its_hull_stops_steady_and_simulate(glider_model,
                                                                         tmp_path, capsys,
                                                                         command):
    """The hand-edited model.json of the issue: steady reported glides that needed 11.8 m of
    travel on the 1.65 m glider."""
    model = json.loads(json.dumps(glider_model))
    model["glider"]["moving_mass_travel_mm"] = [-40000.0, 40000.0]
    path = tmp_path / "model.json"
    write_model(model, path)
    args = [command[0], str(path), *command[1:], "--out", str(tmp_path / "o")]
    assert main(args) == 2
    line = _one_sentence(capsys.readouterr().err)
    assert "model.json: 'glider'" in line and "'moving_mass_travel_mm'" in line
    assert "more than the hull's length of 1.65 m" in line
    assert not (tmp_path / "o").exists()
