"""Benchmark of ``towtank identify`` (#25): 3 coefficients from a 120 s record at 20 Hz.

The target is under 30 s on the 2-core test machine for the whole identification (the filter's
passes, the smoother and the least-squares cross-check). No timing is asserted: the figures
depend on the machine. Run it alone to see them::

    PYTHONPATH=. python tests/benchmarks/test_bench_identify.py

which prints the wall and CPU time and writes nothing; with record lengths [s] as arguments
(``... test_bench_identify.py 120 600 1999.95``: 2,401, 12,001 and 40,000 rows) it measures
each and the time per row, from which identify's row limit
(:data:`towtank.vehicle.identify_log.MAX_ROWS`, docs/formats.md "Why 30 000 rows") is set.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]
PAPER = ["N_ur", "N_rdot", "N_uudr"]
NOISE = {"u_m_s": 0.01, "v_m_s": 0.01, "r_deg_s": 0.2, "psi_deg": 0.5, "x_m": 0.05, "y_m": 0.05}
TARGET_S = 30.0


def _remus(tmp: Path) -> dict:
    from towtank.commands.cli import main

    assert main(["predict", str(REPO / "protocols" / "remus_vehicle.toml"), "--out",
                 str(tmp / "p")]) == 0
    model = json.loads((tmp / "p" / "model.json").read_text())
    model["buoyancy_N"] = model["weight_N"]
    return model


def bench(tmp: Path, duration_s: float = 120.0, rate_hz: float = 20.0,
          max_step_s: float | None = None) -> dict:
    """Identify N_ur, N_rdot, N_uudr from zero; the times [s] and the estimates.
    ``max_step_s``: the record's largest integration step [s] (simulate's default: None)."""
    from towtank.vehicle.identify import identify
    from towtank.vehicle.identify_log import log_from_frame
    from towtank.vehicle.simulate import simulate

    model = _remus(tmp)
    ts = simulate(model, "sine", 1.5, rudder_deg=10.0, period_s=10.0, duration_s=duration_s,
                  sample_hz=rate_hz, max_step_s=max_step_s)
    rng = np.random.default_rng(20)
    df = ts[["t_s", "rudder_deg", "sternplane_deg", *NOISE]].copy()
    for col, sd in NOISE.items():
        df[col] = df[col] + rng.normal(0.0, sd, len(df))
    log = log_from_frame(df, "bench")
    wall, cpu = time.perf_counter(), time.process_time()
    res = identify(model, log, PAPER, start="zero")
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    truth = np.array([model["coefficients"][s] for s in PAPER])
    return {"samples": len(log.t), "wall_s": wall, "cpu_s": cpu, "target_s": TARGET_S,
            "ms_per_row": 1e3 * wall / len(log.t),
            "relative_error": (res.value / truth - 1.0).tolist(), "notes": res.notes}


@pytest.mark.heavy
def test_bench_identify_runs_and_reports(tmp_path: Path) -> None:
    """The benchmark's code on a short record (20 s at 10 Hz, 201 rows: the same
    identification, within 5 % of the truth, every field reported); the 120 s figure is
    measured by running the file alone. The record integrated in steps of at most 20 ms
    (RK45, rtol 1e-8: its states within 1e-6 of the default's, far below the noise)."""
    out = bench(tmp_path, duration_s=20.0, rate_hz=10.0, max_step_s=0.02)
    print(json.dumps(out))
    assert out["samples"] == 201
    assert np.all(np.abs(out["relative_error"]) < 0.05)
    assert out["wall_s"] > 0 and out["cpu_s"] > 0 and out["ms_per_row"] > 0
    assert out["target_s"] == TARGET_S and out["notes"]


if __name__ == "__main__":
    import sys
    import tempfile

    with tempfile.TemporaryDirectory() as d:
        for duration in [float(a) for a in sys.argv[1:]] or [120.0]:
            print(json.dumps(bench(Path(d), duration_s=duration)), flush=True)
