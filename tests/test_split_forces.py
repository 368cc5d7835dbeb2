"""A force measured by several load cells (issue 23 item 1): `towtank inspect` proposes the cells
of one force as `columns = [...]` (never half the drag), and `process` names, in one warning per
run, a channel that looks like a force (or a cell of one) that no [channels] entry uses.

Synthetic: the generator's "two-cell" layout (DragL (V) + DragR (V), the left cell carrying
60 % ± 10 %). Real: the UNH-RVAT tow-tank run (LabVIEW TDMS, DragL and DragR in N, no speed
channel) from ../shared/real when it is present; skipped, saying so, when it is not.
"""

from __future__ import annotations

import io
import tomllib
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest

import towtank
from towtank.commands.inspect import inspect_run
from towtank.ingest.describe import force_parts, unmapped_forces
from towtank.ingest.protocol import read_and_channels
from towtank.reduce.run import unmapped_force_warnings
from towtank.testing import synthetic as syn
from towtank.testing.layouts import layout_channels, protocol_sections

REAL = Path(__file__).resolve().parents[2] / "shared" / "real"
UNH = REAL / "unh_rvat_2013" / "test.tdms"


@pytest.mark.parametrize("names, parts", [
    (["DragL", "DragR", "TorqueTrans", "TorqueArm"], {"drag": ["DragL", "DragR"]}),
    (["Time (s)", "DragL (V)", "DragR (V)"], {"drag": ["DragL (V)", "DragR (V)"]}),
    (["Fx1", "Fx2", "Fy"], {"drag": ["Fx1", "Fx2"]}),
    (["Fx_left", "Fx_right", "Fy_left", "Fy_right"],
     {"drag": ["Fx_left", "Fx_right"], "lift": ["Fy_left", "Fy_right"]}),
    (["Drag port [N]", "Drag stbd [N]"], {"drag": ["Drag port [N]", "Drag stbd [N]"]}),
    (["Drag_a", "Drag_b", "speed"], {"drag": ["Drag_a", "Drag_b"]}),
    (["LeftDrag", "RightDrag"], {"drag": ["LeftDrag", "RightDrag"]}),
    (["Fx1", "Fx2", "Fx3", "Fx4"], {"drag": ["Fx1", "Fx2", "Fx3", "Fx4"]}),
    # not parts of one force
    (["Fx load cell (V)", "Fy load cell (V)"], {}),
    (["Lift", "Rift"], {}),
    (["TorqueL", "TorqueR"], {}),  # a pair, but not a force
    (["Fx_a", "Fx2"], {}),  # two families
    (["Fx", "Fy", "Fz"], {}),
])
def test_the_cells_of_one_force_are_recognised(names, parts):
    assert force_parts(names) == parts


def test_a_drag_cell_left_out_is_named():
    cols = ("DragL", "Untitled/DragL", "DragR", "Untitled/DragR", "TorqueArm")
    assert unmapped_forces(cols, {"DragL"}) == ["DragR"]
    assert unmapped_forces(cols, {"DragL", "DragR"}) == []
    assert unmapped_forces(("Fx", "Fy", "Fz", "Mx"), {"Fx", "Fy"}) == []  # no cell, no drag


def _two_cell_day(root: Path) -> Path:
    syn.make_hull_day(root, seed=7, file_format="two-cell", sheet_format="csv",
                      channel_style="lab")
    channels = layout_channels("two-cell", syn.LabChannels())
    sections = syn.hull_protocol_sections(".", "out", sheet_format="csv", channels=channels,
                                          channel_style="lab")
    return syn.write_protocol(root / "protocol.toml", **protocol_sections("two-cell", sections))


@pytest.mark.heavy
def test_inspect_proposes_both_cells_and_process_warns_of_a_cell_left_out(tmp_path):
    protocol = _two_cell_day(tmp_path)
    run = tmp_path / "data" / "run_021.csv"
    out, err = io.StringIO(), io.StringIO()
    assert inspect_run(run, png=tmp_path / "x.png", out=out, err=err) == 0, err.getvalue()
    text = out.getvalue()
    block = text[text.index("[read]"):text.index("reduced with the block above")]
    read, channels = read_and_channels(tomllib.loads(block), "block")
    assert channels["drag"].columns == ("DragL (V)", "DragR (V)")
    # following the proposal gives the sum of the cells (at the provisional gain 1 N per V)
    raw = towtank.read_run(run, protocol)  # the day's protocol: gain 20 on the sum
    frame = pd.read_csv(run)
    np.testing.assert_allclose(raw.drag, 20.0 * (frame["DragL (V)"] + frame["DragR (V)"]),
                               atol=1e-6)
    from towtank.ingest.runfile import load_run

    proposed = load_run(run, channels, options=read)
    np.testing.assert_allclose(proposed.drag, frame["DragL (V)"] + frame["DragR (V)"],
                               atol=1e-9)
    # the day with both cells: no warning about a channel left out
    day = towtank.process_day(protocol, jobs=1, report=False)
    assert not [w for w in map(str, day.warnings) if "no [channels] entry uses it" in w]
    # only the left cell mapped: said once for the day, naming the channel, how many runs and
    # the first and last file (not once per run)
    half = protocol_sections("two-cell", syn.hull_protocol_sections(
        ".", "out", sheet_format="csv", channels=layout_channels("two-cell", syn.LabChannels()),
        channel_style="lab"))
    half["channels"]["drag"] = {"column": "DragL (V)", "gain": 20.0}
    one = syn.write_protocol(tmp_path / "half.toml", **half)
    day = towtank.process_day(one, jobs=1, report=False)
    said = [w for w in map(str, day.warnings) if "no [channels] entry uses it" in w]
    n = len(day.reductions)
    assert n > 3 and len(said) == 1, said[:3]
    first, last = min(day.reductions), max(day.reductions)
    assert said[0].startswith(
        f"{n} runs ({day.reductions[first].file} … {day.reductions[last].file}; runs ")
    assert "the channel 'DragR (V)' looks like a force" in said[0]
    assert 'columns = ["DragL (V)", "DragR (V)"]' in said[0]
    assert "run_021.csv" not in said[0].split(";")[1]  # no one run's file in the sentence
    from towtank.report.quality import quality_flow

    items = [text for _, text in quality_flow(day).items]
    assert [t for t in items if "'DragR (V)' looks like a force" in t] == said  # once
    # runs.csv keeps each run's own note
    assert all("'DragR (V)' looks like a force" in " ".join(r.notes)
               for r in day.reductions.values())


def test_per_run_warnings_are_grouped_only_when_shared():
    from towtank.analysis.daywide import group_run_warnings

    same = [(r, f"run_{r:03d}.lvm", f"run_{r:03d}.lvm: the channel 'Fx2' is in no force")
            for r in (1, 2, 3, 5)]
    other = [(4, "run_004.lvm", "run_004.lvm: the channel 'Fy2' is in no force")]
    lines = group_run_warnings(same + other)
    assert lines == [
        "4 runs (run_001.lvm … run_005.lvm; runs 1–3, 5): the channel 'Fx2' is in no "
        "force.",
        "run 4: run_004.lvm: the channel 'Fy2' is in no force.",
    ]
    # two runs alike are still said run by run
    assert len(group_run_warnings(same[:2])) == 2


@pytest.mark.skipif(not UNH.exists(), reason="../shared/real/unh_rvat_2013/test.tdms is not "
                    "present (real recordings are not kept in the repository)")
def test_unh_rvat_inspect_proposes_dragl_plus_dragr(tmp_path):
    """UNH-RVAT 2013 (petebachant/pyTDMS test/test.tdms): inspect proposes drag = DragL + DragR;
    read with that proposal, each cell zeroed on its first second, the mean over the lab's
    window 13–29.89 s is the lab's 601.4 N (± 0.1 %), where DragL alone was 288.6 N."""
    from towtank.ingest.readers import stated_units
    from towtank.ingest.runfile import calibrate, channel_map, map_channels, read_columns

    out, err = io.StringIO(), io.StringIO()
    inspect_run(UNH, png=tmp_path / "x.png", out=out, err=err)
    text = out.getvalue()
    assert 'drag = { columns = ["DragL", "DragR"] }' in text
    assert "'DragR'" not in text.split("# not recognised:")[1]
    block = text[text.index("[read]"):]
    read, channels = read_and_channels(tomllib.loads(block), "block")
    cols, _ = read_columns(UNH, UNH.read_bytes(), read)
    used: dict[str, str] = {}
    chans = map_channels(cols, channels, UNH.name, used=used,
                         external=("time", "speed", "accel"))
    drag = calibrate({"drag": np.asarray(chans["drag"], dtype=float)}, channel_map(channels),
                     used, stated_units(cols), UNH.name, [])["drag"]
    fs = 2000.0
    t = np.arange(drag.size) / fs
    cells = [np.asarray(cols[c], dtype=float) for c in ("DragL", "DragR")]
    np.testing.assert_allclose(drag, cells[0] + cells[1], rtol=0, atol=1e-9)
    window = (t >= 13.0) & (t <= 29.89)
    mean = float(np.mean(drag[window] - np.mean(drag[: int(fs)])))
    assert mean == pytest.approx(601.4, rel=1e-3)
    # and process names the cell a protocol leaves out
    proto = SimpleNamespace(channels={"drag": channels["drag"].__class__(column="DragL")},
                            balance=None)
    said = unmapped_force_warnings(proto, tuple(cols), UNH.name)
    assert len(said) == 1 and "'DragR'" in said[0] and "test.tdms" in said[0]
