"""Mains hum leaves no bias (issue 23 item 10): 0.05 N of 50 Hz hum on the forces and
0.005 m/s on the speed, a zero-mean disturbance, must not move any run's zeroed force.

Where it could: the plain mean of a zeros file (``[zeros]``) that is not a whole number of hum
periods long keeps part of a period (up to 0.2 mN), the same for every run sharing the file;
and a still window at the file's start (``zero_at = "file_start"``, or a short still start) sits
in the filter's start-up, where the mirrored padding turns hum into a transient (up to 0.2 mN).
Each test compares the same seeds with and without hum, so that everything but the hum cancels.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from towtank.ingest.protocol import Processing
from towtank.ingest.runfile import RawRun
from towtank.ingest.zerofile import zero_levels
from towtank.pipeline import process_day
from towtank.reduce.run import reduce_run
from towtank.signal.conditioning import still_level
from towtank.testing import synthetic as syn
from towtank.testing.layouts import protocol_sections

HUM_N = 0.05  # [N] on drag and lift
SPEED_HUM = 0.005  # [m/s]
#: Largest change of a zero or a steady force that hum may make [N]: 0.005 mN (a plain window
#: mean lets hum move it by up to 0.2 mN).
BOUND_N = 5e-6


def _hum(**kw) -> syn.Noise:
    return dataclasses.replace(syn.Noise(), hum_amplitude=HUM_N, speed_hum_amplitude=SPEED_HUM,
                               **kw)


def _quiet_hum(**kw) -> syn.Noise:
    return dataclasses.replace(syn.Noise(), hum_amplitude=0.0, **kw)


# ----------------------------------------------------------------------------- generator
def test_the_generator_puts_hum_on_the_speed_without_changing_the_draws():
    frame_h, _ = syn.simulate_run("hull", 0.0, 1.2, 0.5, fs=1000.0, rng=3, noise=_hum())
    frame_0, _ = syn.simulate_run("hull", 0.0, 1.2, 0.5, fs=1000.0, rng=3, noise=_quiet_hum())
    du = frame_h["speed"].to_numpy() - frame_0["speed"].to_numpy()
    # 20 samples a period: the peaks within 1.3 % of the amplitude; the speed quantised (0.1 mm/s)
    assert 0.98 * SPEED_HUM < np.max(np.abs(du)) < SPEED_HUM + 1.01e-4
    assert abs(float(np.mean(du))) < 1e-5
    dd = frame_h["drag"].to_numpy() - frame_0["drag"].to_numpy()
    assert 0.98 * HUM_N < np.max(np.abs(dd)) <= HUM_N * (1 + 1e-12)
    # the difference is a pure 50 Hz sinusoid: every other draw is the same
    t = frame_h["time"].to_numpy()
    basis = np.column_stack([np.sin(2 * np.pi * 50.0 * t), np.cos(2 * np.pi * 50.0 * t)])
    coef = np.linalg.lstsq(basis, dd, rcond=None)[0]
    assert np.max(np.abs(dd - basis @ coef)) < 1e-9


# --------------------------------------------------------------------------- zeros file
@pytest.mark.parametrize("fs", [200.0, 1000.0])
def test_the_zero_of_a_zeros_file_ignores_hum(tmp_path, fs):
    """A zeros file of 1.5 s (plus 0–7 samples: not a whole number of hum periods) or 0.5 s
    holding 0.3 N and 0.05 N of 50 Hz hum at any phase: its zero is 0.3 N within 0.005 mN,
    where the plain mean of the file is off by up to 0.2 mN (0.5 mN over 0.5 s)."""
    plain, errors = [], []
    path = tmp_path / "zero.csv"
    for n in [int(1.5 * fs) + extra for extra in (0, 1, 2, 7)] + [int(0.5 * fs) + 3]:
        t = np.arange(n) / fs
        for phase in np.linspace(0.0, 2.0 * np.pi, 12, endpoint=False):
            hum = HUM_N * np.sin(2.0 * np.pi * 50.0 * t + phase)
            frame = pd.DataFrame({"drag": 0.3 + hum, "lift": -0.1 - hum})
            data = frame.to_csv(index=False).encode()
            path.write_bytes(data)
            levels = zero_levels(path, data, {}, fs=fs, taper_s=Processing().trim)
            errors += [levels["drag"] - 0.3, levels["lift"] + 0.1]
            plain.append(float(np.mean(frame["drag"])) - 0.3)
    assert np.max(np.abs(plain)) > 1e-4  # what the zero was: over 0.1 mN
    assert np.max(np.abs(errors)) < BOUND_N


def test_still_level_is_the_mean_of_a_constant_and_of_a_straight_drift():
    x = np.full(40, 0.25)
    assert still_level(x) == pytest.approx(0.25, abs=1e-12)
    x[5] = np.nan  # a missing sample is interpolated, not a NaN zero
    assert still_level(x, 200.0, 0.05) == pytest.approx(0.25, abs=1e-12)
    drift = 0.1 + 0.003 * np.arange(301) / 300
    for taper_s in (None, 0.0, 0.375, 10.0):
        assert still_level(drift, 200.0, taper_s) == pytest.approx(float(np.mean(drift)),
                                                                  abs=1e-12)


# ----------------------------------------------------------------- still window at the start
def _reduce(frame, fs, **proc):
    raw = RawRun(time=frame["time"].to_numpy(), speed=frame["speed"].to_numpy(),
                 drag=frame["drag"].to_numpy(), lift=frame["lift"].to_numpy(), fs=fs)
    return reduce_run(raw, Processing(**proc), run=1, file="run_001.csv")


@pytest.mark.parametrize("proc, sim", [({"zero_at": "file_start"}, {}),
                                       ({}, {"pre_still_s": 1.5})])
def test_a_zero_at_the_file_start_ignores_hum(proc, sim):
    """The zero window at the file's start (zero_at = "file_start", or a still start of 1.5 s)
    is clear of the filter's start-up: hum moves the zero and the steady drag by less than
    0.005 mN (up to 0.2 mN when the window began at the first sample)."""
    d_zero, d_drag = [], []
    for seed in range(4):
        for angle, speed, accel in ((0.0, 1.2, 0.5), (90.0, 0.3, 0.1)):
            red = {}
            for name, noise in (("hum", _hum()), ("none", _quiet_hum())):
                frame, _ = syn.simulate_run("hull", angle, speed, accel, fs=200.0, rng=seed,
                                            noise=noise, **sim)
                red[name] = _reduce(frame, 200.0, **proc)
            d_zero.append(red["hum"].zero_drag - red["none"].zero_drag)
            d_drag.append(red["hum"].drag_mean_raw - red["none"].drag_mean_raw)
    assert np.max(np.abs(d_zero)) < BOUND_N
    assert np.max(np.abs(d_drag)) < BOUND_N


# -------------------------------------------------------------------------------- a day
SEED = 1


def _shared_zero_day(root: Path, noise: syn.Noise) -> Path:
    """A hull day whose every run takes its zero from one zeros file, 1.49 s at 200 Hz (not a
    whole number of hum periods): the balance at rest before the first run."""
    syn.make_hull_day(root, seed=SEED, file_format="zero-file", sheet_format="csv",
                      channel_style="lab", noise=noise)
    zero = pd.read_csv(root / "data" / "run_001_zero.csv")
    zero.iloc[: len(zero) - 2].to_csv(root / "data" / "still.csv", index=False)
    sections = syn.hull_protocol_sections(".", "out", sheet_format="csv",
                                          channels=syn.LabChannels(), channel_style="lab")
    sections = protocol_sections("zero-file", sections)
    sections["zeros"] = {"file": "still.csv"}
    return syn.write_protocol(root / "protocol.toml", **sections)


@pytest.mark.heavy
def test_hum_leaves_no_bias_on_a_day(tmp_path):
    """The same day (same seed, one zero for the balance, shared by every run) with and
    without hum: the runs' steady drags (before and after the tare) differ by less than
    0.005 mN each, with no common sign, and the coefficients by less than a twentieth of
    their 95 % intervals' half-width. Before, every run moved by up to 0.07 mN the same way
    and Y_v|v| by a tenth of its half-width."""
    days = {}
    for name, noise in (("hum", _hum(zero_offset=0.0)), ("none", _quiet_hum(zero_offset=0.0))):
        days[name] = process_day(_shared_zero_day(tmp_path / name, noise), jobs=1)
    hum, none = days["hum"], days["none"]
    assert not hum.rejected and not none.rejected
    runs = sorted(set(hum.reductions) & set(none.reductions))
    assert len(runs) == len(hum.reductions) == len(none.reductions)
    for key in ("drag_mean_raw", "drag_mean"):
        diff = np.array([getattr(hum.reductions[r], key) - getattr(none.reductions[r], key)
                         for r in runs])
        assert abs(float(np.mean(diff))) < 0.2 * BOUND_N, (key, np.mean(diff))
        assert np.max(np.abs(diff)) < BOUND_N, (key, diff)
        assert 0.2 < float(np.mean(diff > 0)) < 0.8, (key, diff)  # no common sign
    ch = hum.hull.coefficients.set_index("symbol")
    cn = none.hull.coefficients.set_index("symbol")
    for sym in ("X_u|u|", "Y_v|v|", "X_v|v|", "X_udot", "Y_vdot"):
        half = 0.5 * (cn.loc[sym, "ci_high"] - cn.loc[sym, "ci_low"])
        assert abs(ch.loc[sym, "value"] - cn.loc[sym, "value"]) < 0.05 * half, sym
