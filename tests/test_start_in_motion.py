"""Runs logged while the carriage already moves (issue 23 items 3 and 4).

The still window before the carriage moves is needed only when the zero comes from it
(`zero_at = "before_motion"` without a zeros file). With a zeros file (`[zeros]`), or with
`zero_at = "file_start"`, a run may start in motion: its phases then start with the
acceleration or the steady speed; the zero is the zeros file's (drift to the post-run window as
usual) or, with `file_start` and no still start, the still window after the stop.

Proven on the generator's hull day with its zeros files ("zero-file" layout), every run file cut
so that it starts in motion (the carriage accelerating at t = 0, or moving from t = 0.45 s as in
the issue): the fitted coefficients are the truth's within the tolerances of
tests/test_readers.py (2 %). Measured (seed 11): X_udot +1.70 %, Y_vdot +0.19 %, X_u|u| −0.03 %,
Y_v|v| +0.01 % with the zeros files; +1.88 %, −0.33 %, −0.03 %, −0.15 % with file_start; the
uncut day gives +1.73 %, +0.08 %, −0.01 %, 0.00 %.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import towtank
from towtank.errors import RunError
from towtank.signal.conditioning import lowpass
from towtank.signal.phases import detect_phases
from towtank.testing import synthetic as syn
from towtank.testing.layouts import protocol_sections

SEED = 11
SYMBOLS = ("X_udot", "Y_vdot", "X_u|u|", "Y_v|v|")


def _cut_day(root: Path) -> dict:
    """The zero-file hull day with every run file starting in motion: even runs at the start
    of the acceleration (motion at t = 0), odd runs 0.45 s before it; time from 0."""
    syn.make_hull_day(root, seed=SEED, file_format="zero-file", sheet_format="csv",
                      channel_style="lab")
    truth = json.loads((root / "truth.json").read_text())
    for key, run in truth["runs"].items():
        path = root / "data" / run["file"]
        frame = pd.read_csv(path)
        lead = 0.0 if int(key) % 2 == 0 else 0.45
        t = frame["Time (s)"].to_numpy()
        keep = frame[t >= run["t_accel_start"] - lead - 1e-9].copy()
        keep["Time (s)"] = np.round(keep["Time (s)"] - keep["Time (s)"].iloc[0], 6)
        path.write_text(keep.to_csv(index=False, lineterminator="\n"))
    return truth


def _protocol(root: Path, name: str, *, zeros: bool, **processing) -> Path:
    sections = syn.hull_protocol_sections(".", "out", sheet_format="csv",
                                          channels=syn.LabChannels(), channel_style="lab")
    sections = protocol_sections("zero-file", sections)
    if not zeros:
        sections.pop("zeros")
    sections.setdefault("processing", {}).update(processing)
    return syn.write_protocol(root / name, **sections)


@pytest.fixture(scope="session")
def cut_day(tmp_path_factory):
    root = tmp_path_factory.mktemp("moving")
    return root, _cut_day(root)


def _check(day, truth) -> None:
    assert not day.rejected, day.rejected
    got = day.coefficients.set_index("symbol")["value"]
    for sym in SYMBOLS:
        assert got[sym] == pytest.approx(truth["coefficients"][sym], rel=0.02), sym


@pytest.mark.heavy
def test_without_a_zero_source_a_run_in_motion_is_rejected_in_one_sentence(cut_day):
    root, truth = cut_day
    day = towtank.process_day(_protocol(root, "plain.toml", zeros=False), jobs=1,
                              report=False)
    usable = {int(k) for k, r in truth["runs"].items() if r["status"] != "void"}
    assert set(day.rejected) == usable
    reason = str(day.rejected[4])
    assert "there is no still window before the carriage moves" in reason
    assert "[zeros]" in reason and "file_start" in reason


def test_a_zeros_file_replaces_the_still_window(cut_day):
    """Issue 23 item 3: with [zeros] every run starting in motion is reduced, its phases start
    with the acceleration (no still window), and the coefficients are the truth's."""
    root, truth = cut_day
    day = towtank.process_day(_protocol(root, "zeros.toml", zeros=True), jobs=1,
                              report=False)
    _check(day, truth)
    red = day.reductions[4]  # motion from t = 0: the acceleration is the first phase
    assert red.windows["still_pre"] is None
    assert red.windows["accel"] is not None and red.windows["accel"][0] < 1.0
    assert any("zeros file run_004_zero.csv" in n for n in red.notes)


def test_file_start_lets_a_run_start_in_motion(cut_day):
    """Issue 23 item 4: zero_at = "file_start" on runs logged while moving: the zero is the
    still window after the stop (said in the run's notes), the coefficients the truth's."""
    root, truth = cut_day
    day = towtank.process_day(_protocol(root, "start.toml", zeros=False, zero_at="file_start"),
                              jobs=1, report=False)
    _check(day, truth)
    red = day.reductions[5]
    assert red.windows["still_pre"] is None
    assert any(n.startswith("the file starts in motion: the drag and lift zero is the still "
                            "window after the stop") for n in red.notes), red.notes


def test_the_phases_of_a_run_in_motion_start_with_the_acceleration_or_the_plateau():
    frame, truth = syn.simulate_run("hull", 0.0, 1.2, 0.5, fs=200.0, rng=4)
    fs = 200.0
    for cut, first in ((truth["t_accel_start"], "accel"),
                       (truth["t_plateau_start"] + 0.5, "steady")):
        part = frame[frame["time"] >= cut]
        t = part["time"].to_numpy() - cut
        u = lowpass(part["speed"].to_numpy(), fs, 4.0)
        a = np.gradient(u, 1 / fs)
        with pytest.raises(RunError, match="no still window before the carriage moves"):
            detect_phases(t, u, a, fs)
        ph = detect_phases(t, u, a, fs, still_required=False)
        assert ph.still_pre is None and ph.steady is not None
        starts = {k: getattr(ph, k)[0] for k in ("accel", "steady") if getattr(ph, k)}
        assert min(starts, key=starts.get) == first
        if first == "steady":
            assert ph.accel is None


def test_a_run_in_motion_at_both_ends_without_a_zeros_file_is_rejected():
    from towtank.ingest.protocol import Processing
    from towtank.ingest.runfile import RawRun
    from towtank.reduce.run import reduce_run

    frame, truth = syn.simulate_run("hull", 0.0, 1.2, 0.5, fs=200.0, rng=4)
    part = frame[(frame["time"] >= truth["t_accel_start"])
                 & (frame["time"] <= truth["t_decel_start"] + 0.5)]
    raw = RawRun(time=part["time"].to_numpy(), speed=part["speed"].to_numpy(),
                 drag=part["drag"].to_numpy(), lift=part["lift"].to_numpy(), fs=200.0)
    with pytest.raises(RunError, match="the file starts in motion and does not end at rest"):
        reduce_run(raw, Processing(zero_at="file_start"), run=1, file="run_001.csv")
    # with a zeros file it is reduced: the zero held, no drift to remove
    still = frame[frame["time"] < truth["t_accel_start"] - 0.1]
    raw.zero_levels = {"drag": float(still["drag"].mean()), "lift": float(still["lift"].mean())}
    red = reduce_run(raw, Processing(), run=1, file="run_001.csv")
    assert red.windows["still_pre"] is None and red.windows["still_post"] is None
    assert red.drag_mean_raw == pytest.approx(truth["drag_model"], abs=3e-3)


def test_inspect_applies_the_zeros_file_as_process_does(cut_day, tmp_path):
    """inspect with a protocol that has [zeros] reads the run's zeros file ({stem}, and {run}
    from the number in the file's name), so a run that starts in motion is reduced there too."""
    import io

    from towtank.commands.inspect import inspect_run

    root, _ = cut_day
    out, err = io.StringIO(), io.StringIO()
    rc = inspect_run(root / "data" / "run_004.csv", _protocol(root, "z.toml", zeros=True),
                     png=tmp_path / "x.png", out=out, err=err)
    assert rc == 0, err.getvalue()
    text = out.getvalue()
    assert "zeros from the zeros file run_004_zero.csv" in text
    assert "zero (still)      not found" in text
    # without the zeros file, the same run cannot be zeroed before its motion
    rc = inspect_run(root / "data" / "run_004.csv", _protocol(root, "n.toml", zeros=False),
                     png=tmp_path / "y.png", out=io.StringIO(), err=err)
    assert rc == 1 and "no still window before the carriage moves" in err.getvalue()
