"""Issue 33, items 2, 4 and 11: every file the protocol names is in the replay record wherever
it lives, one output lock whatever name the folder is given, and a cache record or manifest
that is well typed but no sane record is a miss, never a crash."""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import io
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import threading
import zlib
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import towtank
from towtank.commands.cli import main
from towtank.reduce.run import PHASE_ACCEL, RunReduction
from towtank.reduce.sanity import reduction_problem, sane_reduction
from towtank.runtime import manifest, records
from towtank.runtime.cache import DayStamp
from towtank.runtime.outfolder import OUTPUT_NAMES
from towtank.runtime.reads import recorded, recording
from towtank.testing import synthetic as syn

REPO = Path(__file__).resolve().parents[1]
#: Enough examples to plant every kind of insanity, few enough that a day's processing per
#: example stays within seconds.
DAY_EXAMPLES = settings(max_examples=6, suppress_health_check=[HealthCheck.too_slow])


@pytest.fixture(scope="session")
def day_dir(trust_day) -> Path:
    """The session's synthetic day (seed 5, CSV run files and sheet: tests/conftest.py)."""
    return trust_day.dir


def _protocol(day_dir: Path, path: Path, extra: str = "") -> Path:
    sections = syn.hull_protocol_sections(str(day_dir), "out", sheet_format="csv")
    protocol = syn.write_protocol(path, **sections)
    protocol.write_text(protocol.read_text() + extra)
    return protocol


def _process(protocol: Path, out: Path, *extra: str) -> int:
    return main(["process", str(protocol), "--out", str(out), "-q", "--jobs", "1",
                 "--no-report", *extra])


def _tables(out: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(out.glob("*.csv"))}


@pytest.fixture(scope="session")
def processed(trust_day) -> tuple[Path, Path, dict[str, bytes]]:
    """(protocol, output folder with its cache, the tables of a fresh run): the session's
    processed day (tests/conftest.py), which the tests only read or copy."""
    return trust_day.protocol, trust_day.out, _tables(trust_day.out)


def _copy(processed, tmp_path_factory, name: str) -> tuple[Path, Path, dict[str, bytes]]:
    """``processed`` with a copy of its output folder of its own, for a test that plants
    things into it."""
    protocol, out, fresh = processed
    copy = tmp_path_factory.mktemp(name) / "out"
    shutil.copytree(out, copy, symlinks=True)
    return protocol, copy, fresh


@pytest.fixture(scope="session")
def own_copy(processed, tmp_path_factory) -> Callable[[str], tuple[Path, Path, dict]]:
    """``own_copy(name)``: :func:`_copy` made once per name, kept across a property test's
    examples."""
    copies: dict[str, tuple[Path, Path, dict]] = {}

    def get(name: str) -> tuple[Path, Path, dict]:
        if name not in copies:
            copies[name] = _copy(processed, tmp_path_factory, name)
        return copies[name]
    return get


# ---------------------------------------- 2. a file the protocol names, wherever it lives
@pytest.mark.parametrize("name", [
    "/run/media/lab/STICK/tare.csv", "/run/user/1000/gvfs/smb-share/day3/hull.csv",
    "/etc/towtank/tare.csv", "/usr/local/share/lab/tare.csv", "/usr/share/lab/tare.csv",
    "/mnt/nas/day3/run_001.csv", "/media/lab/tare.csv", "/lib/lab/tare.csv",
    "/opt/lab/tare.csv", "/srv/tank/tare.csv",
])
def test_the_replay_rule_records_a_file_wherever_it_lives(name):
    assert recorded(name)


def test_the_replay_rule_leaves_out_only_python_towtank_and_the_kernel(tmp_path):
    import email
    import json as stdlib_module

    import pandas

    for module in (stdlib_module, email, np, pandas, towtank):
        assert not recorded(os.path.abspath(module.__file__))
    assert not recorded("/proc/self/status") and not recorded("/sys/fs/cgroup/cpu.max")
    assert not recorded(str(tmp_path / ".cache" / "day.json"), skip=(str(tmp_path / ".cache"),))
    assert recorded(str(tmp_path / "tare.csv"), skip=(str(tmp_path / ".cache"),))


def test_a_module_compiled_under_pythons_bytecode_folder_is_no_input(tmp_path, monkeypatch):
    """PYTHONPYCACHEPREFIX: Python reads a module imported during the day from its own
    bytecode folder, which is then not a file of the day (a pandas module imported lazily
    was listed in provenance.json's inputs, and the day's outputs differed with the moment of
    that first import)."""
    cache = tmp_path / "pycache"
    compiled = cache / "opt" / "venv" / "pandas" / "core" / "reshape.cpython-311.pyc"
    assert recorded(str(compiled))  # no bytecode folder: any file is recorded, as before
    monkeypatch.setattr(sys, "pycache_prefix", str(cache))
    assert not recorded(str(compiled))
    assert recorded(str(tmp_path / "tare.csv"))
    assert recorded(str(tmp_path / "pycache-notes.csv"))  # a name that only begins the same


def test_a_day_imports_through_the_bytecode_folder_and_records_only_its_files(tmp_path):
    """The whole rule in a process of its own that imports a module during the recording
    from PYTHONPYCACHEPREFIX's folder (as a lazy import of a library does during a day)."""
    src, cache = tmp_path / "src", tmp_path / "pycache"
    src.mkdir()
    (src / "late_module.py").write_text("VALUE = 1\n")
    (tmp_path / "tare.csv").write_text("speed_m_s,drag_N\n1,2\n")
    code = (
        "import sys; sys.path.insert(0, sys.argv[1])\n"
        "import late_module\n"  # compiled into the bytecode folder
        "del sys.modules['late_module']\n"
        "from towtank.runtime.reads import Recorder\n"
        "rec = Recorder([]).start()\n"
        "import late_module\n"  # read from the bytecode folder during the recording
        "open(sys.argv[2]).read()\n"
        "print(sorted(rec.stop()))\n")
    root = str(Path(__file__).resolve().parents[1])
    env = {**os.environ, "PYTHONPYCACHEPREFIX": str(cache),
           "PYTHONPATH": os.pathsep.join(filter(None, [root, os.environ.get("PYTHONPATH")]))}
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    done = subprocess.run([sys.executable, "-c", code, str(src), str(tmp_path / "tare.csv")],
                          env=env, capture_output=True, text=True, timeout=120, check=True)
    assert list(cache.rglob("late_module*.pyc"))  # the import went through the folder
    assert done.stdout.strip() == repr([str(tmp_path / "tare.csv")])


@pytest.fixture
def stick() -> Iterator[Path]:
    """A folder under /run/media, where Fedora and Arch mount a USB stick (made only where
    /run is writable; removed after, /run/media too when this made it)."""
    media = Path("/run/media")
    made = not media.exists()
    try:
        media.mkdir(exist_ok=True)
        folder = Path(tempfile.mkdtemp(prefix="towtank-test-", dir=media))
    except OSError:
        pytest.skip("/run/media cannot be written here (the rule is tested directly above)")
    try:
        yield folder
    finally:
        shutil.rmtree(folder, ignore_errors=True)
        if made:
            with contextlib.suppress(OSError):
                media.rmdir()


def _tare_table(day_dir: Path, path: Path, scale: float) -> None:
    """The day's tare as a table, every number written at one width: any scale gives a
    file of the same size."""
    tare = json.loads((day_dir / "truth.json").read_text())["tares"]["A"]
    rows = [f"{u:.3f},{scale * (tare['t2'] * u * u + tare['t1'] * u):+.9e}"
            for u in np.linspace(0.2, 2.2, 11)]
    path.write_text("speed_m_s,drag_N\n" + "\n".join(rows) + "\n")


def _drag_coefficient(out: Path) -> float:
    import pandas as pd

    return float(pd.read_csv(out / "coefficients.csv").set_index("symbol")["value"]["X_u|u|"])


@pytest.mark.heavy
def test_an_edited_tare_table_on_a_usb_stick_is_never_replayed(day_dir, stick, tmp_path):
    table = stick / "tare.csv"
    _tare_table(day_dir, table, 1.0)
    protocol = _protocol(day_dir, tmp_path / "protocol.toml",
                         f'\n[tare]\nsource = "table"\ntable = "{table}"\n')
    out = tmp_path / "out"
    assert _process(protocol, out) == 0
    first = _drag_coefficient(out)
    assert str(table) in json.loads((out / ".cache" / "day.json").read_text())["inputs"]
    before = table.stat()
    _tare_table(day_dir, table, 3.0)  # the mounting re-measured: same size, same time
    os.utime(table, ns=(before.st_atime_ns, before.st_mtime_ns))
    assert (table.stat().st_size, table.stat().st_mtime_ns) == (before.st_size,
                                                                before.st_mtime_ns)
    assert _process(protocol, out) == 0
    again = _drag_coefficient(out)
    assert again != pytest.approx(first, rel=1e-3)
    assert _process(protocol, tmp_path / "fresh", "--no-cache") == 0
    assert again == pytest.approx(_drag_coefficient(tmp_path / "fresh"), rel=1e-12)
    inputs = json.loads((out / "provenance.json").read_text())["inputs"]
    sha = hashlib.sha256(table.read_bytes()).hexdigest()
    assert {"path": str(table), "sha256": sha} in inputs


def test_the_recorder_keeps_a_file_under_a_system_folder(stick):
    (stick / "hull.csv").write_text("x_m,r_m\n0,0\n")
    with recording() as rec:
        (stick / "hull.csv").read_text()
    assert list(rec.files) == [str(stick / "hull.csv")]


# ------------------------------------------------------------ 4. one output lock, one name
@contextlib.contextmanager
def _held(folder: Path) -> Iterator[None]:
    """Hold ``folder``'s output lock (as process does, through the same function) in another
    thread while the block runs."""
    ready, release = threading.Event(), threading.Event()

    def hold() -> None:
        with manifest.output_lock(folder):
            ready.set()
            release.wait(60)

    holder = threading.Thread(target=hold, daemon=True)
    holder.start()
    assert ready.wait(30)
    try:
        yield
    finally:
        release.set()
        holder.join(30)


@pytest.fixture(scope="session")
def vehicle_inputs(tmp_path_factory) -> dict[str, Path]:
    """model.json of REMUS and of the glider, and a short rudder-sine record of REMUS."""
    from towtank.vehicle.simulate import simulate

    root = tmp_path_factory.mktemp("vehicles")
    for name, protocol in (("remus", "remus_vehicle"), ("glider", "glider_parametric")):
        assert main(["predict", str(REPO / "protocols" / f"{protocol}.toml"),
                     "--out", str(root / name)]) == 0
    remus = json.loads((root / "remus" / "model.json").read_text())
    remus["buoyancy_N"] = remus["weight_N"]
    (root / "neutral.json").write_text(json.dumps(remus))
    log = simulate(remus, "sine", 1.5, rudder_deg=10.0, period_s=4.0, duration_s=8.0,
                   sample_hz=5.0)
    log.to_csv(root / "sine.csv", index=False)
    return {"remus": root / "remus" / "model.json", "glider": root / "glider" / "model.json",
            "neutral": root / "neutral.json", "log": root / "sine.csv"}


def _commands(protocol: Path, v: dict[str, Path]) -> dict[str, list[str]]:
    """Every command that writes an output folder, without its --out."""
    return {
        "process": ["process", str(protocol), "-q", "--jobs", "1", "--no-report"],
        "predict": ["predict", str(REPO / "protocols" / "remus_vehicle.toml")],
        "simulate": ["simulate", str(v["neutral"]), "--manoeuvre", "turning", "--duration-s",
                     "0.5"],
        "steady": ["steady", str(v["glider"]), "--ballast-cc", "-200", "--pitch-deg", "-30"],
        "identify": ["identify", str(v["neutral"]), str(v["log"]), "--estimate", "N_ur",
                     "--method", "ls"],
        "scale": ["scale", str(protocol), "--speeds", "5"],
    }


def _outputs(folder: Path) -> dict[str, tuple[int, int]]:
    """(size, mtime_ns) of every entry of ``folder`` but the cache and watch's state."""
    return {str(p.relative_to(folder)): (p.lstat().st_size, p.lstat().st_mtime_ns)
            for p in folder.rglob("*")
            if p.relative_to(folder).parts[0] not in (".cache", ".live")}


@pytest.fixture
def linked(processed, tmp_path_factory, monkeypatch) -> tuple[Path, Path]:
    """(out, olink): a copy of the processed day's output folder and a link to it; a second
    writer waits 0.2 s for the lock."""
    folder = _copy(processed, tmp_path_factory, "locked")[1]
    os.symlink(folder, folder.parent / "olink")
    monkeypatch.setattr(manifest, "LOCK_WAIT_S", 0.2)
    return folder, folder.parent / "olink"


@pytest.mark.heavy
@pytest.mark.parametrize("command", ["process", "predict", "simulate", "steady", "identify",
                                     "scale", "synth"])
def test_a_command_given_a_link_to_a_locked_folder_waits_for_its_lock(
        processed, vehicle_inputs, linked, capsys, command, no_command_figures):
    folder, link = linked
    if command == "synth":
        args = ["synth", str(link), "--force"]
    else:
        args = [*_commands(processed[0], vehicle_inputs)[command], "--out", str(link)]
    before = _outputs(folder)
    capsys.readouterr()
    with _held(folder):
        assert main(args) == 2
    said = [line for line in capsys.readouterr().err.splitlines() if "towtank:" in line]
    assert len(said) == 1 and f"process {os.getpid()} is writing into {folder}" in said[0]
    assert _outputs(folder) == before
    assert main(args) == 0  # the lock let go: the same command writes


def test_watch_given_a_link_to_a_locked_folder_writes_nothing(processed, linked):
    from towtank.ingest.protocol import load_protocol
    from towtank.live.session import WatchSession

    folder, link = linked
    before = _outputs(folder)
    said: list[str] = []
    session = WatchSession(load_protocol(processed[0]), link, jobs=1, report=False,
                           echo=said.append, live_figures=False)
    try:
        with _held(folder):
            session.step()
    finally:
        session.close()
    assert any(f"is writing into {folder}" in line for line in said), said
    assert _outputs(folder) == before


def test_the_lock_is_named_one_way_only():
    """The lock file's name is made in one place (:func:`manifest.lock_path`), from the
    folder's one name (:func:`manifest.lock_target`); no module names it from another path
    (``absolute()`` keeps a link's own name) nor takes a lock by other means."""
    import ast
    import inspect

    package = Path(towtank.__file__).parent
    for path in package.rglob("*.py"):
        text = path.read_text(encoding="utf-8")
        where = path.relative_to(package).as_posix()
        if where != "runtime/manifest.py":
            assert "towtank-lock" not in text and "flock(" not in text, where
        for line in text.splitlines():
            if re.search(r"\b(output_lock|lock_path|lock_target)\(", line):
                assert ".absolute()" not in line and ".resolve()" not in line, (where, line)
    for func in (manifest.output_lock, manifest.lock_path):
        tree = ast.parse(inspect.getsource(inspect.unwrap(func)).lstrip())
        calls = {node.func.attr if isinstance(node.func, ast.Attribute) else
                 getattr(node.func, "id", "") for node in ast.walk(tree)
                 if isinstance(node, ast.Call)}
        assert "lock_target" in calls and not calls & {"absolute", "resolve", "realpath"}
    folder = Path("o")
    assert manifest.lock_target(folder) == folder.resolve()


# ------------------------------------------------- 11. a well-typed record that is no record
def _entries(cache: Path) -> dict[str, list]:
    return json.loads((cache / "files.json").read_text())["entries"]


def _record(cache: Path, loc: list) -> bytes:
    pack, offset, length, _ = loc
    return (cache / "runs" / pack).read_bytes()[offset:offset + length]


@pytest.fixture(scope="session")
def reductions(processed) -> list[RunReduction]:
    cache = processed[1] / ".cache"
    return [records.from_bytes(_record(cache, loc), RunReduction)
            for loc in _entries(cache).values()]


BAD_FLOATS = st.sampled_from([math.nan, math.inf, -math.inf])
Change = Callable[[RunReduction], RunReduction]


def _with(**values) -> Change:
    return lambda red: dataclasses.replace(red, **values)


def _column(table: str, column: str, make: Callable[[np.ndarray], np.ndarray]) -> Change:
    def change(red: RunReduction) -> RunReduction:
        tab = dict(getattr(red, table))
        tab[column] = make(tab[column])
        return dataclasses.replace(red, **{table: tab})
    return change


def _at(i: int, value: float) -> Callable[[np.ndarray], np.ndarray]:
    def put(x: np.ndarray) -> np.ndarray:
        x = x.copy()
        x[i % x.size] = value
        return x
    return put


@st.composite
def insane(draw) -> Change:
    """A change that keeps a reduction well typed (records.from_bytes reads it back) but
    makes it one no reduction can be."""
    kind = draw(st.sampled_from([
        "not finite", "negative", "count", "regressor", "accel", "lift", "window", "dtype",
        "value", "ragged", "columns", "phase", "empty", "tare", "speed", "units", "series"]))
    i = draw(st.integers(0, 10_000))
    if kind == "not finite":
        name = draw(st.sampled_from(["fs", "duration_s", "speed_level", "speed_mean",
                                     "speed_std", "zero_drag", "drift_drag", "drag_mean_raw",
                                     "drag_std"]))
        return _with(**{name: draw(BAD_FLOATS)})
    if kind == "negative":
        name = draw(st.sampled_from(["fs", "duration_s", "speed_std", "drag_std"]))
        return _with(**{name: -draw(st.floats(1e-9, 1e9))})
    if kind == "count":
        bad = draw(st.sampled_from([-1, 0, 1, -(2**40), 2**62]))
        return lambda red: dataclasses.replace(red, n_samples=bad if bad != 2**62
                                               else 2 * red.n_samples + 100)
    if kind == "regressor":
        value = draw(BAD_FLOATS)
        return lambda red: dataclasses.replace(red, steady_regressors=tuple(
            value if k == i % 3 else x for k, x in enumerate(red.steady_regressors)))
    if kind == "accel":  # a mean where no acceleration was sampled, or none where one was
        value = draw(st.sampled_from([math.inf, -math.inf, 0.5]))
        return lambda red: dataclasses.replace(
            red, accel_mean=math.nan if math.isfinite(red.accel_mean) else value)
    if kind == "lift":
        name = draw(st.sampled_from(["zero_lift", "drift_lift", "lift_mean_raw", "has_lift"]))
        if name == "has_lift":
            return lambda red: dataclasses.replace(red, has_lift=not red.has_lift)
        return _with(**{name: draw(BAD_FLOATS)})  # the day's runs all have lift
    if kind == "window":
        how = draw(st.sampled_from(["none", "reversed", "nan", "drop", "extra"]))

        def window(red: RunReduction) -> RunReduction:
            w = dict(red.windows)
            if how == "none":
                w["steady"] = None
            elif how == "reversed":
                a, b = w["steady"]
                w["steady"] = (b + 1.0, a)
            elif how == "nan":
                w["steady"] = (w["steady"][0], math.nan)
            elif how == "drop":
                del w["decel"]
            else:
                w["cruise"] = (0.0, 1.0)
            return dataclasses.replace(red, windows=w)
        return window
    table = draw(st.sampled_from(["samples", "thumb"]))
    column = draw(st.sampled_from(["t", "U", "a", "drag", "lift"]))
    if kind == "dtype":
        to = draw(st.sampled_from([bool, np.int64, np.float32, np.uint8]))
        return _column(table, column, lambda x: x.astype(to))
    if kind == "value":
        # NaN is a thumbnail's "no speed known" (a run at its set speed), never infinity
        nan_ok = table == "thumb" and column in ("U", "a")
        value = draw(st.sampled_from([math.inf, -math.inf] if nan_ok else
                                     [math.nan, math.inf, -math.inf]))
        return _column(table, column, _at(i, value))
    if kind == "ragged":
        return _column(table, column, lambda x: x[:-1])
    if kind == "columns":
        drop = draw(st.booleans())

        def columns(red: RunReduction) -> RunReduction:
            tab = dict(getattr(red, table))
            if drop:
                del tab[column]
            else:
                tab["extra"] = tab[column].copy()
            return dataclasses.replace(red, **{table: tab})
        return columns
    if kind == "phase":
        value = draw(st.sampled_from([-1, 2, 7, 127]))
        return _column("samples", "phase", _at(i, value))
    if kind == "empty":
        return lambda red: dataclasses.replace(red, **{table: {
            k: v[:0] for k, v in getattr(red, table).items()}})
    if kind == "tare":
        what = draw(st.sampled_from(["tare_drag", "tare_lift", "tare_group", "drag_mean",
                                     "lift_mean"]))
        return _with(**{what: "A" if what == "tare_group" else draw(st.floats(0.1, 10.0))})
    if kind == "speed":
        what = draw(st.sampled_from(["source", "u"]))
        return _with(**({"speed_source": "guessed"} if what == "source" else
                        {"speed_u": draw(st.floats(0.0, 1.0))}))
    if kind == "units":
        return lambda red: dataclasses.replace(red, units={
            **red.units, "drag": ("N", "guessed")})
    return lambda red: dataclasses.replace(red, series=dict(red.samples))


def test_every_fresh_reduction_is_sane(reductions):
    assert len(reductions) > 30 and all(r.has_lift for r in reductions)
    assert [reduction_problem(r) for r in reductions] == [None] * len(reductions)


@pytest.mark.parametrize("variant", ["no lift", "nominal speed", "whole series"])
def test_fresh_reductions_of_other_kinds_are_sane(day_dir, tmp_path, variant):
    from towtank.ingest.protocol import load_protocol
    from towtank.reduce.run import reduce_record

    sections = syn.hull_protocol_sections(str(day_dir), "out", sheet_format="csv")
    data = day_dir / "data"
    if variant == "no lift":
        del sections["channels"]["lift"]
    elif variant == "nominal speed":
        import pandas as pd

        data = tmp_path / "data"
        data.mkdir()
        for name in ("run_012.csv", "run_015.csv"):
            frame = pd.read_csv(day_dir / "data" / name)
            frame.drop(columns=[sections["channels"]["speed"]["column"]]).to_csv(
                data / name, index=False)
        del sections["channels"]["speed"]
        sections["processing"] = {**sections.get("processing", {}), "speed_source": "nominal"}
    sections["campaign"]["data_dir"] = str(data)
    protocol = load_protocol(syn.write_protocol(tmp_path / "p.toml", **sections))
    for run, name in ((12, "run_012.csv"), (15, "run_015.csv")):
        row = {"run": run, "file": name, "speed_nominal": 1.2}
        _, red, reason, _ = reduce_record(protocol, row, keep_series=variant == "whole series")
        assert reason is None, reason
        assert reduction_problem(red) is None
        assert (red.speed_source == "nominal") == (variant == "nominal speed")
        assert red.has_lift == (variant != "no lift")


@pytest.mark.heavy
@settings(max_examples=300)
@given(data=st.data())
def test_a_well_typed_insane_record_is_found_out(reductions, data):
    red = data.draw(st.sampled_from(reductions))
    change = data.draw(insane())
    # planted as bytes and read back: the types are right, only the values are wrong
    planted = records.from_bytes(records.to_bytes(change(red)), RunReduction)
    assert reduction_problem(planted) is not None
    assert not sane_reduction(planted)


def _plant(cache: Path, changes: dict[str, Change]) -> None:
    """Replace the cache's records named in ``changes`` by their changed selves (one new
    pack, the index pointing at it) and drop the replay record."""
    index = json.loads((cache / "files.json").read_text())
    pack, data = "pack-1-1.bin", b""
    for name, change in changes.items():
        red = records.from_bytes(_record(cache, index["entries"][name]), RunReduction)
        blob = records.to_bytes(change(red))
        index["entries"][name] = [pack, len(data), len(blob), zlib.crc32(blob)]
        data += blob
    (cache / "runs" / pack).write_bytes(data)
    (cache / "files.json").write_text(json.dumps(index))
    (cache / "day.json").unlink(missing_ok=True)


@pytest.mark.heavy
@DAY_EXAMPLES
@given(data=st.data())
def test_planted_insane_records_are_reduced_again(own_copy, data):
    protocol, out, fresh = own_copy("planted_cache")
    cache = out / ".cache"
    names = data.draw(st.lists(st.sampled_from(sorted(_entries(cache))), min_size=1,
                               max_size=4, unique=True))
    _plant(cache, {name: data.draw(insane()) for name in names})
    assert _process(protocol, out) == 0
    assert _tables(out) == fresh
    entries = _entries(cache)  # each planted record was replaced by the run's fresh one
    for name in names:
        assert sane_reduction(records.from_bytes(_record(cache, entries[name]), RunReduction))


def test_an_accel_run_keeps_its_samples(reductions):
    """The day has runs with and without constant-acceleration samples (both rules of
    ``accel_mean`` are exercised above)."""
    counts = {int(np.count_nonzero(r.samples["phase"] == PHASE_ACCEL)) > 0 for r in reductions}
    assert counts == {True, False}


# --------------------------------------------- 11. the manifest and the replay record too
def _victim(root: Path) -> Path:
    victim = root / "victim.txt"
    if not victim.exists():
        victim.write_text("a file of the user's beside the output folder\n")
    return victim


@st.composite
def planted_manifest(draw, out: Path, victim: Path) -> tuple[dict, bool]:
    """A manifest of ``out``: its true entries, some made insane, plus names that point
    outside the folder with the victim's true size, time and sha256; and whether an output's
    own entry was spoiled (the day must then stop, exit 2)."""
    files = manifest.describe(out, OUTPUT_NAMES)
    st_v = victim.stat()
    true_victim = {"size": st_v.st_size, "mtime_ns": st_v.st_mtime_ns,
                   "sha256": hashlib.sha256(victim.read_bytes()).hexdigest()}
    outside = draw(st.lists(st.sampled_from([
        "../victim.txt", str(victim), "figures/../../victim.txt", "./../victim.txt",
        "a\x00b", "", ".", "x//y", "..\\victim.txt"]), max_size=5, unique=True))
    for rel in outside:
        files[rel] = [true_victim]
    spoiled = False
    for rel in draw(st.lists(st.sampled_from(sorted(files)), max_size=3, unique=True)):
        if rel in outside:
            continue
        entry = dict(files[rel][0])
        key, bad = draw(st.sampled_from([
            ("size", -1), ("size", True), ("size", 1.5), ("size", 2**70), ("mtime_ns", "x"),
            ("mtime_ns", None), ("sha256", "0" * 63 + "g"), ("sha256", entry["sha256"].upper()),
            ("sha256", 12)]))
        entry[key] = bad
        files[rel] = [entry]
        spoiled = True
    written = draw(st.sampled_from([math.nan, math.inf, -1.0, 10**400, True, "today", 1e9]))
    complete = draw(st.sampled_from([True, 1, "yes", None]))
    return {"kind": "towtank output manifest", "complete": complete, "written": written,
            "files": files}, spoiled


@pytest.mark.heavy
@DAY_EXAMPLES
@given(data=st.data())
def test_a_planted_manifest_neither_crashes_nor_reaches_outside(own_copy, data):
    protocol, out, fresh = own_copy("planted_manifest")
    victim = _victim(out.parent)
    before = (victim.read_bytes(), victim.stat().st_mtime_ns)
    (out / "notes.txt").write_text("mine")  # the folder is then updated entry by entry
    planted, spoiled = data.draw(planted_manifest(out, victim))
    (out / manifest.MANIFEST).write_text(json.dumps(planted))
    (out / ".cache" / "day.json").unlink(missing_ok=True)
    with contextlib.redirect_stderr(io.StringIO()) as stderr:
        code = _process(protocol, out)
    err = stderr.getvalue()
    assert code == (2 if spoiled else 0), err
    assert "Traceback" not in err and "internal error" not in err
    assert (victim.read_bytes(), victim.stat().st_mtime_ns) == before
    assert (out / "notes.txt").read_text() == "mine"
    if spoiled:
        assert "which towtank did not write" in err and err.count("\n") == 1
        return
    assert _tables(out) == fresh
    listed = manifest.read_manifest(out)
    assert listed is not None and listed["complete"]
    assert all(manifest.inside_name(rel) and (out / rel).is_file() for rel in listed["files"])


@pytest.mark.parametrize("written", [math.nan, math.inf, -5.0, 10**400, True, "x", None])
def test_a_manifest_time_that_is_no_time_reads_as_zero(tmp_path, written):
    data = {"kind": "towtank output manifest", "complete": True, "written": written,
            "files": {}}
    (tmp_path / manifest.MANIFEST).write_text(json.dumps(data))
    assert manifest.read_manifest(tmp_path)["written"] == 0.0


def test_the_set_put_back_after_a_kill_is_the_latest_despite_a_planted_time(tmp_path):
    out = tmp_path / "out"
    for name, written in ((".out.old-1", 10**400), (".out.tmp-2", math.nan),
                          (".out.old-3", 100.0)):
        (tmp_path / name).mkdir()
        (tmp_path / name / "runs.csv").write_text(name)
        manifest.write_manifest(tmp_path / name, manifest.describe(tmp_path / name,
                                                                   {"runs.csv"}))
        data = json.loads((tmp_path / name / manifest.MANIFEST).read_text())
        data["written"] = written
        (tmp_path / name / manifest.MANIFEST).write_text(json.dumps(data))
    assert "was put back" in manifest.recover_outputs(out)
    assert (out / "runs.csv").read_text() == ".out.old-3"


@pytest.fixture(scope="session")
def synth_fin_day(tmp_path_factory) -> Path:
    """``towtank synth DAY --day fin`` once, for the tests to copy (with its mtimes)."""
    day = tmp_path_factory.mktemp("synth_fin") / "day"
    assert main(["synth", str(day), "--day", "fin"]) == 0
    return day


@pytest.mark.parametrize("files", [{"protocol.toml": 5}, {"protocol.toml": [7]}, [1],
                                   {"/etc/passwd": [{"size": 1, "mtime_ns": 1,
                                                     "sha256": "0" * 64}]}])
def test_a_planted_synth_manifest_is_one_sentence(synth_fin_day, tmp_path, capsys, files):
    day = tmp_path / "day"
    shutil.copytree(synth_fin_day, day, symlinks=True)  # as `towtank synth DAY --day fin`
    (day / "protocol.toml").write_text("mine")
    data = json.loads((day / ".towtank-synth.json").read_text())
    data["files"] = files
    (day / ".towtank-synth.json").write_text(json.dumps(data))
    capsys.readouterr()
    assert main(["synth", str(day), "--day", "fin", "--force"]) == 2
    err = capsys.readouterr().err
    assert "which synth did not write" in err and err.count("\n") == 1
    assert (day / "protocol.toml").read_text() == "mine"


@pytest.mark.parametrize("code", [2, 3, 7, -1, 130])
def test_a_replay_record_of_an_exit_status_no_day_records_is_not_replayed(
        processed, tmp_path_factory, code):
    protocol, copy, fresh = _copy(processed, tmp_path_factory, "replay")
    assert _process(protocol, copy) == 0  # its own replay record
    record = json.loads((copy / ".cache" / "day.json").read_text())
    record["exit_code"] = code
    (copy / ".cache" / "day.json").write_text(json.dumps(record))
    assert _process(protocol, copy) == 0
    assert _tables(copy) == fresh


def test_a_day_stamp_records_only_a_days_exit_status(processed, tmp_path):
    from towtank.ingest.protocol import load_protocol

    stamp = DayStamp(tmp_path / ".cache", load_protocol(processed[0]), tmp_path)
    assert stamp.record(3, "summary") is None
    assert not (tmp_path / ".cache" / "day.json").exists()


def test_records_roundtrip_of_a_sample_table_keeps_its_dtypes(reductions):
    red = reductions[0]
    back = records.from_bytes(records.to_bytes(red), RunReduction)
    assert records.table_length(back.samples, ("t", "U", "a", "drag", "lift"),
                                ("phase",)) == len(red.samples["t"])
    assert records.table_length({"t": np.arange(3.0), "U": np.arange(2.0)}, ("t", "U")) is None
    assert records.table_length({"t": np.arange(3)}, ("t",)) is None
    assert records.table_length({"t": np.zeros(0)}, ("t",)) is None

