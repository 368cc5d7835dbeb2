"""A rejected run is a Rejection (run, file, stage, reason, kind) made where it is decided, and
the sentence it prints is the one towtank always wrote; grouping and the live page read its
fields, never its words; a run's reduction is made whole and never changed after."""

from __future__ import annotations

import dataclasses
import io
import json
import os
import zipfile
from pathlib import Path
from types import SimpleNamespace

import pandas as pd
import pytest
from conftest import process, write_hull_protocol

from towtank.analysis.daywide import group_rejections, run_reason
from towtank.ingest.protocol import load_protocol
from towtank.live.session import WatchSession
from towtank.messages import REJECTION_KINDS, Notice, Rejection
from towtank.reduce import run as reduce_mod
from towtank.reduce.run import RunReduction, crashed_record, record_units, reduce_record
from towtank.reduce.tare_policy import apply_tares
from towtank.runtime import records
from towtank.testing import damage
from towtank.testing import synthetic as syn

PLAN = [syn.RunSpec("sting", 0.0, v, 0.5) for v in (0.8, 1.6)] + [
    syn.RunSpec("hull", 0.0, v, 0.5) for v in (0.8, 1.2, 1.6, 1.2)
]


@pytest.fixture(scope="session")
def bad_day(tmp_path_factory):
    """A day whose runs are rejected in every way the sheet and the reduction decide:
    run 3 an empty file, run 4 its tare group without a sting run, run 7 the file of run 5
    again, run 8 a sheet row with an unknown config, run 9 a link to itself."""
    root = tmp_path_factory.mktemp("bad_day")
    syn.make_hull_day(root, seed=8, runs=PLAN, sheet_format="csv", file_format="csv",
                      channel_style="canonical")
    protocol = write_hull_protocol(root, sheet_format="csv", channel_style="canonical")
    (root / "data" / "run_003.csv").write_bytes(damage.empty())
    os.symlink("loop.csv", root / "data" / "loop.csv")
    sheet = root / "run_sheet.csv"
    frame = pd.read_csv(sheet, dtype=str, keep_default_na=False)
    frame.loc[frame["run"] == "4", "tare_group"] = "no_sting_here"
    extra = []
    for run, file, config in ((7, "./run_005.csv", "hull"), (8, "run_006.csv", "nonsense"),
                              (9, "loop.csv", "hull")):
        row = frame[frame["run"] == "5"].iloc[0].copy()
        row["run"], row["file"], row["config"] = str(run), file, config
        extra.append(row)
    pd.concat([frame, pd.DataFrame(extra)]).to_csv(sheet, index=False)
    return process(protocol, jobs=1)


def test_every_way_a_run_is_rejected_is_a_rejection_of_its_kind(bad_day):
    got = {run: (r.kind, r.stage) for run, r in bad_day.rejected.items()}
    assert got == {3: ("run_error", "reduce"), 4: ("no_tare", "tare"),
                   7: ("duplicate_file", "sheet"), 8: ("sheet", "sheet"),
                   9: ("unreadable", "sheet")}
    assert all(isinstance(r, Rejection) and r.kind in REJECTION_KINDS
               for r in bad_day.rejected.values())
    assert {r.run for r in bad_day.rejected.values()} == set(bad_day.rejected)


def test_the_sentences_are_those_towtank_wrote_before(bad_day):
    said = {run: str(r) for run, r in bad_day.rejected.items()}
    assert said[4] == ("run 4: run_004.csv: its tare group 'no_sting_here' has no usable sting "
                       "(tare) run, so the mounting's force cannot be removed")
    assert said[7] == ("run 7: ./run_005.csv is also the file of run 5 in the sheet; a "
                       "recording is one run (a copied cell?)")
    assert said[8].startswith("run 8: row ") and "config" in said[8]
    assert said[9].startswith("run 9: loop.csv cannot be opened (")
    assert said[3].startswith("run 3: ") and "run_003.csv" in said[3]
    runs = bad_day.runs.set_index("run")
    for run, sentence in said.items():  # runs.csv's reason is the sentence
        assert runs.loc[run, "status"] == "rejected" and runs.loc[run, "reason"] == sentence


def test_a_worker_that_died_and_an_internal_error_are_rejections(bad_day, monkeypatch):
    row = bad_day.sheet[bad_day.sheet["run"] == 5].iloc[0].to_dict()
    run, red, rejection, _ = crashed_record(row)
    assert (run, red, rejection.kind, rejection.file) == (5, None, "crashed", "run_005.csv")
    assert str(rejection).startswith("run 5: run_005.csv: the process reducing it stopped")

    def broken(*args, **kwargs):
        raise ZeroDivisionError("planted")

    monkeypatch.setattr(reduce_mod, "reduce_run", broken)
    run, red, rejection, _ = reduce_record(bad_day.protocol, row)
    assert red is None and rejection.kind == "internal_error" and rejection.stage == "reduce"
    assert str(rejection).startswith(
        "run 5: run_005.csv: an unexpected internal error (ZeroDivisionError: planted")


def test_a_run_error_naming_its_file_is_not_prefixed_twice():
    named = Rejection.of_run_error(2, "run_002.csv", "run_002.csv holds 2 segments")
    prefixed = Rejection.of_run_error(2, "run_002.csv", "run_002.csv: no plateau")
    bare = Rejection.of_run_error(2, "run_002.csv", "no plateau")
    assert str(named) == "run 2: run_002.csv holds 2 segments"
    assert str(prefixed) == str(bare) == "run 2: run_002.csv: no plateau"
    assert prefixed.reason == bare.reason == "no plateau"


def _runs(rejected: dict[int, Rejection], n: int) -> pd.DataFrame:
    return pd.DataFrame({"run": range(1, n + 1), "file": [f"f{r}.csv" for r in range(1, n + 1)],
                         "status": ["rejected" if r in rejected else "ok"
                                    for r in range(1, n + 1)],
                         "reason": [str(rejected[r]) if r in rejected else ""
                                    for r in range(1, n + 1)]})


def test_grouping_reads_the_fields_not_the_words():
    """A reason that itself starts like the run's prefix is kept as it is; two faults with
    the same words but of different kinds are not one."""
    odd = {r: Rejection(r, f"f{r}.csv", "reduce", f"run {r}: f{r}.csv: is how the lab wrote it",
                        "run_error") for r in (1, 2, 3)}
    groups = group_rejections(_runs(odd, 4), odd)
    assert len(groups) == 1 and groups[0].day_wide and groups[0].runs == [1, 2, 3]
    assert groups[0].sentence.endswith("shown for f1.csv: run 1: f1.csv: is how the lab wrote it")
    assert run_reason(1, "", odd) == "run 1: f1.csv: is how the lab wrote it"
    mixed = {1: Rejection(1, "f1.csv", "reduce", "no plateau", "run_error"),
             2: Rejection(2, "f2.csv", "reduce", "no plateau", "run_error"),
             3: Rejection(3, "f3.csv", "tare", "no plateau", "no_tare")}
    groups = group_rejections(_runs(mixed, 3), mixed, min_group=2)
    assert [g.runs for g in groups] == [[1, 2], [3]]
    assert groups[1].sentence == "run 3: f3.csv: no plateau"


def test_the_live_verdict_shows_the_rejection_without_its_run_number():
    rejection = Rejection(3, "f3.csv", "reduce", "the speed never reaches a plateau",
                          "run_error")
    runs = _runs({3: rejection}, 3).assign(test="steady", angle_deg=0.0, speed_mean=float("nan"),
                                           speed_nominal=1.2, drag_mean=float("nan"))
    day = SimpleNamespace(runs=runs, reductions={}, rejected={3: rejection})
    session = WatchSession.__new__(WatchSession)
    session.given, session.reduced = {}, []
    (verdict,) = [v for v in session._verdicts(day) if v.status == "rejected"]
    assert verdict.reason == "f3.csv: the speed never reaches a plateau"
    assert verdict.line.endswith("rejected: f3.csv: the speed never reaches a plateau")


def test_a_reduction_is_made_whole_and_never_changed(bad_day):
    red = bad_day.reductions[5]
    assert isinstance(red.notes, tuple) and isinstance(red.warnings, tuple)
    with pytest.raises(dataclasses.FrozenInstanceError):
        red.notes = ()  # type: ignore[misc]
    raw = SimpleNamespace(units={"drag": ("N", "assumed")})
    again = record_units(red, raw)  # type: ignore[arg-type]
    assert again is not red and again.units == {"drag": ("N", "assumed")}
    assert again.notes[-1] == "drag had no unit label: taken as N"
    assert bad_day.reductions[5].notes == red.notes  # the day's reduction as it was


def test_the_tare_policy_returns_new_values(bad_day):
    untared = {run: dataclasses.replace(r, tare_group="") for run, r in
               bad_day.reductions.items()}
    before = dict(untared)
    tared, rejected = apply_tares(bad_day.protocol, bad_day.sheet, untared, bad_day.tares)
    assert untared == before and set(tared) == set(untared)
    assert rejected == {}
    tared, rejected = apply_tares(bad_day.protocol, bad_day.sheet, untared, {})
    assert set(rejected) == {5, 6} and set(tared) == {1, 2}
    assert {r.kind for r in rejected.values()} == {"no_tare"}


def test_the_days_warnings_and_inputs_are_not_lists_to_append_to(bad_day):
    assert isinstance(bad_day.warnings, tuple)
    assert all(isinstance(n, Notice) for n in bad_day.warnings)
    protocol = load_protocol(Path(bad_day.protocol.path))
    assert str(protocol.path) in bad_day.inputs


def test_the_layout_check_catches_a_reason_read_by_its_words(tmp_path):
    from test_layout import message_text_reads

    pkg = tmp_path / "pkg"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("", encoding="utf-8")
    (pkg / "a.py").write_text('def f(rejection):\n    if rejection.reason.startswith("x"):\n'
                              '        return 1\n', encoding="utf-8")
    assert message_text_reads(pkg, set()) == ["pkg.a:2 (f) reads a message's text"]


def test_the_prototype_values_are_joined_once(bad_day):
    """With a [vehicle], coefficients.csv is the vehicle stage's table, made from the hull's
    with the prototype values already; they are not joined to it a second time."""
    hull = pd.DataFrame({"symbol": ["X_udot", "Y_vdot"], "prime": [0.1, 0.2],
                         "prototype_value": [float("nan")] * 2})
    joined = hull.assign(prototype_value=[1.0, 2.0], predicted=[0.1, 0.2])
    day = dataclasses.replace(
        bad_day, hull=SimpleNamespace(coefficients=hull),
        vehicle=SimpleNamespace(coefficients=joined),
        prototype_values=pd.DataFrame({"symbol": ["X_udot"], "prototype_value": [9.0]}))
    pd.testing.assert_frame_equal(day.coefficients, joined)  # a copy of it
    alone = dataclasses.replace(day, vehicle=None)
    assert alone.coefficients["prototype_value"].tolist()[0] == 9.0
    assert hull["prototype_value"].isna().all()  # the hull's table as it was


def test_a_cached_reduction_of_the_earlier_layout_is_a_clean_miss(bad_day):
    """Notes and warnings stored as JSON lists come back as tuples; an entry without the
    field saying which note is the missing acceleration (written before it) is a miss."""
    red = bad_day.reductions[5]
    blob = records.to_bytes(red)
    assert records.from_bytes(blob, RunReduction).notes == red.notes
    out = io.BytesIO()
    with zipfile.ZipFile(io.BytesIO(blob)) as old, \
            zipfile.ZipFile(out, "w", compression=zipfile.ZIP_STORED) as new:
        for info in old.infolist():
            data = old.read(info)
            if info.filename == records.HEADER:
                header = json.loads(data)
                del header["accel_missing"]
                data = json.dumps(header).encode()
            new.writestr(info.filename, data)
    with pytest.raises(records.RecordError):
        records.from_bytes(out.getvalue(), RunReduction)
