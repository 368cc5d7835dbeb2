"""The speed-ups behind the campaign benchmark change nothing but the time.

The filter gives scipy's result bit for bit (even padding over two periods of the cut-off),
the settings key is the same hash as before, the
packed cache returns what was stored (and a damaged entry is a miss), the parallel map returns
the serial results in sheet order, and the day's fingerprint notices every kind of change.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import pickle
import signal
from concurrent.futures.process import BrokenProcessPool
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from scipy.signal import sosfiltfilt

from towtank import __version__
from towtank.ingest.protocol import ChannelMap, Processing
from towtank.ingest.readers import ReadOptions
from towtank.runtime import cache, manifest, parallel
from towtank.signal import conditioning


# ------------------------------------------------------------------------------------ filter
@pytest.mark.parametrize("n", [2, 3, 27, 28, 29, 500, 12_001])
@pytest.mark.parametrize("channels", [1, 3])
@pytest.mark.parametrize("design", [(1000.0, 4.0, 4), (200.0, 5.0, 2), (50.0, 20.0, 5)])
def test_lowpass_is_sosfiltfilt_bit_for_bit(n, channels, design):
    fs, cutoff, order = design
    x = np.cumsum(np.random.default_rng(n).standard_normal((n, channels)), axis=0) + 2.5
    sos = conditioning.butter_sos(cutoff, fs, order)
    padlen = min(n - 1, max(3 * (2 * sos.shape[0] + 1), int(2.0 * fs / cutoff)))
    expected = sosfiltfilt(sos, x, axis=0, padlen=padlen, padtype="even")
    got = conditioning.lowpass(x, fs, cutoff, order)
    assert got.shape == expected.shape
    assert np.array_equal(got, expected)
    one = conditioning.lowpass(x[:, 0], fs, cutoff, order)
    assert np.array_equal(one, sosfiltfilt(sos, x[:, 0], axis=0, padlen=padlen, padtype="even"))
    assert np.array_equal(x, np.cumsum(np.random.default_rng(n).standard_normal((n, channels)),
                                       axis=0) + 2.5)  # input untouched


def test_lowpass_other_dtypes_take_scipy_path():
    x = (np.arange(200, dtype=np.float32) % 7)[:, None]
    sos = conditioning.butter_sos(5.0, 100.0, 4)
    expected = sosfiltfilt(sos, x, axis=0, padlen=40, padtype="even")
    assert np.array_equal(conditioning.lowpass(x, 100.0, 5.0, 4), expected)


# ------------------------------------------------------------------------------ settings key
def _protocol(**processing):
    return SimpleNamespace(
        processing=replace(Processing(), **processing),
        channels={"drag": ChannelMap("Fx (V)", 20.0, 0.01), "time": ChannelMap("t")},
        read=ReadOptions(),
        balance=None,
    )


def _reference_key(protocol, row):
    """The settings key as first written: one json.dumps of the whole payload."""

    def num(x):
        return None if isinstance(x, float) and math.isnan(x) else x

    payload = {
        "format": cache.CACHE_FORMAT,
        "version": __version__,
        "processing": asdict(protocol.processing),
        "channels": {k: asdict(v) for k, v in sorted(protocol.channels.items())},
        "read": asdict(protocol.read),
        "balance": None,
        "file": str(row["file"]),
        "window": [num(row.get("window_start_s")), num(row.get("window_end_s"))],
        "nominal": [num(row.get("speed_nominal")), num(row.get("accel_nominal"))],
        "test": str(row.get("test", "")).strip().lower(),
    }
    text = json.dumps(payload, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:24]


@pytest.mark.parametrize("row", [
    {"file": "run_001.csv", "speed_nominal": 1.2, "accel_nominal": 0.5},
    {"file": "day 2/run_002.csv.gz", "speed_nominal": math.nan, "accel_nominal": 0.5,
     "window_start_s": 5.0, "window_end_s": 7.25},
    {"file": 'odd "name" \\ é\x00.tdms', "speed_nominal": np.float64(0.8)},
    {"file": "run_004.csv"},
    {"file": "run_005.csv", "test": " Accel"},
])
def test_settings_key_is_unchanged(row):
    p = _protocol()
    assert cache.settings_key(p, row) == _reference_key(p, row)
    other = _protocol(cutoff_hz=7.0)  # a new protocol object: its own settings
    assert cache.settings_key(other, row) == _reference_key(other, row)
    assert cache.settings_key(other, row) != cache.settings_key(p, row)


# ------------------------------------------------------------------------------------ cache
def _sha(i):
    return hashlib.sha256(str(i).encode()).hexdigest()


@dataclass
class _Red:
    run: int
    samples: dict[str, np.ndarray]
    notes: list[str]


def _red(i):
    return _Red(i, {"U": np.linspace(0, 1, 30) * i}, [f"run {i}"])


def test_cache_round_trip_and_index(tmp_path, monkeypatch):
    monkeypatch.setattr(cache, "PACK_ENTRIES", 4)
    monkeypatch.setattr(cache, "PACK_SECONDS", 0.0)
    data = tmp_path / "data"
    data.mkdir()
    files = []
    for i in range(10):
        f = data / f"run_{i:03d}.csv"
        f.write_text(f"t,u\n{i},1\n")
        files.append(f)
    c = cache.RunCache(tmp_path / ".cache", _Red)
    for i, f in enumerate(files):
        assert c.known_sha(f) is None
        c.put(_sha(i), "k", _red(i))
        c.remember_sha(f, _sha(i))
        assert c.get(_sha(i), "k").run == i  # readable before the flush
    c.flush()
    c2 = cache.RunCache(tmp_path / ".cache", _Red)
    for i, f in enumerate(files):
        assert c2.known_sha(f) == _sha(i)
        got = c2.get(c2.known_sha(f), "k")
        assert got.run == i and np.array_equal(got.samples["U"], _red(i).samples["U"])
    assert c2.get(_sha(3), "other-settings") is None
    # a file that changed (size or mtime) is unknown; the index holds real paths
    files[2].write_text("t,u\n2,1\n9,9\n")
    assert c2.known_sha(files[2]) is None
    link = tmp_path / "link.csv"
    os.symlink(files[1], link)
    assert c2.known_sha(link) == _sha(1)
    assert c2.known_sha(tmp_path / "data" / ".." / "data" / "run_005.csv") == _sha(5)


def test_damaged_cache_is_a_miss(tmp_path):
    c = cache.RunCache(tmp_path, _Red)
    c.put("a" * 64, "k", _red(1))
    c.put("b" * 64, "k", _red(2))
    c.flush()
    (pack,) = (tmp_path / "runs").glob("pack-*.bin")
    raw = bytearray(pack.read_bytes())
    raw[5] ^= 0xFF
    pack.write_bytes(bytes(raw))
    c2 = cache.RunCache(tmp_path, _Red)
    assert c2.get("a" * 64, "k") is None
    assert c2.get("b" * 64, "k").run == 2
    (tmp_path / "files.json").write_text("{ not json")
    assert cache.RunCache(tmp_path, _Red).get("b" * 64, "k") is None


def test_cache_never_unpickles_the_one_file_per_entry_layout(tmp_path):
    """Earlier versions kept pickles (runs/<entry>.pkl): never read now, whatever they hold;
    an index of an earlier format (records without ctime and inode) is not trusted."""
    old = tmp_path / "runs" / f"{'c' * 32}-key.pkl"
    old.parent.mkdir(parents=True)
    old.write_bytes(pickle.dumps(_red(7)))
    f = tmp_path / "run.csv"
    f.write_text("x\n1\n")
    st = f.stat()
    (tmp_path / "files.json").write_text(json.dumps({str(f.resolve()): [st.st_size,
                                                                         st.st_mtime_ns,
                                                                         "c" * 64]}))
    c = cache.RunCache(tmp_path, _Red)
    assert c.known_sha(f) is None
    assert c.get("c" * 64, "key") is None
    c.remember_sha(f, "c" * 64)
    assert c.known_sha(f) == "c" * 64


def test_packs_are_merged(tmp_path, monkeypatch):
    monkeypatch.setattr(cache, "MAX_PACKS", 3)
    for i in range(6):  # six processes, one pack each
        c = cache.RunCache(tmp_path, _Red)
        c.put(_sha(i), "k", _red(i))
        c.flush()
    assert len(list((tmp_path / "runs").glob("pack-*.bin"))) <= 3
    c = cache.RunCache(tmp_path, _Red)
    assert [c.get(_sha(i), "k").run for i in range(6)] == list(range(6))


# ---------------------------------------------------------------------------------- parallel
def _square(protocol, rec, *, debug=False):
    if rec["x"] < 0 and debug:
        raise ValueError("negative")
    return rec["x"] ** 2 + protocol["offset"], os.getpid()


@pytest.mark.parametrize("n", [0, 1, 2, 3, 37])
def test_map_runs_keeps_sheet_order(n):
    records = [{"x": i} for i in range(n)]
    serial = [r for r, _ in parallel.map_runs(_square, {"offset": 1}, records, jobs=1)]
    par = list(parallel.map_runs(_square, {"offset": 1}, records, jobs=2))
    assert [r for r, _ in par] == serial == [i * i + 1 for i in range(n)]
    pids = {pid for _, pid in par}
    if n >= parallel.MIN_RECORDS_FOR_POOL:
        assert os.getpid() not in pids and len(pids) >= 1  # all in worker processes
    else:
        assert pids <= {os.getpid()}  # a handful: not worth starting workers
    assert "pool" not in parallel._prestarted


def test_prestarted_pool_is_used_once_and_closed():
    assert parallel.prestart(2)
    records = [{"x": i} for i in range(3)]
    par = list(parallel.map_runs(_square, {"offset": 0}, records, jobs=2))
    assert [r for r, _ in par] == [0, 1, 4]
    assert os.getpid() not in {pid for _, pid in par}  # the prestarted workers did them
    assert "pool" not in parallel._prestarted
    assert parallel.prestart(2)
    parallel.discard_prestarted()
    assert "pool" not in parallel._prestarted
    assert not parallel.prestart(1)  # one job: nothing to start


def test_map_runs_raises_worker_errors_in_debug():
    records = [{"x": 1}, {"x": 2}, {"x": -1}, {"x": 3}] * 5
    with pytest.raises(ValueError, match="negative"):
        list(parallel.map_runs(_square, {"offset": 0}, records, jobs=2, debug=True))
    assert "pool" not in parallel._prestarted


def _die_on_seven(protocol, rec, *, debug=False):
    if rec["x"] == 7:
        os.kill(os.getpid(), signal.SIGKILL)  # a worker killed (out of memory, a crash)
    return rec["x"] ** 2, os.getpid()


def test_a_dying_worker_loses_only_its_record():
    records = [{"x": i} for i in range(20)]
    out = list(parallel.map_runs(_die_on_seven, None, records, jobs=2,
                                 on_crash=lambda rec: ("lost", rec["x"])))
    assert [r for r, _ in out] == [i * i if i != 7 else "lost" for i in range(20)]
    assert out[7] == ("lost", 7)
    with pytest.raises(BrokenProcessPool):
        list(parallel.map_runs(_die_on_seven, None, records, jobs=2))


def test_workers_that_cannot_start_leave_the_records_to_this_process(monkeypatch):
    import multiprocessing as mp

    real = mp.get_context("forkserver")

    class NoProcesses:  # a start method whose processes never start (no /tmp for the socket)
        def __getattr__(self, name):
            return getattr(real, name)

        def Process(self, *args, **kwargs):  # noqa: N802 - the multiprocessing name
            raise OSError("cannot start a process here")

    monkeypatch.setattr(parallel, "_context", lambda: NoProcesses())
    records = [{"x": i} for i in range(20)]
    out = list(parallel.map_runs(_square, {"offset": 0}, records, jobs=2))
    assert [r for r, _ in out] == [i * i for i in range(20)]
    assert {pid for _, pid in out} == {os.getpid()}


def test_background_loading_imports_and_survives_a_missing_module():
    thread = parallel.load_in_background(["colorsys", "towtank_no_such_module"])
    thread.join(timeout=30)
    assert not thread.is_alive()
    import sys

    assert "colorsys" in sys.modules


# ---------------------------------------------------------------------------------- the day
def _day(tmp_path: Path) -> SimpleNamespace:
    (tmp_path / "data").mkdir()
    for i in range(3):
        (tmp_path / "data" / f"run_{i}.csv").write_text(f"t\n{i}\n")
    (tmp_path / "sheet.csv").write_text("run,file\n")
    (tmp_path / "protocol.toml").write_text("[campaign]\n")
    out = tmp_path / "out"
    out.mkdir()
    (out / "runs.csv").write_text("run\n1\n")
    manifest.write_manifest(out, manifest.describe(out, {"runs.csv"}))
    campaign = SimpleNamespace(run_sheet=tmp_path / "sheet.csv", data_dir=tmp_path / "data",
                               reference="remus")
    return SimpleNamespace(path=tmp_path / "protocol.toml", campaign=campaign)


def test_day_stamp_replays_only_an_unchanged_day(tmp_path):
    p = _day(tmp_path)
    out = tmp_path / "out"

    def stamp(**options):
        return cache.DayStamp(out / ".cache", p, out, options or {"report": False})

    assert stamp().replay() is None
    stamp().record(1, "summary\n")
    assert stamp().replay() == (1, "summary\n")
    assert stamp(report=True).replay() is None  # other options
    (out / "runs.csv").write_text("run\n2\n")  # an output edited
    assert stamp().replay() is None
    manifest.write_manifest(out, manifest.describe(out, {"runs.csv"}))
    stamp().record(0, "again\n")
    assert stamp().replay() == (0, "again\n")
    f = tmp_path / "data" / "run_1.csv"
    st = f.stat()
    os.utime(f, ns=(st.st_atime_ns, st.st_mtime_ns + 1))  # a data file touched
    assert stamp().replay() is None
    stamp().record(0, "x\n")
    (tmp_path / "sheet.csv").write_text("run,file\n1,run_1.csv\n")  # the sheet edited
    assert stamp().replay() is None
    stamp().record(0, "x\n")
    (tmp_path / "data" / "new.csv").write_text("t\n")  # a file added
    assert stamp().replay() is None


# ------------------------------------------------------------------ what each process loads
REPO = Path(__file__).resolve().parents[2]
_LOADED = """
import sys
from pathlib import Path
from towtank.ingest.protocol import load_protocol
{body}
print("LOADED:", *(m for m in ("pandas", "statsmodels", "matplotlib") if m in sys.modules))
"""


def _loaded(body: str) -> set[str]:
    import subprocess
    import sys

    code = _LOADED.format(body=body)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         cwd=REPO, check=True)
    last = out.stdout.strip().splitlines()[-1]
    assert last.startswith("LOADED:")
    return set(last.split()[1:])


@pytest.mark.heavy
def test_a_reduction_worker_never_loads_pandas():
    """pyarrow's to_numpy loads pandas; in every worker that cost 0.3 s (see ingest)."""
    loaded = _loaded(
        "from towtank.reduce.run import reduce_record\n"
        "p = load_protocol('protocols/sut2_hull.toml')\n"
        "run, red, reason, _ = reduce_record(p, {'run': 5, 'file': 'run_005.csv.gz'})\n"
        "assert red is not None, reason\n"
    )
    assert loaded == set()


@pytest.mark.heavy
def test_inspect_loads_neither_pandas_nor_statsmodels():
    loaded = _loaded(
        "from towtank.commands.cli import main\n"
        "import tempfile\n"
        "png = Path(tempfile.mkdtemp()) / 'x.png'\n"
        "assert main(['inspect', 'sample_runs/sut2_hull/data/run_005.csv.gz', '--protocol',\n"
        "             'protocols/sut2_hull.toml', '--png', str(png)]) == 0\n"
    )
    assert loaded == {"matplotlib"}
