"""Issue 35 item 8: ``towtank inspect`` and ``towtank watch`` on captive runs.

inspect reduces a captive run as the day does (its steady window, its loads about O with the
inertia removed; a PMM run's cycles, each kept or dropped and why, the measured frequency and
amplitude against the sheet's) and says the day's one sentence for a run the day rejects; its
guess of a captive balance's channels proposes fx, fy, mz, sway, yaw; watch gives captive runs
verdicts that name their test and loads.
"""

from __future__ import annotations

import io
import time
import tomllib
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from towtank.commands.inspect import inspect_run
from towtank.ingest.describe import describe_file, protocol_block
from towtank.ingest.protocol import load_protocol
from towtank.reduce.captive import CaptiveRun, cycle_verdicts, pmm_cycles
from towtank.reduce.run import reduce_record
from towtank.testing.bench_watch import watch_session
from towtank.testing.captive import CaptiveRunSpec, make_captive_day

PLAN = [
    CaptiveRunSpec(1, "drift", drift_deg=8.0),
    CaptiveRunSpec(2, "sway", amplitude_m=0.1, frequency_hz=0.35),
    CaptiveRunSpec(3, "sway", amplitude_m=0.1, frequency_hz=0.35, steady_cycles=2),
    CaptiveRunSpec(4, "yaw", amplitude_m=0.1, frequency_hz=0.35),
]


@pytest.fixture(scope="session")
def day(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("captive")
    make_captive_day(root, plan=PLAN, seed=3)
    sheet = pd.read_csv(root / "run_sheet.csv")
    sheet.loc[sheet["run"] == 4, "pmm_frequency_hz"] = 0.30  # the rig ran at 0.35 Hz
    sheet.to_csv(root / "run_sheet.csv", index=False)
    return root


def _inspect(day: Path, tmp_path: Path, run: int) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    code = inspect_run(day / "data" / f"run_{run:03d}.csv", day / "protocol.toml",
                       png=tmp_path / f"run_{run}.png", out=out, err=err)
    return code, out.getvalue(), err.getvalue()


def _day_record(day: Path, run: int):  # noqa: ANN202 - a Record
    protocol = load_protocol(day / "protocol.toml")
    sheet = pd.read_csv(day / "run_sheet.csv")
    row = sheet[sheet["run"] == run].iloc[0].to_dict()
    return reduce_record(protocol, row)


def _numbers(line: str) -> list[float]:
    return [float(x) for x in line.replace("−", "-").split() if _is_number(x)]


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def test_inspect_a_static_run_gives_the_days_loads_about_o(day, tmp_path):
    code, out, err = _inspect(day, tmp_path, 1)
    assert code == 0 and err == "", err
    assert "captive run: drift test, horizontal plane" in out and "drift 8 deg" in out
    _, red, rejection, _ = _day_record(day, 1)
    assert rejection is None and red is not None
    lo, hi = red.windows["steady"]
    assert f"steady window  {lo:.2f} – {hi:.2f} s" in out
    mean = next(line for line in out.splitlines() if line.strip().startswith("mean "))
    x, _, y, _, n, _ = _numbers(mean.replace("±", " "))
    cr = CaptiveRun.from_arrays(1, "run_001.csv", red.captive)
    day_mean = cr.rows.iloc[0]
    assert (x, y, n) == pytest.approx((day_mean["X"], day_mean["Y"], day_mean["N"]), abs=1e-4)
    assert (tmp_path / "run_1.png").is_file()


def test_inspect_a_pmm_run_lists_its_cycles_and_the_measured_motion(day, tmp_path):
    code, out, err = _inspect(day, tmp_path, 2)
    assert code == 0 and err == "", err
    for part in ("in phase (sin)", "quadrature (cos)", "PMM cycles of the sway"):
        assert part in out
    cycle_lines = [ln for ln in out.splitlines() if "amplitude" in ln and " – " in ln]
    kept = [ln for ln in cycle_lines if ln.rstrip().endswith("kept")]
    dropped = [ln for ln in cycle_lines if "dropped: " in ln]
    assert len(kept) == 5 and dropped and all("ramp-in or ramp-out" in ln
                                              or "outside the steady window" in ln
                                              for ln in dropped)
    assert "cycles_used    5" in out
    freq = next(ln for ln in out.splitlines() if ln.strip().startswith("frequency"))
    assert "0.35 Hz in the sheet" in freq and _numbers(freq)[0] == pytest.approx(0.35, rel=0.01)
    amp = next(ln for ln in out.splitlines() if ln.strip().startswith("amplitude "))
    assert "0.1 m in the sheet" in amp


def test_inspect_says_the_days_sentence_for_a_run_the_day_rejects(day, tmp_path):
    for run, words in ((3, "2 whole steady PMM cycles"), (4, "0.3 Hz")):
        code, out, err = _inspect(day, tmp_path, run)
        _, red, rejection, _ = _day_record(day, run)
        assert red is None and rejection is not None
        assert code == 1 and words in err and rejection.detail.split(": ", 1)[-1] in err
        assert len(err.strip().splitlines()) == 1
        assert "PMM cycles of the sway" in out  # and why: the cycles, kept or dropped
    _, out, _ = _inspect(day, tmp_path, 3)
    assert "cycles_used    2" in out


def test_cycle_verdicts_keep_exactly_the_days_cycles():
    fs, f, a = 100.0, 0.4, 0.1
    t = np.arange(0.0, 40.0, 1.0 / fs)
    env = np.clip((t - 5.0) / 2.5, 0.0, 1.0) * np.clip((35.0 - t) / 2.5, 0.0, 1.0)
    y = a * env * np.sin(2 * np.pi * f * (t - 5.0))
    steady = (int(8.0 * fs), int(33.0 * fs))
    verdicts = cycle_verdicts(t, y, steady)
    cyc = pmm_cycles(t, y, steady)
    kept = [v.start for v in verdicts if v.kept]
    assert kept == pytest.approx(list(cyc.starts))
    assert sum(not v.kept for v in verdicts if t[steady[0]] <= v.start
               and v.end <= t[steady[1] - 1]) == cyc.dropped
    assert any(v.reason == "outside the steady window" for v in verdicts)
    assert all(v.reason for v in verdicts if not v.kept)
    assert [v.start for v in verdicts] == sorted(v.start for v in verdicts)


def _block(tmp_path: Path, header: str) -> str:
    path = tmp_path / "lab.csv"
    n = len(header.split(","))
    path.write_text(header + "\n" + "".join(",".join(["0.0"] * n) + "\n" for _ in range(20)))
    return protocol_block(describe_file(path))


def test_a_captive_balances_columns_are_proposed_as_fx_fy_mz_sway_yaw(tmp_path):
    block = _block(tmp_path, "Time (s),Carriage speed (m/s),Fx (N),Fy (N),Mz (N m),PMM y,"
                             "Yaw angle (deg)")
    channels = tomllib.loads(block)["channels"]
    assert channels == {"time": {"column": "Time (s)"},
                        "speed": {"column": "Carriage speed (m/s)"},
                        "fx": {"column": "Fx (N)"}, "fy": {"column": "Fy (N)"},
                        "mz": {"column": "Mz (N m)"}, "sway": {"column": "PMM y"},
                        "yaw": {"column": "Yaw angle (deg)"}}
    assert "drag" not in channels and "lift" not in channels


@pytest.mark.parametrize("header", ["Time (s),Speed (m/s),Fx (N)",
                                    "Time (s),Speed (m/s),Fx (N),Fy (N)"])
def test_a_hull_balances_fx_is_still_the_drag(tmp_path, header):
    channels = tomllib.loads(_block(tmp_path, header))["channels"]
    assert channels["drag"] == {"column": "Fx (N)"}
    assert "fx" not in channels and "mz" not in channels
    if "Fy" in header:
        assert channels["lift"] == {"column": "Fy (N)"}


@pytest.mark.heavy
def test_watch_gives_captive_runs_their_loads_and_the_days_verdicts(tmp_path):
    make_captive_day(tmp_path, plan=PLAN[:3], seed=3)
    protocol = tmp_path / "protocol.toml"
    protocol.write_text(protocol.read_text() + "\n[watch]\nsettle_s = 1.0\n"
                        "pdf_interval_s = 3600.0\n")
    s, lines = watch_session(protocol, live_figures=True)
    try:
        s.clock = lambda: time.time() + 10.0
        s.step()
        s.clock = lambda: time.time() + 20.0
        s.step()
        state = s.state()
        by_run = {v["run"]: v for v in state["verdicts"]}
        assert set(by_run) == {1, 2, 3}
        ok = by_run[1]
        assert ok["status"] == "ok" and ok["drag_N"] is None
        assert ok["line"].startswith("run 1  drift  β 8.0°  U 1.50 m/s  X ")
        assert " Y " in ok["line"] and " N m" in ok["line"] and "drag" not in ok["line"]
        runs = pd.read_csv(tmp_path / "out" / "runs.csv").set_index("run")
        assert ok["captive"]["Y_N"] == pytest.approx(runs.loc[1, "captive_Y_N"], rel=1e-6)
        assert by_run[2]["captive"]["cycles_used"] == 5 and "5 cycles" in by_run[2]["line"]
        assert "PMM 0.10 m 0.35 Hz" in by_run[2]["line"]
        bad = by_run[3]
        assert bad["status"] == "rejected" and "2 whole steady PMM cycles" in bad["reason"]
        assert bad["captive"] == {"X_N": None, "Y_N": None, "N_Nm": None, "cycles_used": None}
        assert sum(line.startswith("run ") for line in lines) == 3
        assert state["figures"].get("latest_run")
        s._start_fits()
        assert s._collect_fits(wait=True)
        assert s.state()["figures"].get("captive") == "captive.png"
        assert (s.live_dir / "captive.png").read_bytes()[:4] == b"\x89PNG"
    finally:
        s.finish()
