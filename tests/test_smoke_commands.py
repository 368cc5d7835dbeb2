"""The commands a lab runs, end to end in a new process each: both sample days, predict,
simulate and identify, watch with its page server. `.ci/run` runs this file with ``--floors``
on the declared minimum versions of every dependency (.ci/min_constraints.py), so a floor in
pyproject.toml that does not work fails CI. The tests marked ``floors`` are skipped by the
suite's own run (the README's test command): there the same commands run in-process, as the
documents quote them (test_docs_commands_run.py), and the golden test checks their outputs."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time
import urllib.request
from pathlib import Path

import pandas as pd
import pytest
from conftest import lab_environment

REPO = Path(__file__).resolve().parents[1]


def _towtank(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "towtank", *args], capture_output=True,
                          text=True, cwd=REPO, timeout=600, env=lab_environment())


@pytest.mark.floors
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


@pytest.mark.floors
def test_the_sample_fin_day(tmp_path):
    run = _towtank("process", "protocols/naca0015_fin.toml", "--out", str(tmp_path / "fin"),
                   "-q")
    assert run.returncode == 0, run.stderr
    fins = pd.read_csv(tmp_path / "fin" / "fins.csv")
    assert len(fins) == 40 and fins["cl"].notna().all()


@pytest.mark.floors
def test_predict_then_simulate(tmp_path):
    run = _towtank("predict", "protocols/remus_vehicle.toml", "--out", str(tmp_path / "remus"))
    assert run.returncode == 0, run.stderr
    run = _towtank("simulate", str(tmp_path / "remus" / "model.json"), "--manoeuvre",
                   "turning", "--duration-s", "60", "--out", str(tmp_path / "turn"))
    assert run.returncode == 0, run.stderr
    metrics = pd.read_csv(tmp_path / "turn" / "metrics.csv").set_index("metric")["value"]
    assert 1.0 < metrics["steady_turn_radius_m"] < 100.0


@pytest.mark.floors
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


@pytest.mark.heavy
def test_watch_gives_a_verdict_and_its_page_serves_the_state(tmp_path):
    """`towtank watch` with its page server (watchfiles, starlette and uvicorn at their floors
    on .ci/run's minimum versions): a run file written into the watched folder gets its
    verdict line, the page server on 127.0.0.1 serves the state holding it, Ctrl-C is 130."""
    from towtank.testing import synthetic as syn
    from towtank.testing.bench_watch import labview_write, start_watch
    from towtank.testing.browser import free_port
    from towtank.testing.days import RunSpec

    day = tmp_path / "day"
    syn.make_hull_day(day, runs=[RunSpec("sting", 0.0, 1.0, 0.5)], fs=50.0, file_format="csv",
                      sheet_format="csv", seed=2)
    (day / "data").rename(tmp_path / "all")
    (day / "data").mkdir()
    protocol = syn.write_protocol(tmp_path / "p.toml", **syn.hull_protocol_sections(
        "day", "out", sheet_format="csv"))
    port = free_port()
    proc = start_watch(protocol, "--no-report", "--port", str(port))
    said: list[str] = []
    threading.Thread(target=lambda: said.extend(proc.stdout or ()), daemon=True).start()

    def until(check, what: str) -> None:  # bounds a hang only
        end = time.monotonic() + 120
        while not check():
            assert proc.poll() is None, f"watch ended: {proc.stderr.read() if proc.stderr else ''}"
            assert time.monotonic() < end, f"{what} never came: {''.join(said)}"
            time.sleep(0.1)

    try:
        until(lambda: any("the live page:" in line for line in said), "the page line")
        labview_write(tmp_path / "all" / "run_001.csv", day / "data" / "run_001.csv")
        until(lambda: any(line.startswith("run 1  ") for line in said), "run 1's verdict")
        line = next(x for x in said if x.startswith("run 1  "))
        assert "steady" in line and "U 1.00 m/s" in line and line.rstrip().endswith("ok")

        def served() -> dict:
            try:
                with urllib.request.urlopen(f"http://127.0.0.1:{port}/state.json",
                                            timeout=5) as resp:
                    return json.loads(resp.read())
            except OSError:
                return {}

        until(lambda: (served().get("latest") or {}).get("run") == 1, "the served state")
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGINT)
        code = proc.wait(timeout=60)
    assert code == 130
