"""The vehicle outputs of a processed day: predicted.csv and model.json (docs/formats.md)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from towtank.vehicle.model import write_model


def write_vehicle(day: Any, folder: Path) -> None:
    """Write predicted.csv and model.json of ``day.vehicle`` into ``folder``."""
    folder = Path(folder)
    day.vehicle.predicted.to_csv(folder / "predicted.csv", index=False, float_format="%.6g")
    write_model(day.vehicle.model, folder / "model.json")
