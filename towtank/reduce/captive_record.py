"""A captive run's channels as the day reduces them (docs/formats.md, "Captive manoeuvring tests").

The run has been reduced as any run first (:func:`towtank.reduce.run.reduce_read`: its phases,
steady window and the zero of its drag channel); this module conditions its captive channels the
same way and hands them to :func:`towtank.reduce.captive.reduce_captive`:

* speed, sway and yaw low-passed by the day's one zero-phase filter ([processing] cutoff_hz);
* the forces fx, fy [N] and the moment mz [N m] (or a drift run's drag and lift) zeroed as the
  drag is: the mean of the still window before the carriage moves, with the linear drift to the
  still window after it stops ([processing] drift), and the same drift check; not filtered
  (the steady means and the PMM harmonics are their filters);
* the PMM's sway [m] and yaw [deg → rad] are positions, not loads: filtered, never zeroed.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from towtank.errors import RunError
from towtank.ingest.protocol_types import Captive, Processing, Protocol
from towtank.ingest.runfile import RawRun
from towtank.reduce.captive import (
    PMM_TESTS,
    CaptiveRun,
    CycleVerdict,
    condition_captive,
    cycle_verdicts,
    reduce_captive,
)

__all__ = ["CAPTIVE_LOADS", "captive_channels", "pmm_cycle_verdicts", "reduce_captive_record"]

#: The balance's load channels of a captive run, and the drag/lift pair a drift run may have.
CAPTIVE_LOADS = ("fx", "fy", "mz")
#: A PMM frequency closer than this factor to the low-pass cut-off loses its third harmonic.
PMM_CUTOFF_FACTOR = 3.0


def _index_window(t: np.ndarray, window: tuple[float, float] | None) -> tuple[int, int] | None:
    """The index range [i0, i1) of a window given in seconds (as ``RunReduction.windows``)."""
    if window is None:
        return None
    i0 = int(np.searchsorted(t, window[0], side="left"))
    i1 = int(np.searchsorted(t, window[1], side="right"))
    return (i0, i1) if i1 - i0 >= 1 else None


Windows = dict[str, tuple[float, float] | None]


def captive_channels(raw: RawRun, windows: Windows, p: Processing, said: list[str],
                     zero_var: dict[str, float] | None = None) -> dict[str, np.ndarray]:
    """The captive channels of ``raw`` filtered and (the loads) zeroed with the windows [s]
    the run's reduction found (``RunReduction.windows``;
    :func:`towtank.reduce.captive.condition_captive`): ``t`` [s], ``U`` [m/s], ``fx``, ``fy``
    [N], ``mz`` [N m] (or a drift run's ``drag``, ``lift`` [N] in carriage axes), ``sway``
    [m], ``yaw`` [deg]. A large drift's sentence is appended to ``said``; a balance that had
    not settled raises RunError. ``zero_var`` receives the variance of each balance channel's
    zero at the steady window."""
    t = raw.time
    extra = dict(raw.extra)
    loads = {k: extra[k] for k in CAPTIVE_LOADS if k in extra}
    if "fy" not in loads and raw.lift is not None:
        loads = {"drag": raw.drag, "lift": raw.lift, **({"mz": extra["mz"]} if "mz" in extra
                                                          else {})}
    if "fy" not in loads and "lift" not in loads:
        raise RunError("a captive run needs the balance's side force fy (or a drift run's "
                       "lift) and its yaw moment mz; the file has neither fy nor lift")
    if "mz" not in loads:
        raise RunError("a captive run needs the balance's yaw moment mz; the file has none")
    positions: dict[str, np.ndarray] = {k: extra[k] for k in ("sway", "yaw") if k in extra}
    pre = _index_window(t, windows.get("still_pre"))
    post = _index_window(t, windows.get("still_post")) if p.drift == "linear" else None
    steady = _index_window(t, windows.get("steady"))
    if pre is None:
        raise RunError("a captive run needs the still window before the carriage moves for "
                       "the zero of its balance channels")
    return condition_captive(t, {"U": raw.speed, **loads, **positions}, raw.fs,
                             cutoff_hz=p.cutoff_hz, order=p.filter_order, still=(pre, post),
                             steady=steady, said=said, zero_var=zero_var)


def reduce_captive_record(protocol: Protocol, raw: RawRun, windows: Windows, row: dict[str, Any],
                          *, run: int, file: str
                          ) -> tuple[dict[str, np.ndarray], tuple[str, ...], tuple[str, ...]]:
    """The captive reduction of a run whose reduction found the phase ``windows`` [s]: the
    arrays of :meth:`towtank.reduce.captive.CaptiveRun.to_arrays` (``RunReduction.captive``),
    its notes and its warnings (a large balance drift).

    ``row`` is the run sheet's row (test, plane, drift_deg, rudder_deg, radius_m,
    pmm_amplitude_m, pmm_frequency_hz). Raises RunError with one sentence for a run that
    cannot give captive loads."""
    model = protocol.model
    if model is None:
        raise RunError("a captive run needs the protocol's [model] (mass_kg, izz_kg_m2, xg_m, "
                       "balance_x_m)")
    p = protocol.processing
    warnings: list[str] = []
    freq = float(row.get("pmm_frequency_hz", math.nan))
    if math.isfinite(freq) and p.cutoff_hz < PMM_CUTOFF_FACTOR * freq:
        raise RunError(
            f"the low-pass cut-off [processing] cutoff_hz = {p.cutoff_hz:g} Hz is less than "
            f"{PMM_CUTOFF_FACTOR:g} times the PMM frequency {freq:g} Hz, so it would cut the "
            "loads' harmonics; raise cutoff_hz")
    zero_var: dict[str, float] = {}
    chans = captive_channels(raw, windows, p, warnings, zero_var)
    steady = _index_window(raw.time, windows.get("steady"))
    assert steady is not None
    options = protocol.captive or Captive()
    cr: CaptiveRun = reduce_captive(chans, raw.fs, steady, row, model,
                                    run=run, file=file,
                                    min_cycles=options.min_cycles,
                                    amplitude_tolerance=options.amplitude_tolerance,
                                    zero_var=zero_var, moment_ref=options.moment_ref)
    return cr.to_arrays(), (*warnings, *cr.notes), tuple(warnings)


def pmm_cycle_verdicts(protocol: Protocol, raw: RawRun, windows: Windows, row: dict[str, Any]
                       ) -> list[CycleVerdict]:
    """Every cycle of a PMM run's recorded sway, kept or dropped with its reason, as
    :func:`reduce_captive_record` chooses them (:func:`towtank.reduce.captive.cycle_verdicts`
    on the same filtered channel and steady window); empty for a static run, a run without
    sway or steady window. Raises RunError as :func:`captive_channels` does."""
    test = str(row.get("test", "")).strip().lower()
    steady = _index_window(raw.time, windows.get("steady"))
    if test not in PMM_TESTS or "sway" not in raw.extra or steady is None:
        return []
    chans = captive_channels(raw, windows, protocol.processing, [])
    options = protocol.captive or Captive()
    return cycle_verdicts(chans["t"], chans["sway"], steady,
                          tolerance=options.amplitude_tolerance)
