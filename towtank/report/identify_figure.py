"""identify.png of ``towtank identify``: each estimate's convergence with its ±2σ band (the
REMUS identification study's Fig. 9) and the measured against the re-simulated states."""

from __future__ import annotations

from typing import Any

import numpy as np

from towtank.vehicle.identify import coefficient_unit
from towtank.vehicle.identify_log import STATE_COLUMNS

#: Width of identify.png [in] and its resolution [dpi].
WIDTH_IN, DPI = 11.0, 110

_LABELS = {"x_m": "x [m]", "y_m": "y [m]", "z_m": "z [m]", "phi_deg": "roll φ [deg]",
           "theta_deg": "pitch θ [deg]", "psi_deg": "heading ψ [deg]", "u_m_s": "u [m/s]",
           "v_m_s": "v [m/s]", "w_m_s": "w [m/s]", "p_deg_s": "p [deg/s]",
           "q_deg_s": "q [deg/s]", "r_deg_s": "r [deg/s]"}


def identify_figure(result: Any, name: str = "model") -> Any:
    """The figure of one identification (:class:`towtank.results.IdentifyResult`)."""
    # loaded on use: `towtank identify` imports this module at start and draws the figure
    # last, so matplotlib is loaded only when the figure is drawn
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure  # loaded on use, as matplotlib above

    k = len(result.symbols)
    meas = result.measured
    states = [c for c in STATE_COLUMNS if meas is not None and meas[c].notna().any()][:6]
    top = k if result.history else 0
    ncol = 3
    nrow = -(-top // ncol) + -(-len(states) // ncol)
    fig = Figure(figsize=(WIDTH_IN, 2.6 * max(nrow, 1) + 0.8))
    grid = fig.add_gridspec(max(nrow, 1), ncol, hspace=0.55, wspace=0.3)
    ok = result.identifiable()
    for j, sym in enumerate(result.symbols if top else []):
        ax = fig.add_subplot(grid[j // ncol, j % ncol])
        t = result.history["t"]
        mean, sd = result.history["mean"][:, j], result.history["sd"][:, j]
        ax.fill_between(t, mean - 2 * sd, mean + 2 * sd, color="tab:blue", alpha=0.2,
                        label="filter ±2σ")
        ax.plot(t, mean, color="tab:blue", lw=1.2, label=f"{result.method.upper()} (filtered)")
        ax.axhline(result.value[j], color="k", lw=1.0, ls="-", label="smoothed")
        if result.check is not None:
            ax.axhline(result.check["value"][j], color="tab:red", lw=1.0, ls="--",
                       label="least squares")
        span = max(10 * float(result.sd[j]), 0.05 * abs(float(result.value[j])), 1e-9)
        if np.isfinite(span):  # zoomed on the answer; where it started is in the title
            ax.set_ylim(result.value[j] - span, result.value[j] + span)
        verdict = "" if ok[j] else " (not identifiable)"
        ax.set_title(f"{sym}{verdict}, from {result.start[j]:.4g}", fontsize=9)
        ax.set_ylabel(coefficient_unit(sym), fontsize=7)
        ax.set_xlabel("t [s]", fontsize=8)
        ax.tick_params(labelsize=7)
        if j == 0:
            ax.legend(fontsize=6, loc="best")
    first = -(-top // ncol)
    for i, col in enumerate(states):
        ax = fig.add_subplot(grid[first + i // ncol, i % ncol])
        ax.plot(meas["t_s"], meas[col], ".", ms=1.5, color="0.55", label="measured")
        if result.resimulated is not None:
            ax.plot(result.resimulated["t_s"], result.resimulated[col], color="tab:red", lw=1.0,
                    label="re-simulated, identified")
        ax.set_ylabel(_LABELS[col], fontsize=8)
        ax.set_xlabel("t [s]", fontsize=8)
        ax.tick_params(labelsize=7)
        if i == 0:
            ax.legend(fontsize=6, loc="best")
    fig.suptitle(f"{name}: {', '.join(result.symbols)} identified ({result.method})",
                 fontsize=10)
    return fig


def save_identify_figure(result: Any, path: Any, name: str) -> None:
    """Draw :func:`identify_figure` and write it as a PNG to ``path``."""
    fig = identify_figure(result, name)
    fig.savefig(path, dpi=DPI)
