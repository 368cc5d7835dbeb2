"""The vehicle outputs of a processed day: predicted.csv, model.json and the figure of measured
beside predicted primes (docs/formats.md, section 6)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from towtank.vehicle.model import write_model


def write_vehicle(day: Any, folder: Path, figure: bool = True) -> None:
    """Write predicted.csv and model.json of ``day.vehicle`` into ``folder``, and with
    ``figure`` (and the protocol's [report] figures) figures/predicted_vs_measured.png."""
    folder = Path(folder)
    day.vehicle.predicted.to_csv(folder / "predicted.csv", index=False, float_format="%.6g")
    write_model(day.vehicle.model, folder / "model.json")
    report = getattr(day.protocol, "report", None)
    if figure and getattr(report, "figures", True) and "predicted" in day.coefficients:
        fig = predicted_figure(day.coefficients)
        if fig is not None:
            (folder / "figures").mkdir(exist_ok=True)
            fig.savefig(folder / "figures" / "predicted_vs_measured.png", dpi=150,
                        facecolor="white", metadata={"Software": None})


def predicted_figure(coefficients: Any) -> Any:
    """Measured primes with their 95 % intervals beside the predicted ones, each divided by
    |predicted| (the prediction at ±1); None when no coefficient has a prediction."""
    from matplotlib.figure import Figure

    rows = coefficients[[math.isfinite(float(p)) and float(p) != 0
                         for p in coefficients["predicted"]]]
    if rows.empty:
        return None
    fig = Figure(figsize=(6.5, 0.45 * len(rows) + 1.4), layout="constrained")
    ax = fig.add_subplot()
    for i, (_, r) in enumerate(rows.iterrows()):
        scale = abs(float(r["predicted"]))
        lo = float(r.get("prime_ci_low", float("nan")))
        hi = float(r.get("prime_ci_high", float("nan")))
        meas = float(r["prime"]) / scale
        if math.isfinite(lo) and math.isfinite(hi):
            ax.errorbar(meas, i, xerr=[[meas - lo / scale], [hi / scale - meas]], fmt="o",
                        color="C0", capsize=3, label="measured (95 %)" if i == 0 else None)
        else:
            ax.plot(meas, i, "o", color="C0", label="measured" if i == 0 else None)
        ax.plot(float(r["predicted"]) / scale, i, "D", mfc="none", color="C3",
                label="predicted" if i == 0 else None)
    ax.set_yticks(range(len(rows)), list(rows["symbol"]))
    ax.invert_yaxis()
    ax.axvline(0.0, color="0.6", lw=0.8)
    ax.set_xlabel("prime / |predicted prime|")
    ax.set_title("Measured beside predicted (docs/method.md, Prediction from geometry)",
                 loc="left", fontsize=9)
    ax.grid(True, axis="x", alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    return fig
