"""A mistake that rejects every run (a missing gain, a wrong extension) is one sentence for the
day, in the terminal and in the report, with no empty thumbnails; a fault of a few files is
still named file by file."""

from __future__ import annotations

import pandas as pd
import pytest

from towtank.analysis.daywide import group_rejections, run_ranges
from towtank.commands.cli import main
from towtank.messages import Rejection
from towtank.testing import synthetic as syn


def _runs(n: int, bad: dict[int, str], void: tuple[int, ...] = ()) -> pd.DataFrame:
    rows = []
    for run in range(1, n + 1):
        file = f"run_{run:03d}.csv"
        status = "void" if run in void else "rejected" if run in bad else "ok"
        reason = bad.get(run, "").format(file=file, run=run)
        rows.append({"run": run, "file": file, "status": status, "reason": reason})
    return pd.DataFrame(rows)


def rejections_of(runs: pd.DataFrame) -> dict[int, Rejection]:
    """The Rejection objects whose sentences are the ``reason`` of the rejected rows."""
    out = {}
    for r in runs[runs["status"] == "rejected"].itertuples():
        detail = r.reason.removeprefix(f"run {r.run}: ")
        prefixed = detail.startswith(f"{r.file}: ")
        out[int(r.run)] = Rejection(int(r.run), r.file, "reduce",
                                    detail.removeprefix(f"{r.file}: "), "run_error",
                                    file_prefix=prefixed)
        assert str(out[int(r.run)]) == r.reason
    return out


GAIN = "run {run}: {file}: the drag column 'Fx (V)' is recorded in V: give its calibration"


def test_one_fault_in_every_run_is_one_group():
    runs = _runs(42, {r: GAIN for r in range(1, 43) if r != 20}, void=(20,))
    groups = group_rejections(runs, rejections_of(runs))
    assert len(groups) == 1 and groups[0].day_wide
    assert groups[0].runs == [r for r in range(1, 43) if r != 20]
    assert "every run that is not void (runs 1–19, 21–42)" in groups[0].sentence
    assert "shown for run_001.csv: the drag column" in groups[0].sentence


def test_a_few_bad_files_are_named_one_by_one():
    missing = "run {run}: the data file {file} is not found in /data"
    runs = _runs(40, {3: missing, 9: missing, 17: missing, 30: GAIN})
    groups = group_rejections(runs, rejections_of(runs))
    assert [g.runs for g in groups] == [[3], [9], [17], [30]]
    assert not any(g.day_wide for g in groups)
    assert groups[0].sentence == "run 3: the data file run_003.csv is not found in /data"


def test_different_reasons_are_not_merged():
    runs = _runs(6, {1: GAIN, 2: GAIN, 3: GAIN, 4: "run {run}: {file}: too short",
                     5: "run {run}: {file}: too short", 6: "run {run}: {file}: too short"})
    groups = group_rejections(runs, rejections_of(runs))
    assert [g.runs for g in groups] == [[1, 2, 3], [4, 5, 6]]
    assert all(g.day_wide for g in groups)


@pytest.mark.parametrize("runs,text", [([1, 2, 3, 5, 7, 8], "1–3, 5, 7, 8"), ([4], "4"),
                                       ([2, 3], "2, 3"), ([9, 1, 10, 11], "1, 9–11")])
def test_run_ranges(runs, text):
    assert run_ranges(runs) == text


@pytest.mark.heavy
def test_a_missing_gain_is_one_sentence_and_no_empty_thumbnails(tmp_path, capsys):
    syn.make_hull_day(tmp_path, seed=3, file_format="csv", sheet_format="csv")
    sections = syn.hull_protocol_sections(".", "out", sheet_format="csv")
    protocol = syn.write_protocol(tmp_path / "protocol.toml", **sections)
    for f in (tmp_path / "data").glob("*.csv"):  # a wrong extension on every file
        f.rename(f.with_suffix(".txt"))
    assert main(["process", str(protocol), "--no-cache"]) == 1
    out = capsys.readouterr().out
    rejected = [ln for ln in out.splitlines() if ln.startswith("  rejected:")]
    assert len(rejected) == 1, out
    assert "one fault rejected every run that is not void" in rejected[0]
    from pypdf import PdfReader

    text = "\n".join(p.extract_text() for p in PdfReader(tmp_path / "out" / "report.pdf").pages)
    assert "one fault rejected every run" in text
    assert "run thumbnails" not in text  # the only run left is the void one: nothing to draw
    runs = pd.read_csv(tmp_path / "out" / "runs.csv")  # runs.csv still has every run's reason
    assert (runs["status"] == "rejected").sum() == len(runs) - (runs["status"] == "void").sum()
    assert runs.loc[runs["status"] == "rejected", "reason"].str.contains("not found").all()
