"""A day with damaged runs among good ones, through the command line.

Bad input never crashes a day and never loses data: every damaged run is rejected with one
sentence saying why, repairable damage leaves the run ok with a note, the rest of the day still
gives the hull's coefficients within tolerance, the raw files are never touched, outputs are
replaced only when complete, and a protocol or run-sheet fault writes nothing at all.
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import json
from pathlib import Path

import pandas as pd
import pytest

from towtank.commands.cli import main
from towtank.testing import damage

SEED = 5
# |relative error| allowed per coefficient (the hull tolerances)
TOLERANCE = {
    "X_udot": 0.05,
    "Y_vdot": 0.02,
    "Z_wdot": 0.02,
    "X_u|u|": 0.01,
    "Y_uv": 0.01,
    "Z_uw": 0.01,
    "Y_v|v|": 0.015,
    "Z_w|w|": 0.015,
    "X_uv": 0.20,
    "X_uw": 0.20,
    "X_v|v|": 0.35,
    "X_w|w|": 0.35,
}


def run_cli(*args: str) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = main(["process", *args])
    return rc, out.getvalue(), err.getvalue()


def fingerprint(folder: Path, skip: tuple[str, ...] = ()) -> dict[str, tuple[str, int]]:
    """sha256 and mtime of every file under ``folder``."""
    out = {}
    for p in sorted(folder.rglob("*")):
        rel = p.relative_to(folder).as_posix()
        if p.is_file() and not rel.startswith(skip):
            out[rel] = (hashlib.sha256(p.read_bytes()).hexdigest(), p.stat().st_mtime_ns)
    return out


def raw_inputs(day: damage.DamagedDay) -> dict[str, tuple[str, int]]:
    files = fingerprint(day.root / "data")
    for p in (day.protocol, day.root / "run_sheet.csv"):
        files[p.name] = (hashlib.sha256(p.read_bytes()).hexdigest(), p.stat().st_mtime_ns)
    return files


@pytest.fixture(scope="session")
def day(tmp_path_factory) -> damage.DamagedDay:
    return damage.make_damaged_day(tmp_path_factory.mktemp("damaged") / "day", seed=SEED)


@pytest.fixture(scope="session")
def processed(day, tmp_path_factory):
    before = raw_inputs(day)
    out = tmp_path_factory.mktemp("outputs") / "out"
    rc, stdout, stderr = run_cli(str(day.protocol), "--no-report", "--out", str(out))
    runs = pd.read_csv(out / "runs.csv", keep_default_na=False)
    return {
        "rc": rc, "stdout": stdout, "stderr": stderr, "out": out, "before": before,
        "runs": runs.set_index("run"),
    }


@pytest.mark.heavy
def test_make_damaged_day_unpacks_and_covers_every_kind(day):
    expected, ok_with_note = day
    assert set(day.kinds.values()) >= {
        "empty", "truncate", "text_rows_many", "text_rows_few", "drop_channel", "nan_gap_long",
        "nan_gap_short", "duplicate_block", "time_reset", "irregular_rate", "time_in_ms",
        "clip", "spikes", "no_plateau", "no_tare_group", "missing_file",
    }
    assert set(expected) | set(ok_with_note) == set(day.kinds)
    missing = next(r for r, k in day.kinds.items() if k == "missing_file")
    assert not (day.root / "data" / f"run_{missing:03d}.csv").exists()
    assert (day.root / "data" / day.stray_file).exists()


def test_damage_is_deterministic(tmp_path, day):
    good = (day.root / "data" / "run_014.csv").read_bytes()
    for fn in (damage.truncate, damage.duplicate_block, damage.time_reset,
               damage.irregular_rate, damage.no_plateau):
        assert fn(good, 3) == fn(good, 3)
    assert damage.spikes(good, 4, "drag", 9) == damage.spikes(good, 4, "drag", 9)
    frame = damage.read_frame(good)
    assert damage.frame_bytes(frame) == good  # the CSV round trip is exact
    assert damage.nan_gap(frame, 0.1, "drag", 2).equals(damage.nan_gap(frame, 0.1, "drag", 2))


def test_the_day_finishes_with_exit_1_and_no_traceback(processed):
    assert processed["rc"] == 1
    assert "Traceback" not in processed["stdout"] + processed["stderr"]


def test_every_damaged_run_is_rejected_with_its_reason(day, processed):
    runs = processed["runs"]
    for run, keyword in day.expected.items():
        row = runs.loc[run]
        assert row["status"] == "rejected", (run, row["reason"])
        text = row["reason"]
        assert text.startswith(f"run {run}: "), text
        assert keyword in text.lower(), (day.kinds[run], text)
        assert "\n" not in text and "internal error" not in text
        assert f"rejected: {text}" in processed["stdout"]


def test_every_reason_names_the_file(day, processed):
    runs = processed["runs"]
    unnamed = [
        (run, runs.loc[run, "reason"]) for run in day.expected
        if f"run_{run:03d}.csv" not in runs.loc[run, "reason"]
    ]
    assert unnamed == []


def test_repairable_damage_leaves_the_run_ok_with_a_note(day, processed):
    runs = processed["runs"]
    for run in day.ok_with_note:
        row = runs.loc[run]
        assert row["status"] == "ok", (run, row["reason"])
        assert day.notes[run] in row["notes"], (day.kinds[run], row["notes"])


def test_the_good_runs_are_all_used(day, processed):
    runs = processed["runs"]
    good = runs.loc[[r for r in runs.index if r not in day.kinds]]
    assert set(good["status"]) == {"ok", "void"}
    assert list(good.index[good["status"] == "void"]) == [20]


def test_the_stray_file_is_a_warning(day, processed):
    assert (
        f"warning: {day.stray_file} is in the data folder but not in the run sheet; it is "
        "ignored." in processed["stdout"]
    )
    assert day.stray_file not in set(processed["runs"]["file"])


def test_coefficients_of_the_remaining_runs_meet_the_tolerances(day, processed):
    truth = json.loads((day.root / "truth.json").read_text())["coefficients"]
    coef = pd.read_csv(processed["out"] / "coefficients.csv").set_index("symbol")
    errors = {s: (coef.loc[s, "value"] - v) / abs(v) for s, v in truth.items()}
    bad = {s: f"{100 * e:+.2f} %" for s, e in errors.items() if abs(e) > TOLERANCE[s]}
    assert bad == {}


def test_raw_files_are_bit_identical_afterwards(day, processed):
    assert raw_inputs(day) == processed["before"]


def test_provenance_records_the_inputs_it_used(day, processed):
    prov = json.loads((processed["out"] / "provenance.json").read_text())
    recorded = {Path(i["path"]).name: i["sha256"] for i in prov["inputs"]}
    runs = processed["runs"]
    expect = [day.protocol, day.root / "run_sheet.csv"] + [
        day.root / "data" / f for f in runs.loc[runs["status"] == "ok", "file"]
    ]
    for p in expect:
        assert recorded[p.name] == hashlib.sha256(p.read_bytes()).hexdigest(), p.name


def test_provenance_records_every_input_file(day, processed):
    """Rejected runs' files too: what was read is on record, whatever came of it."""
    prov = json.loads((processed["out"] / "provenance.json").read_text())
    recorded = {Path(i["path"]).name: i["sha256"] for i in prov["inputs"]}
    for p in (day.root / "data").iterdir():
        if p.name != day.stray_file:
            assert recorded[p.name] == hashlib.sha256(p.read_bytes()).hexdigest(), p.name


def test_a_second_run_gives_byte_identical_csvs(day, processed, tmp_path):
    out = processed["out"]
    first = {p.name: p.read_bytes() for p in out.glob("*.csv")}
    assert set(first) >= {"runs.csv", "coefficients.csv", "scaling.csv"}
    rc, _, _ = run_cli(str(day.protocol), "--no-report", "--out", str(out), "-q")
    assert rc == 1
    assert {p.name: p.read_bytes() for p in out.glob("*.csv")} == first  # from the cache
    fresh = tmp_path / "fresh"
    rc, _, _ = run_cli(str(day.protocol), "--no-report", "--out", str(fresh), "--no-cache", "-q")
    assert rc == 1
    assert {p.name: p.read_bytes() for p in fresh.glob("*.csv")} == first


def _leftovers(out: Path) -> list[str]:
    return sorted(p.name for p in out.parent.iterdir() if p.name.startswith(f".{out.name}."))


def test_a_misspelt_protocol_key_writes_nothing(day, processed, tmp_path):
    out = processed["out"]
    before = fingerprint(out)
    broken = day.root / "broken_protocol.toml"
    text = day.protocol.read_text()
    assert "temperature_C = " in text
    broken.write_text(text.replace("temperature_C = ", "temprature_C = ", 1))
    rc, stdout, stderr = run_cli(str(broken), "--no-report", "--out", str(out))
    assert rc == 2
    assert "'temprature_C'" in stderr and "did you mean 'temperature_C'" in stderr
    assert len(stderr.strip().splitlines()) == 1 and "Traceback" not in stderr
    assert fingerprint(out) == before and _leftovers(out) == []
    fresh = tmp_path / "never"
    rc, _, stderr = run_cli(str(broken), "--no-report", "--out", str(fresh))
    assert rc == 2 and "temprature_C" in stderr
    assert not fresh.exists() and list(tmp_path.iterdir()) == []


def test_duplicated_run_numbers_stop_the_day(day, processed, tmp_path):
    sheet = (day.root / "run_sheet.csv").read_text().splitlines()
    dup = sheet + [sheet[5]]  # run 5 twice
    (day.root / "dup_sheet.csv").write_text("\n".join(dup) + "\n")
    text = day.protocol.read_text().replace("run_sheet.csv", "dup_sheet.csv")
    proto = day.root / "dup_protocol.toml"
    proto.write_text(text)
    out = processed["out"]
    before = fingerprint(out)
    rc, _, stderr = run_cli(str(proto), "--no-report", "--out", str(out))
    assert rc == 2
    assert f"duplicated run numbers (run 5 on rows 6, {len(dup)})" in stderr
    assert fingerprint(out) == before and _leftovers(out) == []
    fresh = tmp_path / "never"
    assert run_cli(str(proto), "--no-report", "--out", str(fresh))[0] == 2
    assert not fresh.exists()


def test_a_failing_report_writer_leaves_the_old_outputs(day, processed, monkeypatch):
    from towtank.report import outputs

    out = processed["out"]
    before = fingerprint(out)

    def writer(day_result, folder: Path) -> None:
        (folder / "report.pdf").write_bytes(b"%PDF-half")
        raise RuntimeError("disk full while writing the report")

    monkeypatch.setattr(outputs, "_report_writers", lambda **_: [writer])
    rc, stdout, stderr = run_cli(str(day.protocol), "--out", str(out), "-q")
    assert rc not in (0, 1)
    assert "disk full while writing the report" in stderr and "Traceback" not in stderr
    assert fingerprint(out) == before
    assert _leftovers(out) == []


def test_an_internal_bug_rejects_one_run_and_debug_shows_it(day, monkeypatch, tmp_path):
    from towtank.reduce import run as reduce_stage

    real = reduce_stage.reduce_run

    def buggy(raw, processing, *, run, **kw):
        if run == 14:
            raise ZeroDivisionError("float division by zero")
        return real(raw, processing, run=run, **kw)

    monkeypatch.setattr(reduce_stage, "reduce_run", buggy)
    out = tmp_path / "out"
    args = (str(day.protocol), "--no-report", "--out", str(out), "-j", "1", "--no-cache")
    rc, stdout, stderr = run_cli(*args)
    assert rc == 1
    assert "Traceback" not in stdout + stderr
    reason = pd.read_csv(out / "runs.csv").set_index("run").loc[14, "reason"]
    assert reason.startswith("run 14: run_014.csv: an unexpected internal error")
    assert "ZeroDivisionError" in reason and "--debug" in reason
    with pytest.raises(ZeroDivisionError):
        run_cli(*args, "--debug")


def test_a_run_whose_worker_dies_is_rejected_in_one_sentence():
    from towtank.reduce.run import crashed_record

    run, red, reason, preview = crashed_record({"run": 30, "file": "run_030.csv"})
    assert (run, red, preview) == (30, None, None)
    assert reason.kind == "crashed" and (reason.run, reason.file) == (30, "run_030.csv")
    sentence = str(reason)
    assert sentence.startswith("run 30: run_030.csv: the process reducing it stopped abruptly")
    assert sentence.count(". ") == 0 and "\n" not in sentence
