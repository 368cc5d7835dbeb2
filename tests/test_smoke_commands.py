"""The commands a lab runs, end to end in a new process each: both sample days, predict,
simulate and identify. `.ci/run` also runs this file on the declared minimum versions of every
dependency (.ci/min_constraints.py), so a floor in pyproject.toml that does not work fails CI."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest

REPO = Path(__file__).resolve().parents[1]


def _towtank(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "towtank", *args], capture_output=True,
                          text=True, cwd=REPO, timeout=600)


def test_the_sample_hull_day(tmp_path):
    run = _towtank("process", "protocols/sut2_hull.toml", "--out", str(tmp_path / "hull"), "-q")
    assert run.returncode == 0, run.stderr
    coef = pd.read_csv(tmp_path / "hull" / "coefficients.csv").set_index("symbol")["value"]
    # the generator's truth of the sample day (README): found within its stated errors
    assert coef["X_u|u|"] == pytest.approx(-0.205317, rel=0.005)
    assert coef["Y_v|v|"] == pytest.approx(-5.97285, rel=0.005)
    assert coef["Y_vdot"] == pytest.approx(-0.68084, rel=0.01)
    for name in ("report.pdf", "report.xlsx", "predicted.csv", "model.json"):
        assert (tmp_path / "hull" / name).is_file(), name


def test_the_sample_fin_day(tmp_path):
    run = _towtank("process", "protocols/naca0015_fin.toml", "--out", str(tmp_path / "fin"),
                   "-q")
    assert run.returncode == 0, run.stderr
    fins = pd.read_csv(tmp_path / "fin" / "fins.csv")
    assert len(fins) == 40 and fins["cl"].notna().all()


def test_predict_then_simulate(tmp_path):
    run = _towtank("predict", "protocols/remus_vehicle.toml", "--out", str(tmp_path / "remus"))
    assert run.returncode == 0, run.stderr
    run = _towtank("simulate", str(tmp_path / "remus" / "model.json"), "--manoeuvre",
                   "turning", "--duration-s", "60", "--out", str(tmp_path / "turn"))
    assert run.returncode == 0, run.stderr
    metrics = pd.read_csv(tmp_path / "turn" / "metrics.csv").set_index("metric")["value"]
    assert 1.0 < metrics["steady_turn_radius_m"] < 100.0


def test_simulate_a_sine_then_identify(tmp_path):
    """A noisy sine record from simulate, N_ur identified back by the UKF (filterpy at its
    floor on .ci/run's minimum versions)."""
    run = _towtank("predict", "protocols/remus_vehicle.toml", "--out", str(tmp_path / "remus"))
    assert run.returncode == 0, run.stderr
    model = tmp_path / "remus" / "model.json"
    run = _towtank("simulate", str(model), "--manoeuvre", "sine", "--rudder-deg", "10",
                   "--period-s", "10", "--duration-s", "30", "--sample-hz", "10",
                   "--net-buoyancy-N", "0", "--out", str(tmp_path / "sine"))
    assert run.returncode == 0, run.stderr
    rec = pd.read_csv(tmp_path / "sine" / "manoeuvre.csv")
    rec = rec[["t_s", "psi_deg", "r_deg_s", "u_m_s", "v_m_s", "rudder_deg", "sternplane_deg"]]
    rec.to_csv(tmp_path / "log.csv", index=False)
    run = _towtank("identify", str(model), str(tmp_path / "log.csv"), "--estimate", "N_ur",
                   "--noise", "psi=0.1,r=0.05,u=0.005,v=0.005", "--out", str(tmp_path / "id"))
    assert run.returncode == 0, run.stderr
    assert "N_ur: identifiable" in run.stdout
    for name in ("identified.csv", "model.json", "identify.png"):
        assert (tmp_path / "id" / name).is_file(), name
