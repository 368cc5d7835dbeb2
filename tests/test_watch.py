"""Issue 27: ``towtank watch`` plays a generated day run by run.

Each run file is written the way LabVIEW writes it (opened, appended in blocks with pauses,
closed) by a thread while the watch session runs in this process; after every run the output
folder's runs.csv and coefficients.csv must equal those ``towtank process`` writes for the
runs so far, and no file is ever reduced before its writer closed it. Then the edge cases: a
burst of files, an edited and a half-saved sheet, Excel's lock file, a file that vanishes, a
file the sheet does not name, the PDF carried between redraws, and the command itself with
Ctrl-C. Waits are bounded by generous timeouts that only catch a hang; nothing is timed.
"""

from __future__ import annotations

import dataclasses
import json
import os
import queue
import shutil
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pandas as pd
import pytest
from conftest import draw_only_pages

from towtank.live.session import WatchSession
from towtank.pipeline import process_day
from towtank.report.tables import write_tables
from towtank.runtime.manifest import read_manifest
from towtank.runtime.safefile import sha256_regular
from towtank.testing import synthetic as syn
from towtank.testing.bench_watch import labview_write as write_in_blocks
from towtank.testing.bench_watch import watch_session as session_of
from towtank.testing.days import RunSpec

ROOT = Path(__file__).resolve().parents[1]
HANG_S = 120.0  # bounds a hang only

PLAY = ([RunSpec("sting", 0.0, v, 0.5) for v in (0.8, 1.6, 2.0)]
        + [RunSpec("hull", 0.0, v, 0.5) for v in (0.8, 1.6, 2.0)]
        + [RunSpec("hull", 5.0, 1.6, 0.5, status="void", remarks="carriage stopped early",
                   plateau_s=0.6)]
        + [RunSpec("hull", a, 1.6, 0.5) for a in (10.0, 15.0)]
        + [RunSpec("hull", 0.0, 2.0, 0.5, test="accel")])
BURST = ([RunSpec("sting", 0.0, v, 0.5) for v in (0.8, 1.2, 1.6, 2.0)]
         + [RunSpec("hull", a, v, 0.5) for a in (0.0, 5.0, 10.0, 15.0)
            for v in (0.8, 1.2, 1.6, 2.0)])


def make_day(root: Path, plan: list[RunSpec], *, watch: dict | None = None,
             vehicle: dict | None = None) -> Path:
    """A generated day in ``root/day`` whose run files wait in ``root/all`` (the data folder
    is empty); the protocol ``root/p.toml`` writes into ``root/out``."""
    syn.make_hull_day(root / "day", runs=plan, fs=50.0, file_format="csv", sheet_format="csv",
                      seed=5)
    shutil.move(root / "day" / "data", root / "all")
    (root / "day" / "data").mkdir()
    sections = syn.hull_protocol_sections("day", "out", sheet_format="csv")
    sections["watch"] = {"settle_s": 1.0, "pdf_interval_s": 3600.0, **(watch or {})}
    if vehicle is not None:
        sections["vehicle"] = vehicle
    return syn.write_protocol(root / "p.toml", **sections)


def labview_write(src: Path, dst: Path) -> None:
    """Write ``src``'s bytes into ``dst`` as LabVIEW does: open, append six blocks, close."""
    write_in_blocks(src, dst, blocks=6, pause_s=0.05)


def reference_tables(root: Path, runs: list[int], tag: str) -> dict[str, str]:
    """runs.csv and coefficients.csv of ``towtank process`` on the sheet's rows ``runs``
    (written as a sheet of their own) with the watched data folder."""
    sheet = pd.read_csv(root / "day" / "run_sheet.csv", dtype=str, keep_default_na=False)
    ref = root / f"ref_{tag}"
    ref.mkdir()
    sheet[sheet["run"].astype(int).isin(runs)].to_csv(ref / "run_sheet.csv", index=False)
    sections = syn.hull_protocol_sections("day", "out", sheet_format="csv")
    sections["campaign"]["run_sheet"] = f"ref_{tag}/run_sheet.csv"
    protocol = syn.write_protocol(root / f"ref_{tag}.toml", **sections)
    day = process_day(protocol, jobs=1)
    write_tables(day, ref)
    return {name: (ref / name).read_text() for name in ("runs.csv", "coefficients.csv")}


def assert_outputs_equal_process(root: Path, runs: list[int], tag: str) -> None:
    want = reference_tables(root, runs, tag)
    for name, text in want.items():
        assert (root / "out" / name).read_text() == text, f"{name} after {tag}"


def sheet_runs(root: Path) -> pd.DataFrame:
    return pd.read_csv(root / "day" / "run_sheet.csv", dtype=str, keep_default_na=False)


# ------------------------------------------------------------------------------ the play
@pytest.mark.heavy
def test_a_day_played_run_by_run_equals_process_after_every_run(tmp_path):
    protocol = make_day(tmp_path, PLAY)
    s, lines = session_of(protocol, live_figures=True)
    sheet = sheet_runs(tmp_path)
    void = [int(r) for r, st in zip(sheet["run"], sheet["status"], strict=True) if st == "void"]
    s.step()
    state = json.loads((tmp_path / "out" / ".live" / "state.json").read_text())
    assert {r["state"] for r in state["sheet"]} == {"to do", "void"}
    done: list[int] = []
    versions = [state["version"]]
    ranked: list[int] = []  # how many of the sheet's runs were ranked after each run
    for run, file in zip(sheet["run"].astype(int), sheet["file"], strict=True):
        if run in void:
            continue
        writer = threading.Thread(target=labview_write,
                                  args=(tmp_path / "all" / file, tmp_path / "day" / "data" / file))
        early: list[int] = []

        def until(sess: WatchSession, run: int = run, writer: threading.Thread = writer,
                  early: list[int] = early) -> bool:
            if writer.is_alive() and run in sess.given:
                early.append(run)  # a verdict while the writer still held the file open
            return run in sess.given and not writer.is_alive()

        writer.start()
        s.run(until, timeout_s=HANG_S)
        writer.join()
        assert run in s.given, f"run {run} got no verdict"
        assert not early, f"run {run} was reduced while being written"
        done.append(run)
        assert_outputs_equal_process(tmp_path, sorted(done + void), f"run{run}")
        assert any(line.startswith(f"run {run}  ") for line in lines)
        state = json.loads((tmp_path / "out" / ".live" / "state.json").read_text())
        versions.append(state["version"])
        states = {r["run"]: r["state"] for r in state["sheet"]}
        assert all(states[r] in ("done", "rejected") for r in done)
        assert all(states[r] == "void" for r in void)
        assert sum(v == "to do" for v in states.values()) == len(sheet) - len(done) - len(void)
        assert state["latest"]["run"] == run
        # which run next: only runs still to do, each expected to narrow its target
        todo = {r for r, st in states.items() if st == "to do"}
        assert all(n["run"] in todo for n in state["next_runs"] if n["run"] is not None)
        assert all(n["half_width_after"] <= n["half_width_now"] * (1 + 1e-9)
                   for n in state["next_runs"]
                   if n["half_width_now"] is not None and n["half_width_after"] is not None)
        ranked.append(len([n for n in state["next_runs"] if n["run"] is not None]))
        assert "latest_run" in state["figures"]
        assert (tmp_path / "out" / ".live" / state["figures"]["latest_run"]).is_file()
    # every reduction this session made was of a complete file, each file reduced once
    final = {f: sha256_regular(tmp_path / "day" / "data" / f) for f in sheet["file"]}
    assert s.reduced and all(sha == final[f] for _run, f, sha in s.reduced)
    assert len({f for _r, f, _s in s.reduced}) == len(s.reduced)
    assert versions == sorted(versions) and len(set(versions)) == len(versions)
    # once the hull fit exists and runs are left, the top three are ranked and printed
    assert max(ranked) == 3 and ranked[-1] == 0
    assert any(line.startswith("  next 1. run ") for line in lines)
    ok = [line for line in lines if line.startswith("run ")]
    assert len(ok) == len(done)
    assert all("  ok" in line or "suspicious" in line for line in ok)
    # the hull fit grew with the day: the C_D(α) figure is there at the end
    s.finish()
    state = json.loads((tmp_path / "out" / ".live" / "state.json").read_text())
    assert "damping" in state["figures"] and state["coefficients"]
    assert (tmp_path / "out" / ".live" / state["figures"]["damping"]).is_file()
    assert state["coefficient_columns"][0] == "symbol"


# ------------------------------------------------------------------------------ edge cases
def clocked(s: WatchSession, ahead_s: float) -> None:
    """Let the session see the files ``ahead_s`` later than now (new files have settled)."""
    s.clock = lambda: time.time() + ahead_s


def settled_step(s: WatchSession, ahead_s: float, changed: set[str] | None = None) -> list:
    """Two looks, the second ``ahead_s + 2`` s ahead: a file changed since the last look
    is seen changing, then settled (more than [watch] settle_s later)."""
    clocked(s, ahead_s)
    first = s.step(changed)
    clocked(s, ahead_s + 2.0)
    return first + s.step(changed)


def test_a_burst_of_twenty_files_is_one_batch(tmp_path):
    protocol = make_day(tmp_path, BURST)
    s, lines = session_of(protocol)
    s.step()
    batches, writes = s.batches, s.writes
    for f in sorted((tmp_path / "all").iterdir()):
        shutil.copy(f, tmp_path / "day" / "data" / f.name)
    clocked(s, 5.0)
    verdicts = s.step()
    assert len(verdicts) == 20 and s.batches == batches + 1 and s.writes == writes + 1
    assert sum(line.startswith("run ") for line in lines) == 20
    assert_outputs_equal_process(tmp_path, list(range(1, 21)), "burst")


def test_sheet_edits_lock_files_vanishing_and_unlisted_files(tmp_path):
    protocol = make_day(tmp_path, PLAY)
    s, lines = session_of(protocol)
    data = tmp_path / "day" / "data"
    for name in ("run_001.csv", "run_002.csv", "run_003.csv", "run_004.csv", "run_005.csv"):
        shutil.copy(tmp_path / "all" / name, data / name)
    clocked(s, 5.0)
    s.step()
    assert sorted(s.given) == [1, 2, 3, 4, 5]

    # Excel opens the sheet: its lock file beside it is ignored, said once
    lock = tmp_path / "day" / "~$run_sheet.xlsx"
    lock.write_bytes(b"\x00owner")
    s.step({str(lock)})
    s.step({str(lock)})
    said = [m for m in s.said.messages if "~$run_sheet.xlsx" in m]
    assert len(said) == 1 and "lock file" in said[0]

    # the sheet saved half-way cannot be read: the last good sheet stays, said once
    sheet_path = tmp_path / "day" / "run_sheet.csv"
    good = sheet_path.read_text()
    sheet_path.write_text("run,fi")
    settled_step(s, 10.0)
    settled_step(s, 14.0)
    bad = [m for m in s.said.messages if "could not be read" in m]
    assert len(bad) == 1 and "last good sheet is kept" in bad[0]
    assert s.sheet is not None and len(s.sheet) == len(PLAY)

    # then saved whole, with run 5 marked void and run 4's set speed corrected
    sheet = pd.read_csv(pd.io.common.StringIO(good), dtype=str, keep_default_na=False)
    sheet.loc[sheet["run"] == "5", ["status", "remarks"]] = ["void", "wrong model trim"]
    sheet.loc[sheet["run"] == "4", "speed_nominal"] = "0.9"
    sheet.to_csv(sheet_path, index=False)
    settled_step(s, 20.0)
    runs = pd.read_csv(tmp_path / "out" / "runs.csv")
    row5 = runs[runs["run"] == 5].iloc[0]
    assert row5["status"] == "void" and row5["reason"] == "wrong model trim"
    assert float(runs[runs["run"] == 4].iloc[0]["speed_nominal"]) == 0.9
    assert_outputs_equal_process(tmp_path, [1, 2, 3, 4, 5, 7], "edited")

    # a file that appears and disappears before it is complete
    part = data / "run_006.csv"
    with open(part, "wb") as fh:
        fh.write((tmp_path / "all" / "run_006.csv").read_bytes()[:500])
        fh.flush()
        s.clock = time.time
        s.step()
        assert 6 not in s.given and s.tracker.is_waiting("run_006.csv")
    part.unlink()
    s.step()
    gone = [m for m in s.said.messages if "appeared and disappeared" in m]
    assert len(gone) == 1 and "run_006.csv" in gone[0] and 6 not in s.given

    # a file the sheet does not name: the sentence of process's warning, once
    stray = data / "spare_take.csv"
    shutil.copy(tmp_path / "all" / "run_006.csv", stray)
    s.step({str(stray)})
    s.step({str(stray)})
    stray_said = [m for m in s.said.messages if "spare_take.csv" in m]
    assert stray_said == ["spare_take.csv is in the data folder but not in the run sheet; it "
                          "is ignored."]
    # a changed recording is reduced again and gets a new verdict
    before = len([line for line in lines if line.startswith("run 1  ")])
    shutil.copy(tmp_path / "all" / "run_003.csv", data / "run_001.csv")  # recorded over
    settled_step(s, 30.0)
    assert len([line for line in lines if line.startswith("run 1  ")]) == before + 1


@pytest.mark.heavy
def test_a_vehicle_figure_drawn_now_beside_the_carried_figures(tmp_path, monkeypatch):
    """A day with a [vehicle]: each write draws figures/predicted_vs_measured.png itself, and
    the figures carried over from the last report go in beside it (a restarted watch on an
    output folder with a report once stopped here with FileExistsError)."""
    draw_only_pages(monkeypatch, lambda page: False)  # figures/ is read here, report.pdf not
    protocol = make_day(tmp_path, PLAY[:6], vehicle={"name": "SUT-2 1/4 model",
                                                     "hull": "myring", "speed_m_s": 1.0})
    s, _lines = session_of(protocol, report=True)
    data = tmp_path / "day" / "data"
    for name in ("run_001.csv", "run_002.csv", "run_003.csv", "run_004.csv", "run_005.csv"):
        shutil.copy(tmp_path / "all" / name, data / name)
    clocked(s, 5.0)
    s.step()
    assert s._collect_report(wait=True)  # report.pdf and figures/ into the outputs
    out = tmp_path / "out"
    drawn = sorted(p.name for p in (out / "figures").iterdir())
    assert "predicted_vs_measured.png" in drawn and len(drawn) > 1
    shutil.copy(tmp_path / "all" / "run_006.csv", data / "run_006.csv")
    verdicts = settled_step(s, 30.0)  # within pdf_interval_s: the figures are carried over
    assert [v.run for v in verdicts] == [6]
    assert sorted(p.name for p in (out / "figures").iterdir()) == drawn
    man = read_manifest(out)
    assert man is not None and "runs.csv" in man["files"]
    assert "run_006.csv" in (out / "runs.csv").read_text()
    s.close()


@pytest.mark.heavy
def test_the_pdf_is_carried_over_between_redraws_and_provenance_says_which_runs(tmp_path,
                                                                                monkeypatch):
    # the PDFs are compared whole; the runs table, which lists the runs each PDF covers, is
    # the page drawn (the others blank, still headed and numbered)
    draw_only_pages(monkeypatch, lambda page: page.kind == "runs")
    protocol = make_day(tmp_path, PLAY[:4])
    s, _lines = session_of(protocol, report=True)
    data = tmp_path / "day" / "data"
    for name in ("run_001.csv", "run_002.csv"):
        shutil.copy(tmp_path / "all" / name, data / name)
    clocked(s, 5.0)
    s.step()  # the first batch: the tables at once, the PDF drawn beside
    out = tmp_path / "out"
    assert not (out / "report.pdf").exists() and (out / "runs.csv").is_file()
    assert s._job is not None
    assert s._collect_report(wait=True)  # drawn: into the outputs
    first = (out / "report.pdf").read_bytes()
    assert json.loads((out / "provenance.json").read_text())["watch"]["pdf_current"]
    shutil.copy(tmp_path / "all" / "run_003.csv", data / "run_003.csv")
    s.step()  # within pdf_interval_s: the tables move on, the PDF is carried over
    assert (out / "report.pdf").read_bytes() == first
    man = read_manifest(out)
    assert man is not None and "report.pdf" in man["files"] and "report.xlsx" in man["files"]
    assert any(k.startswith("figures/") for k in man["files"])
    prov = json.loads((out / "provenance.json").read_text())["watch"]
    assert prov["pdf_runs"] == [1, 2] and prov["runs"] == [1, 2, 3] and not prov["pdf_current"]
    state = json.loads((out / ".live" / "state.json").read_text())
    assert state["pdf"]["runs"] == 2
    s.finish()  # at the end: the PDF of every run so far
    prov = json.loads((out / "provenance.json").read_text())["watch"]
    assert prov["pdf_runs"] == [1, 2, 3] and prov["pdf_current"]
    assert (out / "report.pdf").read_bytes() != first

    # Ctrl-C while a report is being drawn: its process is ended and its folder removed
    shutil.copy(tmp_path / "all" / "run_004.csv", data / "run_004.csv")
    s.protocol = dataclasses.replace(
        s.protocol, watch=dataclasses.replace(s.protocol.watch, pdf_interval_s=0.0))
    clocked(s, 10.0)
    s.step()
    assert s._job is not None
    pid, folder = s._job[0], s._job[1]
    s.close()
    with pytest.raises(ChildProcessError):
        os.waitpid(pid, os.WNOHANG)  # reaped
    assert not folder.exists() and not list((out / ".live").glob(".report-*"))


# ------------------------------------------------------------------------------ the command
def _text(path: Path) -> str:
    try:
        return path.read_text()
    except OSError:  # between the two renames of an output swap
        return ""


def _lines(stream, q: queue.Queue) -> None:
    for line in stream:
        q.put(line)
    q.put(None)


def _wait_for(q: queue.Queue, text: str, seen: list[str]) -> str:
    end = time.monotonic() + HANG_S
    while time.monotonic() < end:
        try:
            line = q.get(timeout=1.0)
        except queue.Empty:
            continue
        if line is None:
            break
        seen.append(line)
        if text in line:
            return line
    raise AssertionError(f"{text!r} never came; stdout: {''.join(seen)}")


@pytest.mark.heavy
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="signals")
def test_the_command_gives_a_verdict_and_stops_cleanly_on_ctrl_c(tmp_path):
    protocol = make_day(tmp_path, PLAY[:4])
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT), env.get("PYTHONPATH")) if p)
    proc = subprocess.Popen(
        [sys.executable, "-m", "towtank", "watch", str(protocol), "--no-browser",
         "--no-server", "--no-report"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
        text=True, env=env, start_new_session=True)
    q: queue.Queue = queue.Queue()
    threading.Thread(target=_lines, args=(proc.stdout, q), daemon=True).start()
    seen: list[str] = []
    try:
        _wait_for(q, "Ctrl-C to stop", seen)
        labview_write(tmp_path / "all" / "run_001.csv", tmp_path / "day" / "data" / "run_001.csv")
        line = _wait_for(q, "run 1  ", seen)
        assert "steady" in line and "m/s" in line and "drag" in line and "ok" in line
        end = time.monotonic() + HANG_S  # the verdict comes first, then the outputs
        while time.monotonic() < end and "run_001.csv" not in _text(tmp_path / "out" /
                                                                    "runs.csv"):
            time.sleep(0.05)
        os.killpg(proc.pid, signal.SIGINT)
        code = proc.wait(timeout=HANG_S)
    finally:
        if proc.poll() is None:
            proc.kill()
    err = proc.stderr.read()
    assert code == 130, err
    assert "interrupted" in err and "Traceback" not in err
    out = tmp_path / "out"
    man = read_manifest(out)
    assert man is not None and man.get("complete", True)
    for rel, entries in man["files"].items():
        assert sha256_regular(out / rel) == entries[-1]["sha256"], rel
    runs = pd.read_csv(out / "runs.csv")
    assert list(runs["run"]) == [1]


def test_a_file_that_never_stops_growing_is_said_once_and_never_reduced(tmp_path):
    protocol = make_day(tmp_path, PLAY[:3], watch={"never_stops_s": 1.0, "settle_s": 0.5})
    s, _lines = session_of(protocol)
    data = tmp_path / "day" / "data"
    src = (tmp_path / "all" / "run_001.csv").read_bytes()
    ahead = 0.0
    with open(data / "run_001.csv", "wb") as fh:  # held open, a block before every look
        for k in range(8):
            fh.write(src[k * 100:(k + 1) * 100])
            fh.flush()
            os.utime(fh.fileno(), ns=(time.time_ns() + k, time.time_ns() + k))
            clocked(s, ahead)
            s.step()
            ahead += 0.4  # each look 0.4 s later than the last: below settle_s
    said = [m for m in s.said.messages if "still being written" in m]
    assert len(said) == 1 and "run_001.csv" in said[0] and "never_stops_s" in said[0]
    assert 1 not in s.given and not s.reduced


def test_a_file_of_the_users_with_an_outputs_name_stops_the_writes_not_the_verdicts(tmp_path):
    protocol = make_day(tmp_path, PLAY[:3])
    s, lines = session_of(protocol)
    data = tmp_path / "day" / "data"
    shutil.copy(tmp_path / "all" / "run_001.csv", data / "run_001.csv")
    clocked(s, 5.0)
    s.step()
    mine = "my own notes\n"
    (tmp_path / "out" / "runs.csv").write_text(mine)  # the user's file now
    writes = s.writes
    shutil.copy(tmp_path / "all" / "run_002.csv", data / "run_002.csv")
    s.step()
    assert any(line.startswith("run 2  ") for line in lines) and s.writes == writes
    said = [m for m in s.said.messages if "runs.csv" in m and "verdicts go on" in m]
    assert len(said) == 1
    assert (tmp_path / "out" / "runs.csv").read_text() == mine  # never overwritten


def test_a_second_watch_of_the_same_output_folder_is_refused_in_one_sentence(tmp_path):
    from towtank.commands.watch import hold_watch_lock
    from towtank.errors import ProtocolError

    live = tmp_path / "out" / ".live"
    first = hold_watch_lock(live)
    with pytest.raises(ProtocolError) as err:
        hold_watch_lock(live)
    sentence = str(err.value)
    assert sentence.count(". ") == 0 and f"(process {os.getpid()})" in sentence
    assert "already watching into" in sentence and str(tmp_path / "out") in sentence
    first.close()  # the first watch ends: the next may start
    hold_watch_lock(live).close()
