"""A captive run drawn as what it measured: X, Y [N] and N [N m] against time.

The report's appendix thumbnails, ``watch``'s latest-run plot and ``inspect``'s plot of a
captive run draw from the run's load trace (:func:`towtank.reduce.captive.load_trace`, kept in
``RunReduction.captive``), never from the raw file: the balance forces X, Y in body axes on the
right axis, the moment N about O on the left, the still windows and the steady window shaded
(for a PMM run the kept cycles instead of the steady window), and for a PMM run the sway and
yaw motion in a band along the top, each scaled to its own range (its amplitude written
beside it). The loads are the balance's, zeroed; the model's inertia is not removed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

import towtank.report.style as style
from towtank.reduce.captive import PMM_TESTS, TRACE_COLUMNS
from towtank.report.figure_base import align_zero

if TYPE_CHECKING:
    from matplotlib.axes import Axes

    from towtank.reduce.run import RunReduction

__all__ = ["CAPTIVE_LOADS_LABEL", "CAPTIVE_MOMENT_LABEL", "CaptiveTrace", "captive_legend_handles",
           "captive_thumbnail", "captive_trace"]

#: Axis labels of a captive thumbnail: the moment (left) and the forces (right), with units.
CAPTIVE_MOMENT_LABEL = r"$N$ [N m]"
CAPTIVE_LOADS_LABEL = r"$X$, $Y$ [N]"
MOMENT_COLOR = "#009E73"
SWAY_COLOR = "#555555"
YAW_COLOR = "#CC79A7"
#: The kept PMM cycles' shades, alternating so that each cycle is seen.
CYCLE_SHADES = ("#c7e9c0", "#a1d99b")
#: The motion band of a PMM run: its bottom and height as fractions of the axes.
MOTION_BAND = (0.72, 0.2)
#: The PMM tests that oscillate the heading (their yaw is drawn).
YAW_TESTS = ("yaw", "yaw_drift")


@dataclass(frozen=True)
class CaptiveTrace:
    """What a captive run's plot draws.

    ``trace``: rows of :data:`towtank.reduce.captive.TRACE_COLUMNS` (t [s], X, Y [N], N [N m],
    sway [m], yaw [deg]); ``kept``: the kept PMM cycles as (start, end) [s]; ``test``: the
    run's captive test (a PMM run's motion is drawn: the sway, and a yaw run's yaw);
    ``about``: the point N is taken about (O, or the balance point without a protocol)."""

    trace: np.ndarray
    kept: tuple[tuple[float, float], ...] = ()
    test: str = "drift"
    about: str = "O"

    @property
    def pmm(self) -> bool:
        """The run is a PMM run."""
        return self.test in PMM_TESTS

    @property
    def motion(self) -> tuple[str, ...]:
        """The motion channels its plot draws."""
        return ("sway", "yaw") if self.test in YAW_TESTS else ("sway",) if self.pmm else ()

    def column(self, name: str) -> np.ndarray:
        """One column of the trace by its name in :data:`TRACE_COLUMNS`."""
        return np.asarray(self.trace[:, TRACE_COLUMNS.index(name)], dtype=float)


def captive_trace(reduction: RunReduction) -> CaptiveTrace | None:
    """The plot's data of a reduced captive run (``reduction.captive``), or None for a run that
    is not captive or whose arrays hold no trace."""
    if not reduction.captive:
        return None
    # loaded on use: the captive run's tables load pandas, which a hull run's plot never needs
    from towtank.reduce.captive import CaptiveRun

    try:
        cr = CaptiveRun.from_arrays(reduction.run, reduction.file, reduction.captive)
    except ValueError:
        return None
    if cr.trace is None or cr.trace.shape[0] < 2:
        return None
    kept: tuple[tuple[float, float], ...] = ()
    if cr.test in PMM_TESTS and len(cr.cycles) and cr.frequency_hz > 0:
        starts = cr.cycles["t_start"].to_numpy(dtype=float)
        ends = np.append(starts[1:], starts[-1] + 1.0 / cr.frequency_hz)
        kept = tuple((float(a), float(b)) for a, b in zip(starts, ends, strict=True))
    return CaptiveTrace(cr.trace, kept, cr.test)


def _ylim(values: np.ndarray, *, above: float, below: float) -> tuple[float, float]:
    # loaded on use: figures imports this module's users
    from towtank.report.figures import thumbnail_ylim

    return thumbnail_ylim(values, above=above, below=below)


def _amplitude(x: np.ndarray) -> tuple[float, float]:
    """(middle, half range) of the finite samples of a motion channel."""
    v = x[np.isfinite(x)]
    if v.size == 0:
        return math.nan, math.nan
    lo, hi = float(np.min(v)), float(np.max(v))
    return 0.5 * (lo + hi), 0.5 * (hi - lo)


def _motion_band(ax: Axes, ct: CaptiveTrace, *, linewidth: float, fontsize: float) -> None:
    """The sway and yaw along the top of ``ax``, each scaled to its own range, labelled with
    its amplitude (half its range)."""
    band = ax.inset_axes((0.0, MOTION_BAND[0], 1.0, MOTION_BAND[1]), sharex=ax)
    band.patch.set_visible(False)
    band.set_axis_off()
    band.set_ylim(-1.25, 1.25)
    t = ct.column("t")
    said = []
    for name, color, unit, style_ in (("sway", SWAY_COLOR, " m", "-"),
                                      ("yaw", YAW_COLOR, "°", "--")):
        if name not in ct.motion:
            continue
        x = ct.column(name)
        mid, half = _amplitude(x)
        if not (math.isfinite(half) and half > 0):
            continue
        band.plot(t, (x - mid) / half, color=color, lw=linewidth * 0.8, ls=style_)
        said.append(f"{name} ±{half:.3g}{unit}")
    if said:  # above the band, inside the axes
        ax.text(0.01, 0.99, ", ".join(said), transform=ax.transAxes, ha="left", va="top",
                fontsize=fontsize, color=SWAY_COLOR)


def captive_thumbnail(ax: Axes, twin: Axes, ct: CaptiveTrace,
                      windows: dict[str, tuple[float, float] | None], *,
                      linewidth: float = 1.0, labels: bool = True, fontsize: float = 5.8
                      ) -> None:
    """Draw a captive run: X, Y [N] on ``twin`` (right), N [N m] on ``ax`` (left), the phases
    shaded on ``twin`` (a PMM run's kept cycles instead of its steady window), a PMM run's
    sway and yaw in a band along the top of ``ax``.

    Parameters
    ----------
    ax, twin : Axes
        The thumbnail's axes and its twin (:func:`towtank.report.figures.thumbnail_twin`).
    ct : CaptiveTrace
        The run's trace and kept cycles (:func:`captive_trace`).
    windows : dict
        The run's phase windows [s] (``RunReduction.windows``).
    linewidth : float
        Line width [pt].
    labels : bool
        Axis labels with units.
    fontsize : float
        Size of the motion band's label [pt].
    """
    for name, (color, _label) in style.PHASE_SHADES.items():
        w = windows.get(name)
        if w is None or (name == "steady" and ct.pmm):
            continue
        twin.axvspan(w[0], w[1], color=color, lw=0, zorder=0)
    for k, (a, b) in enumerate(ct.kept):
        twin.axvspan(a, b, color=CYCLE_SHADES[k % 2], lw=0, zorder=0)
    t = ct.column("t")
    x, y, n = ct.column("X"), ct.column("Y"), ct.column("N")
    twin.plot(t, x, color=style.DRAG_COLOR, lw=linewidth * 0.9, zorder=2)
    twin.plot(t, y, color=style.LIFT_COLOR, lw=linewidth * 0.9, zorder=2)
    ax.plot(t, n, color=MOMENT_COLOR, lw=linewidth * 0.9, zorder=3)
    if t.size >= 2:
        ax.set_xlim(float(t[0]), float(t[-1]))
    # a PMM run's loads keep below its motion band
    above = 0.5 if ct.pmm else 0.12
    twin.set_ylim(*_ylim(np.concatenate([x, y]), above=above, below=0.08))
    ax.set_ylim(*_ylim(n, above=above, below=0.08))
    align_zero(ax, twin)
    if ct.pmm:
        _motion_band(ax, ct, linewidth=linewidth, fontsize=fontsize)
    if labels:
        ax.set_xlabel(r"$t$ [s]")
        ax.set_ylabel(f"moment $N$ about {ct.about} [N m]")
        twin.set_ylabel(r"forces $X$, $Y$, body axes [N]")


def captive_legend_handles(pmm: bool = True, yaw: bool = True, *, phases: bool = True
                           ) -> list[Any]:
    """Legend entries of :func:`captive_thumbnail`: the loads, the motion (``pmm``; the yaw
    with ``yaw``), the phase shades (``phases``: not when a resistance run's legend beside
    them gives them) and the kept PMM cycles' shade."""
    handles: list[Any] = [
        Line2D([], [], color=style.DRAG_COLOR, label="$X$ [N] (right)"),
        Line2D([], [], color=style.LIFT_COLOR, label="$Y$ [N] (right)"),
        Line2D([], [], color=MOMENT_COLOR, label="$N$ [N m] (left)"),
    ]
    if pmm:
        handles.append(Line2D([], [], color=SWAY_COLOR, label="sway (top, scaled)"))
    if pmm and yaw:
        handles.append(Line2D([], [], color=YAW_COLOR, ls="--", label="yaw (top, scaled)"))
    shades = style.PHASE_SHADES
    if phases:
        handles += [Patch(color=shades["still_pre"][0], label="zero (still)"),
                    Patch(color=shades["accel"][0], label="acceleration"),
                    Patch(color=shades["steady"][0], label="steady (kept)"),
                    Patch(color=shades["decel"][0], label="deceleration")]
    if pmm:
        handles.append(Patch(color=CYCLE_SHADES[1], label="kept PMM cycles"))
    return handles
