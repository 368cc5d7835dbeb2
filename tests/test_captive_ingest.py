"""Captive manoeuvring tests, ingest (issue 35): the protocol's [model] and [captive] keys, the
run sheet's captive columns, the run files' balance and PMM channels, the lab's table of
static means, and a ship's [model] given by its frontal area (no diameter)."""

from __future__ import annotations

import math
from pathlib import Path

import pandas as pd
from conftest import JOBS

from towtank.commands import cli
from towtank.testing import synthetic as syn

# ------------------------------------------------------------------ a ship: no diameter_m
SHIP_PLAN = [
    syn.RunSpec("sting", 0.0, 1.0, 0.5), syn.RunSpec("sting", 0.0, 1.4, 0.5),
    syn.RunSpec("sting", 90.0, 0.6, 0.5), syn.RunSpec("sting", 90.0, 0.9, 0.5),
    syn.RunSpec("hull", 0.0, 1.0, 0.5), syn.RunSpec("hull", 0.0, 1.4, 0.5),
    syn.RunSpec("hull", 10.0, 1.0, 0.5), syn.RunSpec("hull", 10.0, 1.4, 0.5),
    syn.RunSpec("hull", 90.0, 0.6, 0.5), syn.RunSpec("hull", 90.0, 0.9, 0.5),
]


def _ship_day(day: Path) -> Path:
    """A generated hull day whose [model] gives frontal_area_m2 and no diameter, no lateral
    area and no Myring description (as a ship's would)."""
    syn.make_hull_day(day, seed=5, sheet_format="csv", channel_style="canonical",
                      runs=SHIP_PLAN)
    sections = syn.hull_protocol_sections(".", "out", sheet_format="csv",
                                          channel_style="canonical")
    model = sections["model"]
    for key in ("diameter_m", "myring", "lateral_area_m2"):
        model.pop(key)
    model["frontal_area_m2"] = math.pi * 0.05**2 / 4.0
    return syn.write_protocol(day / "p.toml", **sections)


def test_frontal_area_without_diameter_processes_the_day(tmp_path, capsys):
    protocol = _ship_day(tmp_path)
    out = tmp_path / "out"
    code = cli.main(["process", str(protocol), "--out", str(out), "--jobs", str(JOBS)])
    said = capsys.readouterr()
    err = said.err + said.out
    assert code == 0, err
    assert "internal error" not in err
    coef = pd.read_csv(out / "coefficients.csv").set_index("symbol")
    assert math.isfinite(coef.loc["Y_v|v|", "value"])  # the area cancels in it
    assert math.isfinite(coef.loc["X_u|u|", "value"])
    runs = pd.read_csv(out / "runs.csv")
    assert runs.loc[runs["config"] == "hull", "cd_lateral"].isna().all()
    assert (out / "report.pdf").is_file()
    assert "lateral_area_m2 nor diameter_m" in err
