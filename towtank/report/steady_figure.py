"""steady.png of ``towtank steady``: a glider's steady glides and spirals.

Three panels in the report's style: the wings-level glides' speed and glide angle against the
pitch, one line per ballast; the steady spirals' turn radius against the roll, one line per
ballast and pitch (an empty panel saying so when no roll was asked).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from matplotlib.figure import Figure

from towtank.report.figure_base import styled

if TYPE_CHECKING:
    import pandas as pd

#: Size of steady.png [in] and its resolution [dpi].
STEADY_SIZE: tuple[float, float] = (12.0, 4.2)
STEADY_DPI = 110
#: Most lines of the spiral panel (pairs of ballast and pitch, evenly picked) [-].
MAX_SPIRAL_LINES = 8


@styled
def steady_figure(table: pd.DataFrame, name: str) -> Figure:
    """The figure of steady.csv ``table`` (columns of
    :data:`towtank.vehicle.spiral.STEADY_COLUMNS`)."""
    fig = Figure(figsize=STEADY_SIZE, layout="constrained")
    ax_v, ax_g, ax_r = fig.subplots(1, 3)
    ok = table[table["converged"].astype(bool)]
    glides = ok[ok["roll_deg"] == 0.0]
    for ballast, grp in glides.groupby("ballast_cc", sort=True):
        grp = grp.sort_values("pitch_deg")
        label = f"{ballast:g} cc ({grp['net_buoyancy_N'].iloc[0]:+.2f} N)"
        ax_v.plot(grp["pitch_deg"], grp["speed_m_s"], marker="o", ms=3, label=label)
        ax_g.plot(grp["pitch_deg"], grp["glide_angle_deg"], marker="o", ms=3, label=label)
    ax_v.set(xlabel="pitch θ [deg]", ylabel="speed |V| [m/s]", title="Steady glide: speed")
    ax_g.set(xlabel="pitch θ [deg]", ylabel="glide angle γ [deg]",
             title="Steady glide: path angle")
    for ax in (ax_v, ax_g):
        if len(glides):
            ax.legend(title="ballast", fontsize="small")
        else:
            ax.text(0.5, 0.5, "no converged wings-level glide\n(roll 0) in the table",
                    ha="center", va="center", transform=ax.transAxes)
    spirals = ok[ok["roll_deg"] != 0.0]
    if len(spirals):
        groups = list(spirals.groupby(["ballast_cc", "pitch_deg"], sort=True))
        shown = groups if len(groups) <= MAX_SPIRAL_LINES else [
            groups[round(k * (len(groups) - 1) / (MAX_SPIRAL_LINES - 1))]
            for k in range(MAX_SPIRAL_LINES)]
        for (ballast, pitch), grp in shown:
            grp = grp.sort_values("roll_deg")
            line = None
            for side in (grp[grp["roll_deg"] < 0], grp[grp["roll_deg"] > 0]):
                if len(side):  # port and starboard rolls apart: no line through roll 0
                    kw = {"color": line.get_color()} if line is not None else {
                        "label": f"{ballast:g} cc, θ {pitch:g}°"}
                    (line,) = ax_r.plot(side["roll_deg"], side["turn_radius_m"], marker="o",
                                        ms=3, **kw)
        ax_r.legend(fontsize="small")
        if len(shown) < len(groups):
            ax_r.text(0.02, 0.02, f"{len(shown)} of {len(groups)} ballast-pitch pairs",
                      transform=ax_r.transAxes, fontsize="small")
    else:
        ax_r.text(0.5, 0.5, "no steady spiral\n(give --roll-deg)", ha="center", va="center",
                  transform=ax_r.transAxes)
    ax_r.set(xlabel="roll φ [deg]", ylabel="turn radius [m]", title="Steady spiral: radius")
    fig.suptitle(f"{name}: steady states")
    return fig


def save_steady_figure(table: pd.DataFrame, path: Any, name: str) -> None:
    """Draw :func:`steady_figure` and write it as a PNG to ``path``."""
    fig = steady_figure(table, name)
    fig.savefig(path, dpi=STEADY_DPI, facecolor="white", metadata={"Software": None})
