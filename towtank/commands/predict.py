"""``towtank predict``: the coefficients of the protocol's [vehicle] predicted from geometry."""

from __future__ import annotations

import sys
from pathlib import Path

import pandas as pd

from towtank.commands.storage import write_outputs_or_stop
from towtank.errors import ProtocolError
from towtank.ingest.protocol import load_protocol
from towtank.vehicle import model as vmodel
from towtank.vehicle.assumptions import guessed_line
from towtank.vehicle.stage import predict_vehicle

#: The files ``predict`` always writes.
PREDICT_OUTPUTS = frozenset({"predicted.csv", "model.json"})
#: The files it writes when the protocol has the section: powering.csv ([vehicle.propeller]),
#: pressure_hull.csv ([vehicle.pressure_hull]).
DESIGN_OUTPUTS = {"powering": "powering.csv", "pressure_hull": "pressure_hull.csv"}


def predict_command(protocol_path: Path, out: Path | None = None) -> int:
    """Write predicted.csv and model.json for the protocol's [vehicle]; print the table.

    The protocol needs [water] and [vehicle] (its [campaign] may leave out the run sheet and
    the data folder). Output folder: ``--out``, else the protocol's output folder.
    """
    protocol = load_protocol(protocol_path, check_paths=False, require_runs=False)
    if protocol.vehicle is None:
        raise ProtocolError(f"{protocol.path.name}: prediction needs a [vehicle] section.")
    try:
        result = predict_vehicle(protocol)
    except ValueError as exc:  # a bad hull table or hull description
        raise ProtocolError(f"{protocol.path.name}: {exc}") from None
    folder = Path(out) if out is not None else protocol.campaign.output_dir

    extra = {name: getattr(result, attr) for attr, name in DESIGN_OUTPUTS.items()
             if getattr(result, attr) is not None}

    def write(tmp: Path) -> None:
        result.predicted.to_csv(tmp / "predicted.csv", index=False, float_format="%.6g")
        vmodel.write_model(result.model, tmp / "model.json")
        for name, table in extra.items():
            table.to_csv(tmp / name, index=False, float_format="%.6g")

    write_outputs_or_stop(folder, PREDICT_OUTPUTS | frozenset(extra), write)
    with pd.option_context("display.max_rows", None, "display.width", 120,
                           "display.max_colwidth", 60):
        print(result.predicted[["symbol", "value", "unit", "prime"]].to_string(index=False))
    p = result.profile
    print(f"\nhull {p.name}: L = {p.length:.4g} m, D = {p.max_diameter:.4g} m, "
          f"V = {p.volume:.4g} m^3, S_w = {p.wetted_area:.4g} m^2; rho = {result.rho:.2f} kg/m^3")
    for name, table in extra.items():
        print(f"\n{name}:\n{table.to_string(index=False)}")
    line = guessed_line(result.model.get("assumptions"))
    if line:
        print(line)
    for warning in result.warnings:
        print(f"warning: {warning}", file=sys.stderr)
    names = ["predicted.csv", "model.json", *extra]
    print("wrote " + ", ".join(str(folder / n) for n in names))
    return 0
