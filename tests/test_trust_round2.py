"""Issue 20, items 1-5 and 11: a cache that cannot run code or go stale, no user file lost to a
name clash, two writers never mixed, output-folder entries that cannot hang or crash a run, and
a manifest that is never trusted unchecked."""

from __future__ import annotations

import hashlib
import json
import os
import pickle
import shutil
import subprocess
import sys
import threading
import zlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import towtank
from towtank.commands.cli import main
from towtank.runtime import records
from towtank.runtime.manifest import MANIFEST, lock_path, output_lock, read_manifest
from towtank.testing import synthetic as syn
from towtank.testing.child import run_in_child
from towtank.testing.hang import hang_bound

SEED = 5


def _protocol(root: Path, extra: str = "", **model) -> Path:
    sections = syn.hull_protocol_sections(".", "out", sheet_format="csv")
    sections["model"].update(model)
    path = syn.write_protocol(root / "protocol.toml", **sections)
    path.write_text(path.read_text() + extra)
    return path


@pytest.fixture(scope="session")
def day_dir(trust_day) -> Path:
    """The session's synthetic day (seed 5, CSV run files and sheet: tests/conftest.py)."""
    return trust_day.dir


@pytest.fixture(scope="session")
def day(trust_day) -> Path:
    """A protocol of the module's day, in a folder of its own (the tests only read it)."""
    return trust_day.protocol


def _process(protocol: Path, out: Path, *extra: str) -> int:
    return main(["process", str(protocol), "--out", str(out), "-q", "--jobs", "1",
                 "--no-report", *extra])


@pytest.fixture(scope="session")
def processed_out(trust_day) -> Path:
    """The output folder (with its cache) of ``day`` processed once: a test that starts from
    the processed day copies it (:func:`_processed`) rather than process the day again."""
    return trust_day.out


def _processed(processed_out: Path, out: Path) -> None:
    """``out``: a copy of the processed day's output folder, as ``_process(day, out)`` writes
    it."""
    shutil.copytree(processed_out, out, symlinks=True)


def _coefficients(out: Path) -> pd.Series:
    return pd.read_csv(out / "coefficients.csv").set_index("symbol")["value"]


# ---------------------------------------------------------------- 1. the cache runs no code
class _Planted:
    """Unpickling this writes a marker file: the proof that a planted entry ran code."""

    def __init__(self, marker: str):
        self.marker = marker

    def __reduce__(self):
        return (Path.write_text, (Path(self.marker), "code ran"))


def _plant(cache: Path, make_blob) -> int:
    """Replace every indexed cache entry by ``make_blob(original)``; return how many."""
    index = json.loads((cache / "files.json").read_text())
    pack = "pack-1-1.bin"
    data, entries = b"", {}
    for name, (old_pack, offset, length, _) in index["entries"].items():
        old = (cache / "runs" / old_pack).read_bytes()[offset:offset + length]
        blob = make_blob(old)
        entries[name] = [pack, len(data), len(blob), zlib.crc32(blob)]
        data += blob
    (cache / "runs" / pack).write_bytes(data)
    index["entries"] = entries
    (cache / "files.json").write_text(json.dumps(index))
    (cache / "day.json").unlink()  # no replay: the runs are looked up in the cache
    return len(entries)


@pytest.mark.heavy
def test_a_planted_pickle_in_the_cache_runs_no_code(day, processed_out, tmp_path):
    out = tmp_path / "out"
    _processed(processed_out, out)
    first = _coefficients(out)
    marker = tmp_path / "pwned"
    assert _plant(out / ".cache", lambda old: pickle.dumps(_Planted(str(marker)))) > 30
    assert _process(day, out) == 0
    assert not marker.exists()
    pd.testing.assert_series_equal(_coefficients(out), first)


def _retyped(old: bytes) -> bytes:
    """A well-formed record of the right fields with one field of the wrong type."""
    import io
    import zipfile

    src = zipfile.ZipFile(io.BytesIO(old))
    header = json.loads(src.read(records.HEADER))
    header["fs"] = "a thousand"
    header["samples"] = header["thumb"]  # and an array named twice
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as dst:
        for info in src.infolist():
            dst.writestr(info, json.dumps(header) if info.filename == records.HEADER
                         else src.read(info))
    return buf.getvalue()


@pytest.mark.parametrize("make_blob", [
    _retyped,
    lambda old: old[: len(old) // 2],  # cut short
    lambda old: b"PK\x03\x04" + os.urandom(200),  # noise behind a zip signature
    lambda old: json.dumps([1, 2, 3]).encode(),
], ids=["wrong-type", "truncated", "noise", "json"])
def test_a_damaged_or_retyped_cache_entry_is_a_miss(day, processed_out, tmp_path, make_blob):
    out = tmp_path / "out"
    _processed(processed_out, out)
    first = _coefficients(out)
    _plant(out / ".cache", make_blob)
    assert _process(day, out) == 0
    pd.testing.assert_series_equal(_coefficients(out), first)


@dataclass
class _OneArray:
    x: np.ndarray


def test_a_record_with_a_huge_declared_array_is_refused_before_it_is_allocated():
    import io
    import zipfile

    blob = records.to_bytes(_OneArray(np.arange(10.0)))
    assert records.from_bytes(blob, _OneArray).x.tolist() == list(np.arange(10.0))
    npy = io.BytesIO()
    np.lib.format.write_array_header_1_0(
        npy, {"descr": "<f8", "fortran_order": False, "shape": (1 << 40,)})
    npy.write(b"\0" * 80)
    src = zipfile.ZipFile(io.BytesIO(blob))
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as dst:
        for info in src.infolist():
            dst.writestr(info, npy.getvalue() if info.filename.endswith(".npy")
                         else src.read(info))
    with pytest.raises(records.RecordError, match="declares more than it holds"):
        records.from_bytes(buf.getvalue(), _OneArray)


# ------------------------------------------------------ 2. every file the day read is stamped
def _tare_table(root: Path, scale: float) -> None:
    truth = json.loads((root / "truth.json").read_text())
    tare = truth["tares"]["A"]
    u = np.linspace(0.2, 2.2, 11)
    lines = ["speed_m_s,drag_N"] + [
        f"{x},{scale * (tare['t2'] * x * x + tare['t1'] * x)}" for x in u]
    (root / "tare.csv").write_text("\n".join(lines) + "\n")


def _hull_table(path: Path, radius: float) -> None:
    x = np.linspace(0, 0.353, 41)
    r = radius * np.sqrt(np.clip(1 - (2 * x / 0.353 - 1) ** 2, 0, None))
    pd.DataFrame({"x_m": x, "r_m": r}).to_csv(path, index=False)


@pytest.mark.heavy
def test_an_edited_tare_table_or_hull_table_is_never_replayed(day_dir, tmp_path):
    root = tmp_path
    for name in ("run_sheet.csv", "truth.json"):
        (root / name).write_bytes((day_dir / name).read_bytes())
    os.symlink(day_dir / "data", root / "data")
    _tare_table(root, 1.0)
    _hull_table(root / "hull.csv", 0.025)
    extra = ('\n[tare]\nsource = "table"\ntable = "tare.csv"\n'
             '\n[vehicle]\nhull = "table"\nhull_table = "hull.csv"\nspeed_m_s = 1.0\n')
    protocol = _protocol(root, extra)
    out = root / "out"
    assert _process(protocol, out) == 0
    first = _coefficients(out)["X_u|u|"]
    pred = pd.read_csv(out / "predicted.csv").set_index("symbol")["value"]["Y_vdot"]
    recorded = json.loads((out / ".cache" / "day.json").read_text())["inputs"]
    assert str((root / "tare.csv").resolve()) in recorded
    assert str((root / "hull.csv").resolve()) in recorded
    assert _process(protocol, out) == 0  # unchanged: replayed
    _tare_table(root, 0.5)  # the mounting re-measured
    assert _process(protocol, out) == 0
    again = _coefficients(out)["X_u|u|"]
    assert again != pytest.approx(first, rel=1e-3)
    fresh = root / "fresh"
    assert _process(protocol, fresh, "--no-cache") == 0
    assert again == pytest.approx(_coefficients(fresh)["X_u|u|"], rel=1e-12)
    _hull_table(root / "hull.csv", 0.05)  # a fatter hull: more added mass
    assert _process(protocol, out) == 0
    pred2 = pd.read_csv(out / "predicted.csv").set_index("symbol")["value"]["Y_vdot"]
    assert pred2 < 2 * pred  # about 4 times: the sectional area goes with r²
    provenance = json.loads((out / "provenance.json").read_text())
    assert any(str(k).endswith("hull.csv") for k in json.dumps(provenance).split('"'))


def test_the_recorder_sees_every_way_of_reading_a_file(tmp_path):
    from towtank.runtime.reads import recording

    files = [tmp_path / f"f{i}.csv" for i in range(5)]
    for f in files:
        f.write_text("a,b\n1,2\n")
    with recording(skip=[tmp_path / "skip"]) as rec:
        open(files[0]).read()
        files[1].read_bytes()
        pd.read_csv(files[2])
        np.loadtxt(files[3], delimiter=",", skiprows=1)
        os.close(os.open(files[4], os.O_RDONLY))
        (tmp_path / "skip").mkdir()
        (tmp_path / "skip" / "x").write_text("written, not read")
        (tmp_path / "skip" / "x").read_text()
        (tmp_path / "w.txt").write_text("only written")
    assert set(rec.files) == {str(f) for f in files}


# ------------------------------------------- 3. the user's files are never taken for ours
#: Names of the user's own files that look like towtank's temporaries.
LOOKALIKES = (".out.notes", ".figures.old-mine", ".out.tmp-1", ".cachex")


def test_user_files_with_names_like_temporaries_are_kept(day, processed_out, tmp_path):
    """All the look-alike names in one folder, which the day's outputs are written into twice:
    each is kept as it was."""
    out = tmp_path / "out"
    _processed(processed_out, out)
    for name in LOOKALIKES:
        (out / name).write_text(f"mine: {name}")
    assert _process(day, out, "--no-cache") == 0
    assert _process(day, out, "--no-cache") == 0
    for name in LOOKALIKES:
        assert (out / name).is_file(), f"{name} was removed"
        assert (out / name).read_text() == f"mine: {name}", f"{name} was overwritten"


# ----------------------------------------------------------------- 4. two writers, one folder
@pytest.fixture(scope="session")
def two_days(trust_day, tmp_path_factory):
    """The session's processed day and another (the next seed), processed."""
    other = tmp_path_factory.mktemp("other")
    syn.make_hull_day(other, seed=SEED + 1, file_format="csv", sheet_format="csv")
    sections = syn.hull_protocol_sections(str(other), "out", sheet_format="csv")
    p = syn.write_protocol(tmp_path_factory.mktemp("p") / "p.toml", **sections)
    return [trust_day.day, towtank.process_day(p, jobs=1)]


def _folder_is_one_day(out: Path, alone: list[dict[str, bytes]]) -> None:
    data = read_manifest(out)
    assert data is not None and data["complete"]
    for rel, entries in data["files"].items():
        sha = hashlib.sha256((out / rel).read_bytes()).hexdigest()
        assert sha in {e["sha256"] for e in entries}, rel
    tables = {p.name: p.read_bytes() for p in out.glob("*.csv")}
    assert any(tables == {k: v for k, v in a.items() if k.endswith(".csv")} for a in alone)


@pytest.mark.heavy
def test_two_threads_writing_one_folder_never_mix(two_days, tmp_path):
    from towtank.report import write_outputs

    alone = []
    for i, d in enumerate(two_days):
        write_outputs(d, tmp_path / f"alone{i}", report=False)
        alone.append({p.name: p.read_bytes() for p in (tmp_path / f"alone{i}").glob("*.csv")})
    assert alone[0]["coefficients.csv"] != alone[1]["coefficients.csv"]
    out = tmp_path / "out"
    errors: list[BaseException] = []
    for _ in range(30):
        def write(d):
            try:
                write_outputs(d, out, report=False)
            except BaseException as exc:  # noqa: BLE001
                errors.append(exc)
        threads = [threading.Thread(target=write, args=(d,)) for d in two_days]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        assert not errors
        _folder_is_one_day(out, alone)
    assert not [p for p in tmp_path.iterdir() if ".tmp-" in p.name or ".old-" in p.name]


def test_a_second_writer_is_told_who_holds_the_folder(tmp_path):
    out = tmp_path / "out"
    code = ("import sys,time; from pathlib import Path; "
            "from towtank.runtime.manifest import output_lock\n"
            f"with output_lock(Path({str(out)!r})):\n"
            "    print('locked', flush=True); time.sleep(30)\n")
    holder = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "locked"
        with pytest.raises(towtank.ProtocolError) as err, output_lock(out, wait_s=0.3):
            pass
        assert f"process {holder.pid} is writing into {out}" in str(err.value)
    finally:
        holder.kill()
        holder.wait()
    assert lock_path(out).exists()  # a killed holder leaves its file ...
    with output_lock(out, wait_s=5):  # ... but the system released its lock
        assert lock_path(out).read_text().endswith(f"{os.getpid()}\n")
    assert not lock_path(out).exists()  # removed as it is let go


def test_a_lock_file_that_is_not_towtanks_is_never_written(tmp_path):
    out = tmp_path / "out"
    lock_path(out).write_text("my notes")
    with pytest.raises(towtank.ProtocolError, match="not towtank's lock file"), \
            output_lock(out):
        pass
    assert lock_path(out).read_text() == "my notes"


# ------------------------------------- 5. odd entries in the output folder hang nothing
def _in_process(*args: str, capsys: pytest.CaptureFixture[str], timeout: float
                ) -> subprocess.CompletedProcess:
    """``towtank ARGS`` run here within a hang bound, as :func:`run_in_child` reports it."""
    capsys.readouterr()
    with hang_bound(timeout):
        code = main(list(args))
    said = capsys.readouterr()
    return subprocess.CompletedProcess(["towtank", *args], code, said.out, said.err)


#: Odd entries that a regression could make towtank read without end (/dev/zero, a sparse
#: 12 GB file): their runs get a process of their own, whose memory a regression cannot take
#: from the tests (one child for both: :func:`own_process_runs`). The others (a FIFO, which a
#: hang bound interrupts) run here.
OWN_PROCESS = ("zero-link", "huge")


def _plant_odd(out: Path, odd: str) -> None:
    """Put the odd entry ``odd`` into the processed output folder ``out``."""
    cache = out / ".cache"
    if odd == "fifo":
        os.mkfifo(out / "pipe")
    elif odd == "zero-link":
        os.symlink("/dev/zero", out / "zeros")
    elif odd == "huge":
        with open(out / "big.bin", "wb") as fh:
            fh.truncate(12 << 30)  # sparse: 12 GB that take no disk
    elif odd == "cache-file":
        shutil.rmtree(cache)
        cache.write_text("not a folder")
    elif odd == "day-dir":
        (cache / "day.json").unlink()
        (cache / "day.json").mkdir()
    elif odd == "files-dir":
        (cache / "files.json").unlink()
        (cache / "files.json").mkdir()
    elif odd == "files-fifo":
        (cache / "files.json").unlink()
        (cache / "day.json").unlink()
        os.mkfifo(cache / "files.json")


def _odd_args(day: Path, out: Path) -> tuple[str, ...]:
    return (str(day), "--out", str(out), "-q", "--jobs", "1", "--no-report")


@pytest.fixture(scope="module")
def own_process_runs(day, processed_out, tmp_path_factory
                     ) -> dict[str, list[subprocess.CompletedProcess]]:
    """Each :data:`OWN_PROCESS` entry planted into a copy of the processed folder, and the
    day processed twice into each copy, all in one child process: odd -> its two runs."""
    commands = []
    for odd in OWN_PROCESS:
        out = tmp_path_factory.mktemp(f"odd-{odd}") / "out"
        _processed(processed_out, out)
        _plant_odd(out, odd)
        commands += [("process", *_odd_args(day, out))] * 2
    runs = run_in_child(commands, timeout=240)
    return {odd: runs[2 * i: 2 * i + 2] for i, odd in enumerate(OWN_PROCESS)}


@pytest.mark.heavy
@pytest.mark.parametrize("odd", ["fifo", "zero-link", "huge", "cache-file", "day-dir",
                                 "files-dir", "files-fifo"])
def test_odd_entries_in_the_output_folder_neither_hang_nor_crash(day, processed_out, tmp_path,
                                                                 odd, capsys, request):
    if odd in OWN_PROCESS:
        runs = request.getfixturevalue("own_process_runs")[odd]
    else:
        out = tmp_path / "out"
        _processed(processed_out, out)
        _plant_odd(out, odd)
        runs = [_in_process("process", *_odd_args(day, out), capsys=capsys, timeout=60)
                for _ in range(2)]
    assert len(runs) == 2
    for run in runs:
        assert run.returncode == 0, run.stderr
        assert "Traceback" not in run.stderr
    if odd == "cache-file":
        cache = tmp_path / "out" / ".cache"
        assert cache.read_text() == "not a folder"
        assert "is not a folder" in run.stderr or run.stderr == ""


def test_a_cache_link_is_not_followed(day, processed_out, tmp_path):
    out = tmp_path / "out"
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    _processed(processed_out, out)
    shutil.rmtree(out / ".cache")
    os.symlink(elsewhere, out / ".cache")
    assert _process(day, out) == 0
    assert _process(day, out) == 0
    assert list(elsewhere.iterdir()) == []
    assert (out / ".cache").is_symlink()


# ------------------------------------------------ 11. a manifest is never trusted unchecked
@pytest.mark.parametrize("files", [{"runs.csv": 5}, [1, 2], "x",
                                   {"runs.csv": [{"size": "1", "sha256": 3}]}, "deep"])
def test_a_corrupt_manifest_stops_the_day_in_one_sentence(day, processed_out, tmp_path, capsys,
                                                          files):
    out = tmp_path / "out"
    _processed(processed_out, out)
    before = (out / "runs.csv").read_bytes()
    data = json.loads((out / MANIFEST).read_text())
    if files == "deep":
        (out / MANIFEST).write_text('{"kind": "towtank output manifest", "files": '
                                    + "[" * 100000 + "]" * 100000 + "}")
    else:
        data["files"] = files
        (out / MANIFEST).write_text(json.dumps(data))
    capsys.readouterr()
    assert _process(day, out, "--no-cache") == 2
    err = capsys.readouterr().err
    assert "which towtank did not write" in err and err.count("\n") == 1
    assert (out / "runs.csv").read_bytes() == before


def _small_day(root: Path) -> Path:
    """A four-run hull day (two sting, two hull runs) in ``root``: its protocol."""
    plan = [syn.RunSpec(kind, 0.0, speed, 0.5) for kind in ("sting", "hull")
            for speed in (0.8, 1.6)]
    syn.make_hull_day(root, seed=3, file_format="csv", sheet_format="csv", runs=plan)
    return syn.write_protocol(root / "protocol.toml",
                              **syn.hull_protocol_sections(".", "out", sheet_format="csv"))


@pytest.mark.heavy
def test_simulate_files_stay_towtanks_after_process_rewrites_the_folder(tmp_path):
    repo = Path(__file__).resolve().parents[1]
    protocol = repo / "protocols" / "remus_vehicle.toml"
    out = tmp_path / "out"
    assert main(["predict", str(protocol), "--out", str(tmp_path / "remus")]) == 0
    sim = ["simulate", str(tmp_path / "remus" / "model.json"), "--manoeuvre", "turning",
           "--duration-s", "5", "--out", str(out)]
    assert main(sim) == 0
    (out / "notes.txt").write_text("mine")
    day_protocol = _small_day(tmp_path / "day")
    assert main(["process", str(day_protocol), "--out", str(out), "-q", "--no-report",
                 "--jobs", "1"]) == 0
    assert main(sim) == 0  # its files are still known as towtank's
    listed = read_manifest(out)["files"]
    assert "manoeuvre.csv" in listed and "runs.csv" in listed
    assert (out / "notes.txt").read_text() == "mine"


# ------------------------------- issue 23 item 5: every readable format is warned when unlisted
@pytest.mark.parametrize("name", ["forgotten.lvm", "forgotten.mat", "forgotten.h5",
                                  "forgotten.hdf5", "forgotten.h5m", "forgotten.txt",
                                  "sub/forgotten.dat.gz", "forgotten.tdms"])
def test_a_forgotten_run_file_of_any_format_is_named(tmp_path, name):
    from towtank.ingest.runsheet import unlisted_files

    data = tmp_path / "data"
    (data / "sub").mkdir(parents=True)
    (data / "run_001.csv").write_text("t\n")
    (data / name).write_bytes(b"x")
    (data / "photo.jpg").write_bytes(b"x")  # not a run file: not named
    sheet = pd.DataFrame({"file": ["run_001.csv"]})
    assert unlisted_files(sheet, data) == [name]
