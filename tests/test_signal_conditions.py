"""Real signals: mains hum, low sample rates, 4× noise, long runs, a wake on the balance after
the stop, a zero at the file's start. One run at a time through reduce_run, against the
generator's truth (towtank.testing)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

import towtank.testing.synthetic as syn
from towtank.errors import RunError
from towtank.ingest.protocol import Processing
from towtank.ingest.runfile import RawRun
from towtank.reduce.run import reduce_run
from towtank.signal.conditioning import lowpass
from towtank.signal.drift import drift_verdict
from towtank.signal.phases import detect_phases, sustained_peak


def _reduce(frame, fs, **proc):
    raw = RawRun(time=frame["time"].to_numpy(), speed=frame["speed"].to_numpy(),
                 drag=frame["drag"].to_numpy(), lift=frame["lift"].to_numpy(), fs=fs)
    return reduce_run(raw, Processing(**proc), run=1, file="run_001.csv")


def _run(angle, speed, accel, *, fs=200.0, seed=1, noise=None, **kw):
    return syn.simulate_run("hull", angle, speed, accel, fs=fs, rng=seed, noise=noise, **kw)


# ------------------------------------------------------------------------------ hum, zero
def test_zero_from_the_filtered_force_ignores_mains_hum():
    """0.05 N of 50 Hz hum at 200 Hz: the raw mean of a 2 s still window that is not a whole
    number of hum periods moves the zero by up to ~0.3 mN; the filtered zero does not."""
    hum = dataclasses.replace(syn.Noise.quiet(), hum_amplitude=0.05)
    errors = []
    for seed in range(6):
        frame, truth = _run(10.0, 0.8, 0.5, fs=200.0, seed=seed, noise=hum)
        red = _reduce(frame, 200.0)
        errors.append(red.drag_mean_raw - truth["drag_model"])
    assert np.max(np.abs(errors)) < 2e-5  # [N]: 0.02 mN


# ------------------------------------------------------------- acceleration at low rates
@pytest.mark.parametrize("fs, factor", [(100.0, 1.0), (50.0, 1.0), (200.0, 4.0), (50.0, 4.0)])
def test_transverse_acceleration_found_at_low_rates_and_with_4x_noise(fs, factor):
    """The 0.1 m/s² transverse ramp to 0.3 m/s (3 s of constant acceleration) is found at 50–
    100 Hz and with 4× the speed and balance noise, and its level is within 3 %."""
    base = syn.Noise()
    noise = dataclasses.replace(base, speed_sigma=factor * base.speed_sigma,
                                balance_sigma=factor * base.balance_sigma)
    for seed in range(5):
        frame, truth = _run(90.0, 0.3, 0.1, fs=fs, seed=seed, noise=noise)
        red = _reduce(frame, fs)
        assert red.windows["accel"] is not None, (fs, factor, seed)
        assert red.accel_mean == pytest.approx(0.1, rel=0.03)


# --------------------------------------------------------------------------- long runs
def test_a_long_run_keeps_its_still_window_and_ramps():
    """A 1200 s plateau (ramps well under 0.5 % of the file): the still window, the
    acceleration and the steady mean are found as in a short run."""
    frame, truth = _run(90.0, 0.3, 0.1, fs=50.0, seed=2, plateau_s=1200.0,
                        tank_length_m=400.0)
    assert truth["duration_s"] > 1200
    red = _reduce(frame, 50.0)
    assert red.windows["still_pre"][1] < truth["t_accel_start"]
    assert red.windows["accel"] is not None
    assert red.speed_mean == pytest.approx(0.3, rel=1e-3)
    assert red.drag_mean_raw == pytest.approx(truth["drag_model"], abs=5e-4)


def test_sustained_peak_does_not_depend_on_the_length():
    x = np.zeros(1_000_000)
    x[1000:1100] = 1.0  # 100 samples at the peak in a million
    assert sustained_peak(x, 50) == 1.0
    assert sustained_peak(x, 200) == 0.0


# ------------------------------------------------------------------ drift, wake, zero_at
def test_linear_drift_is_removed_and_a_wake_is_not():
    t = np.linspace(0.0, 20.0, 4001)
    pre, post = (100, 500), (3400, 4000)
    drift = 0.02 * t / 20.0  # 20 mN of straight drift: settled, removed (with a warning)
    v = drift_verdict(t, drift, pre, post, steady_force=0.1)
    assert v.settled and v.reject is None and "drift" in v.warning
    wake = np.where(t > 15.0, 0.1 * np.exp(-(t - 15.0) / 3.0), 0.0)  # the signal's size
    v = drift_verdict(t, wake, pre, post, steady_force=0.1)
    assert not v.settled and "the balance had not settled after the stop" in v.reject


@pytest.mark.parametrize("wake", [0.1, 0.5])
def test_wake_on_the_balance_is_never_applied_silently(wake):
    """A wake of 10 % or 50 % of the plateau drag still on the balance after the stop: the run
    is rejected ("the balance had not settled after the stop") or warned, never its drift
    subtracted silently."""
    noise = dataclasses.replace(syn.Noise(), wake=wake)
    for seed in range(4):
        frame, truth = _run(0.0, 1.2, 0.5, seed=seed, noise=noise)
        try:
            red = _reduce(frame, 200.0)
        except RunError as exc:
            assert "the balance had not settled after the stop" in exc.reason
            continue
        assert any("settled" in w or "drift" in w for w in red.warnings), red.warnings
        # drift = "none": the pre-run zero only, the wake left out of the steady mean
        red = _reduce(frame, 200.0, drift="none")
        assert red.drag_mean_raw == pytest.approx(truth["drag_model"], rel=0.01)


def test_zero_at_file_start():
    """zero_at = "file_start": the zero window is the start of the file, not the still water
    just before the carriage moves (a model active in still water), one trim (0.375 s at 4 Hz)
    after the file's first sample, clear of the filter's start-up."""
    frame, truth = _run(0.0, 1.2, 0.5, seed=4)
    t = frame["time"].to_numpy()
    fs = 200.0
    u = lowpass(frame["speed"].to_numpy(), fs, 4.0)
    a = np.gradient(u, 1 / fs)
    ph = detect_phases(t, u, a, fs, zero_window_s=1.0, zero_at="file_start")
    assert ph.still_pre == (75, 275)
    ph = detect_phases(t, u, a, fs, zero_window_s=1.0)
    assert ph.still_pre[0] > 200
    red = _reduce(frame, fs, zero_at="file_start", zero_window_s=1.0)
    assert red.windows["still_pre"][0] == pytest.approx(0.375)
    assert red.drag_mean_raw == pytest.approx(truth["drag_model"], abs=1e-3)
    assert math.isfinite(red.drift_drag)
