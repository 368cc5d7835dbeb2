"""manoeuvre.png of ``towtank simulate``: the track of the manoeuvre and its time histories.

One figure, in the report's style (:func:`towtank.report.style.rc`):

- the track, at true scale (equal axes) where its shape allows: the plan view (x north, y east
  = starboard at the start) of a turning circle, zig-zag, spiral or spiralling glide (heading
  turned by more than 90°), the vertical plane (x, depth z down) of a dive or straight glide.
  A compact track (a turning circle) fills the left column; an
  elongated one (a zig-zag, a dive) spans the top row with its long side across, and when it is
  more than :data:`EXAGGERATE_ABOVE` times longer than wide its cross-track scale is stretched
  (said on the axis);
- four panels against time, each quantity on its own axis with its unit: heading ψ (wrapped
  to ±180° when the vehicle turns through more than a full circle) or pitch θ; the controls
  δr and δs; the speeds u and |V|; the depth z.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator, MultipleLocator

import towtank.report.style as style
from towtank.report.figure_base import place_legend, styled
from towtank.vehicle.steady import speed_magnitude

if TYPE_CHECKING:
    import pandas as pd
    from matplotlib.axes import Axes

#: Size of manoeuvre.png [in].
MANOEUVRE_SIZE: tuple[float, float] = (11.0, 8.5)
#: Resolution of manoeuvre.png [dpi].
MANOEUVRE_DPI = 120
#: A track longer than this many times its width is drawn across the top row [-].
ELONGATED_ABOVE = 2.5
#: A track longer than this many times its width has its cross-track scale stretched [-].
EXAGGERATE_ABOVE = 8.0
#: Smallest half-range of the controls' axis [deg], so that a constant deflection shows.
CONTROL_MIN_DEG = 5.0


def wrapped_heading(psi_deg: np.ndarray) -> np.ndarray:
    """Heading wrapped to [−180°, 180°) with NaN where it wraps, so that no line is drawn
    across the axis at the jump.

    Parameters
    ----------
    psi_deg : ndarray
        Heading, continuous (unwrapped) [deg].
    """
    psi = np.asarray(psi_deg, dtype=float)
    w = (psi + 180.0) % 360.0 - 180.0
    jump = np.flatnonzero(np.abs(np.diff(w)) > 180.0)
    return np.insert(w, jump + 1, np.nan)


def _insert_at_wraps(values: np.ndarray, psi_deg: np.ndarray) -> np.ndarray:
    """``values`` with the NaN of :func:`wrapped_heading` inserted at the same places (their
    neighbour's value, so that the times stay increasing)."""
    w = (np.asarray(psi_deg, dtype=float) + 180.0) % 360.0 - 180.0
    jump = np.flatnonzero(np.abs(np.diff(w)) > 180.0)
    return np.insert(np.asarray(values, dtype=float), jump + 1, np.asarray(values)[jump + 1])


def _track_axes(ts: pd.DataFrame, vertical: bool) -> tuple[np.ndarray, np.ndarray, str, str,
                                                            bool]:
    """The track's (horizontal, vertical) data, their labels, and whether the vertical axis
    points down (depth, or starboard when x runs across)."""
    x, y, z = (ts[c].to_numpy(float) for c in ("x_m", "y_m", "z_m"))
    if vertical:
        return x, z, "x (forward, earth axes) [m]", "depth z [m]", True
    if np.ptp(x) >= ELONGATED_ABOVE * max(np.ptp(y), 1e-9):
        # long northward track across: a rotation of the plan, starboard (y) down
        return x, y, "x (north) [m]", "y (east, starboard) [m]", True
    return y, x, "y (east, starboard) [m]", "x (north) [m]", False


def _elongation(h: np.ndarray, v: np.ndarray) -> float:
    """Length over width of the track's bounding box [-]."""
    a, b = float(np.ptp(h)), float(np.ptp(v))
    return max(a, b) / max(min(a, b), 1e-9 * max(a, b, 1e-9))


@styled
def _spirals(ts: pd.DataFrame) -> bool:
    """Whether the heading turned by more than a quarter turn: a glide that spirals is drawn in
    plan view (its radius shows there), a straight one in the vertical plane."""
    psi = np.unwrap(np.radians(ts["psi_deg"].to_numpy(float)))
    return bool(psi.size and np.ptp(psi) > np.pi / 2)


def manoeuvre_figure(ts: pd.DataFrame, manoeuvre: str, name: str = "model") -> Figure:
    """The figure of one simulated manoeuvre (manoeuvre.png).

    Parameters
    ----------
    ts : DataFrame
        manoeuvre.csv's time series: ``t_s`` [s], ``x_m, y_m, z_m`` [m] (earth axes, z down),
        ``theta_deg, psi_deg`` [deg], ``u_m_s, v_m_s, w_m_s`` [m/s], ``rudder_deg,
        sternplane_deg`` [deg].
    manoeuvre : str
        turning, zigzag, spiral, dive or glide.
    name : str
        The vehicle's name (title).

    Returns
    -------
    Figure
        Axes in order: the track, then attitude, controls, speed and depth against time.
    """
    vertical = manoeuvre == "dive" or (manoeuvre == "glide" and not _spirals(ts))
    h, v, hlabel, vlabel, down = _track_axes(ts, vertical)
    ratio = _elongation(h, v)
    elongated = ratio > ELONGATED_ABOVE
    fig = Figure(figsize=MANOEUVRE_SIZE)
    if elongated:
        gs = fig.add_gridspec(3, 2, left=0.07, right=0.98, top=0.9, bottom=0.07, hspace=0.45,
                              wspace=0.22, height_ratios=[1.15, 1.0, 1.0])
        ax_track = fig.add_subplot(gs[0, :])
        slots = [gs[1, 0], gs[1, 1], gs[2, 0], gs[2, 1]]
    else:
        gs = fig.add_gridspec(4, 2, left=0.07, right=0.98, top=0.9, bottom=0.07, hspace=0.3,
                              wspace=0.22, width_ratios=[1.05, 1.0])
        ax_track = fig.add_subplot(gs[:, 0])
        slots = [gs[k, 1] for k in range(4)]
    _draw_track(ax_track, h, v, hlabel, vlabel, down, exaggerated=ratio > EXAGGERATE_ABOVE)
    axes = [fig.add_subplot(slots[0])]
    axes += [fig.add_subplot(s, sharex=axes[0]) for s in slots[1:]]
    t = ts["t_s"].to_numpy(float)
    _attitude(axes[0], ts, t, vertical)
    _controls(axes[1], ts, t)
    _speed(axes[2], ts, t)
    _depth(axes[3], ts, t)
    bottom = axes[2:] if elongated else axes[3:]  # the time axis is shared: labelled below
    for ax in axes:
        ax.set_xlim(float(t[0]), float(t[-1]))
        ax.xaxis.set_major_locator(MaxNLocator(8))
        if ax in bottom:
            ax.set_xlabel(r"time $t$ [s]")
        else:
            ax.tick_params(labelbottom=False)
    u0 = float(speed_magnitude(ts["u_m_s"].iloc[0], ts["v_m_s"].iloc[0], ts["w_m_s"].iloc[0]))
    rudder = float(ts["rudder_deg"].abs().max())
    stern = float(ts["sternplane_deg"].abs().max())
    fig.suptitle(f"{name}: {manoeuvre}, starting at {u0:.2f} m/s; rudder {rudder:g}°, sternplanes "
                 f"{stern:g}°", x=0.07, ha="left", fontsize=11, fontweight="bold")
    return fig


def _draw_track(ax: Axes, h: np.ndarray, v: np.ndarray, hlabel: str, vlabel: str, down: bool,
                *, exaggerated: bool) -> None:
    ax.plot(h, v, color=style.PALETTE[0], lw=1.4)
    ax.plot(h[0], v[0], "o", color="black", ms=6, zorder=4)
    ax.plot(h[-1], v[-1], "s", color=style.PALETTE[1], ms=6, zorder=4)
    ax.annotate("start", (h[0], v[0]), xytext=(6, 6), textcoords="offset points", fontsize=8)
    ax.annotate("end", (h[-1], v[-1]), xytext=(6, 6), textcoords="offset points", fontsize=8,
                color=style.PALETTE[1])
    ax.set_xlabel(hlabel)
    ax.set_ylabel(vlabel + (" (stretched)" if exaggerated else ""))
    for axis in (ax.xaxis, ax.yaxis):
        axis.set_major_locator(MaxNLocator(8, steps=[1, 2, 2.5, 5, 10]))
    if down:
        ax.invert_yaxis()
    if exaggerated:
        ax.set_title("Track (cross-track scale stretched to show the path)")
        span = float(np.ptp(v)) or 1.0
        lo, hi = float(np.min(v)) - 0.15 * span, float(np.max(v)) + 0.15 * span
        ax.set_ylim((hi, lo) if down else (lo, hi))
    else:
        ax.set_title("Track (true scale)")
        ax.set_aspect("equal", adjustable="box")
        hspan, vspan = float(np.ptp(h)) or 1.0, float(np.ptp(v)) or 1.0
        pad = 0.06 * max(hspan, vspan)
        ax.set_xlim(float(np.min(h)) - pad, float(np.max(h)) + pad)
        lo, hi = float(np.min(v)) - pad, float(np.max(v)) + pad
        ax.set_ylim((hi, lo) if down else (lo, hi))


def _attitude(ax: Axes, ts: pd.DataFrame, t: np.ndarray, vertical: bool) -> None:
    if vertical:
        ax.plot(t, ts["theta_deg"], color=style.PALETTE[0])
        ax.set_ylabel(r"pitch $\theta$ [deg]")
        ax.set_title("Pitch (positive nose up)")
        return
    psi = ts["psi_deg"].to_numpy(float)
    if np.ptp(psi) > 360.0:
        ax.plot(_insert_at_wraps(t, psi), wrapped_heading(psi), color=style.PALETTE[0])
        ax.set_ylim(-190, 190)
        ax.yaxis.set_major_locator(MultipleLocator(90))
        turns = (psi[-1] - psi[0]) / 360.0
        ax.set_title(f"Heading, wrapped to ±180° ({abs(turns):.1f} turns to "
                     f"{'starboard' if turns > 0 else 'port'})")
    else:
        ax.plot(t, psi, color=style.PALETTE[0])
        ax.set_title("Heading")
    ax.set_ylabel(r"heading $\psi$ [deg]")


def _controls(ax: Axes, ts: pd.DataFrame, t: np.ndarray) -> None:
    dr = ts["rudder_deg"].to_numpy(float)
    ds = ts["sternplane_deg"].to_numpy(float)
    ax.plot(t, dr, color=style.PALETTE[1], label=r"rudder $\delta_r$")
    ax.plot(t, ds, color=style.PALETTE[2], ls="--", label=r"stern planes $\delta_s$")
    top = max(CONTROL_MIN_DEG, float(np.nanmax(np.abs(np.concatenate([dr, ds])))) * 1.25)
    ax.set_ylim(-top, top)
    ax.axhline(0.0, color="#777777", lw=0.6, zorder=0)
    ax.set_ylabel(r"deflection $\delta$ [deg]")
    ax.set_title("Controls")
    place_legend(ax, fontsize=7.5, ncol=2)


def _speed(ax: Axes, ts: pd.DataFrame, t: np.ndarray) -> None:
    u = ts["u_m_s"].to_numpy(float)
    total = speed_magnitude(u, ts["v_m_s"].to_numpy(float), ts["w_m_s"].to_numpy(float))
    ax.plot(t, total, color=style.PALETTE[0], label=r"speed $|V|$")
    ax.plot(t, u, color=style.PALETTE[4], ls="--", label=r"surge $u$")
    ax.set_ylim(0.0, float(np.nanmax(total)) * 1.1)
    ax.set_ylabel(r"speed [m/s]")
    ax.set_title("Speed")
    place_legend(ax, fontsize=7.5, ncol=2)


def _depth(ax: Axes, ts: pd.DataFrame, t: np.ndarray) -> None:
    z = ts["z_m"].to_numpy(float)
    ax.plot(t, z, color=style.PALETTE[0])
    span = float(np.ptp(z))
    if span < 0.2:  # a level run: a readable range about its depth
        mid = float(np.mean(z))
        ax.set_ylim(mid + 0.1, mid - 0.1)
    else:
        ax.set_ylim(float(np.max(z)) + 0.05 * span, float(np.min(z)) - 0.05 * span)
    ax.set_ylabel(r"depth $z$ [m] (down)")
    ax.set_title("Depth")


def save_manoeuvre_figure(ts: pd.DataFrame, manoeuvre: str, path: Any, name: str) -> None:
    """Draw :func:`manoeuvre_figure` and write it as a PNG to ``path``."""
    fig = manoeuvre_figure(ts, manoeuvre, name)
    fig.savefig(path, dpi=MANOEUVRE_DPI, facecolor="white", metadata={"Software": None})
