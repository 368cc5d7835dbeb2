"""Issue 27: the protocol's [watch] section (towtank watch's timings) and the pipeline's
process_sheet, which watch calls on the runs so far."""

from __future__ import annotations

import pandas as pd
import pytest

from towtank.errors import ProtocolError
from towtank.ingest.protocol import load_protocol
from towtank.ingest.runsheet import read_run_sheet
from towtank.testing import synthetic as syn
from towtank.testing.days import RunSpec

PLAN = [RunSpec("sting", 0.0, v, 0.5) for v in (0.8, 1.6)] + [
    RunSpec("hull", 0.0, v, 0.5) for v in (0.8, 1.6)]


def _protocol(tmp_path, watch=None):
    syn.make_hull_day(tmp_path / "day", runs=PLAN, fs=50.0, file_format="csv",
                      sheet_format="csv", seed=2)
    sections = syn.hull_protocol_sections("day", "out", sheet_format="csv")
    if watch is not None:
        sections["watch"] = watch
    return syn.write_protocol(tmp_path / "p.toml", **sections)


def test_watch_defaults_and_values(tmp_path):
    p = load_protocol(_protocol(tmp_path))
    assert (p.watch.settle_s, p.watch.never_stops_s, p.watch.pdf_interval_s) == (1.0, 600.0, 60.0)
    (tmp_path / "day").rename(tmp_path / "old")
    p = load_protocol(_protocol(tmp_path, {"settle_s": 2.5, "pdf_interval_s": 0}))
    assert (p.watch.settle_s, p.watch.never_stops_s, p.watch.pdf_interval_s) == (2.5, 600.0, 0.0)


@pytest.mark.parametrize(("watch", "words"), [
    ({"settle_s": 0.0}, "'settle_s' in [watch] must lie in 0.05–3600 s"),
    ({"never_stops_s": -1}, "'never_stops_s' in [watch] must lie in"),
    ({"settle": 1.0}, "did you mean 'settle_s'"),
    ({"pdf_interval_s": "often"}, "pdf_interval_s"),
])
def test_watch_mistakes_are_one_sentence(tmp_path, watch, words):
    with pytest.raises(ProtocolError) as info:
        load_protocol(_protocol(tmp_path, watch))
    assert words in str(info.value) and "\n" not in str(info.value)


def test_process_sheet_on_a_subset_is_process_day_on_that_sheet(tmp_path):
    from towtank.pipeline import process_day, process_sheet

    path = _protocol(tmp_path)
    p = load_protocol(path)
    whole = process_day(path, jobs=1)
    sheet = read_run_sheet(p.campaign.run_sheet, p.water.temperature_C, p.sheet)
    same = process_sheet(p, sheet, jobs=1)
    pd.testing.assert_frame_equal(whole.runs, same.runs)
    assert whole.warnings == same.warnings
    # two rows only: the tables of a sheet that lists only those two
    part = process_sheet(p, sheet[sheet["run"].isin([1, 3])].reset_index(drop=True), jobs=1,
                         unlisted=[])
    assert list(part.runs["run"]) == [1, 3]
    full = whole.runs.set_index("run")
    for col in ("drag_mean", "speed_mean", "tare_drag"):
        assert part.runs.set_index("run").loc[1, col] == full.loc[1, col]
    # run 3's tare is fitted to run 1 alone: it differs from the whole day's
    assert part.runs.set_index("run").loc[3, "tare_drag"] != full.loc[3, "tare_drag"]
