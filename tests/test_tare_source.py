"""[tare] source = "table" (a tare measured once, kept as drag against speed) and "none"."""

from __future__ import annotations

import json

import numpy as np
import pytest

import towtank
from towtank.testing import synthetic as syn


@pytest.fixture(scope="session")
def day_dir(tmp_path_factory):
    root = tmp_path_factory.mktemp("tare")
    syn.make_hull_day(root, seed=3, file_format="csv", sheet_format="csv")
    truth = json.loads((root / "truth.json").read_text())
    return root, truth


def _protocol(root, extra: str, mass_kg: float | None = None) -> str:
    sections = syn.hull_protocol_sections(".", "out", sheet_format="csv")
    if mass_kg is not None:
        sections["model"] = {**sections["model"], "mass_kg": mass_kg}
    path = syn.write_protocol(root / "p.toml", **sections)
    path.write_text(path.read_text() + extra)
    return path


@pytest.mark.heavy
def test_a_tare_table_recovers_the_hull(day_dir):
    """A table of the mounting's drag against speed (from the generator's true tare) replaces
    the sting runs; with the mounting's mass weighed into mass_kg (a table holds no tare
    mass, docs/formats.md) every coefficient is recovered as with sting runs."""
    root, truth = day_dir
    tare = truth["tares"]["A"]
    u = np.linspace(0.2, 2.2, 11)
    lines = ["speed_m_s,drag_N,lift_N"] + [
        f"{x},{tare['t2'] * x * x + tare['t1'] * x},{tare['lift_t2'] * x * x + tare['lift_t1'] * x}"
        for x in u]
    (root / "tare.csv").write_text("\n".join(lines) + "\n")
    mass = truth["hull"]["m"] + tare["m_t"]
    p = _protocol(root, '\n[tare]\nsource = "table"\ntable = "tare.csv"\n', mass_kg=mass)
    day = towtank.process_day(p, jobs=1)
    got = day.coefficients.set_index("symbol")["value"]
    for sym, rel in (("X_udot", 0.05), ("Y_vdot", 0.01), ("X_u|u|", 0.01), ("Y_v|v|", 0.01)):
        assert got[sym] == pytest.approx(truth["coefficients"][sym], rel=rel), sym
    sting = day.runs[day.runs["config"] == "sting"]
    assert (sting["status"] == "ok").all()


def test_no_tare_subtracts_nothing_and_says_so(day_dir):
    root, truth = day_dir
    p = _protocol(root, '\n[tare]\nsource = "none"\n')
    day = towtank.process_day(p, jobs=1)
    assert any("no tare is subtracted" in w for w in map(str, day.warnings))
    hull = [r for r in day.reductions.values() if r.tare_group == "" and r.drag_mean_raw]
    assert all(r.drag_mean == r.drag_mean_raw for r in hull)
    got = day.coefficients.set_index("symbol")["value"]
    # the mounting's drag is now in the hull's: X_u|u| is too negative by about t2
    assert got["X_u|u|"] < truth["coefficients"]["X_u|u|"]


@pytest.mark.parametrize("body, message", [
    ('source = "table"\n', "needs 'table'"),
    ('source = "tables"\n', "must be 'sting', 'table' or 'none'"),
    ('source = "table"\ntable = "nope.csv"\n', "cannot be read"),
    ('source = "none"\ntable = "tare.csv"\n', "needs source = \"table\""),
])
def test_bad_tare_sections_stop_the_day(day_dir, body, message):
    root, _ = day_dir
    p = _protocol(root, "\n[tare]\n" + body)
    with pytest.raises(towtank.ProtocolError, match=message):
        towtank.load_protocol(p)


def test_a_bad_tare_table_is_named(day_dir):
    root, _ = day_dir
    (root / "bad.csv").write_text("speed_m_s,drag_N\n1.0,0.1\n0.5,x\n")
    p = _protocol(root, '\n[tare]\nsource = "table"\ntable = "bad.csv"\n')
    with pytest.raises(towtank.ProtocolError, match="bad.csv holds a value that is not a number"):
        towtank.load_protocol(p)
