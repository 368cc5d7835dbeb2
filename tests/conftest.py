"""Shared fixtures: synthetic days generated once per session and processed by the pipeline.

Every day is written by :mod:`towtank.testing.synthetic` (whose truth is exact) into a session
temporary
folder, with its protocol beside it (paths relative to the protocol), and processed once. Tests
then compare the pipeline's numbers with the per-run truth of ``truth.json``.
"""

from __future__ import annotations

import atexit
import contextlib
import copy
import gc
import importlib
import os
import pickle
import shutil
import signal
import sys
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from towtank.testing.bytecode import pycache_folders, remove_new_pycache, write_bytecode_again

# The suite starts about sixty new Python processes (the commands that need a process of their
# own, the fork servers of the worker pools, pytest-xdist's workers). Where the environment
# switches bytecode writing off (PYTHONDONTWRITEBYTECODE), each of them would compile towtank's
# modules and the test modules from source again (0.9 CPU-s a start for towtank's): the run
# writes them beside the sources, in __pycache__, as Python does by default, and the process
# that switched writing on (the one that started the run) removes the folders it made when it
# ends, after its pytest-xdist workers.
_SOURCES = tuple(Path(__file__).resolve().parents[1] / name for name in ("towtank", "tests"))
if write_bytecode_again():
    atexit.register(remove_new_pycache, _SOURCES, pycache_folders(_SOURCES))

import pandas as pd  # noqa: E402 - after the bytecode switch, as every import below
import pytest  # noqa: E402
from hypothesis import Phase, settings  # noqa: E402

from towtank.runtime.parallel import default_jobs  # noqa: E402
from towtank.testing import days as syn_days  # noqa: E402
from towtank.testing import synthetic as syn  # noqa: E402

#: Worker processes for the days the fixtures process: none. The suite runs on two pytest-xdist
#: workers on two cores, so a pool of workers per day only adds its start-up; the tests that are
#: about worker pools ask for them (``--jobs 2``, ``jobs=2``).
JOBS = 1
# For the same reason, the processes towtank uses when a test (or a documented command it runs
# as written) does not say: each pytest-xdist worker gets its share of the cores through
# towtank's TOWTANK_JOBS (one each for two workers on two cores), unless it is set already. A
# test about the default itself clears it (``monkeypatch.delenv``).
_SHARE_SET = ("TOWTANK_JOBS" not in os.environ
              and os.environ.get("PYTEST_XDIST_WORKER_COUNT", "").isdigit())
if _SHARE_SET:
    os.environ["TOWTANK_JOBS"] = str(max(1, default_jobs()
                                         // max(1, int(os.environ["PYTEST_XDIST_WORKER_COUNT"]))))

# A suite started with Ctrl-C ignored (under nohup, or as `pytest &` from a script: a
# non-interactive shell starts a background command with SIGINT ignored) still tests what a
# terminal's Ctrl-C does to a towtank command: the commands the tests start would inherit the
# ignored SIGINT (towtank then leaves it ignored, as nohup asks) and the Ctrl-C tests would
# wait for an exit that never comes. SIGINT is Python's default again in each test process; a
# command started from it gets the default action (exec resets a handled signal).
if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)


def lab_environment(**extra: str) -> dict[str, str]:
    """The environment for a towtank command run in a process of its own as a lab runs it, on
    every core (the suite's TOWTANK_JOBS share left out): for the tests about its processes
    (Ctrl-C, the forked writers, a real full disk). ``extra``: variables added."""
    env = dict(os.environ)
    if _SHARE_SET:
        env.pop("TOWTANK_JOBS", None)
    env.update(extra)
    return env


ROOT = Path(__file__).resolve().parents[1]

# No per-example deadline in any property test: a deadline is a timing bound, and on a loaded
# two-core CI machine one slow example (a garbage collection, the other worker) would fail a
# correct test as "Flaky". Speed is measured by the benchmarks, not here.
# No "explain" phase either: with it, Hypothesis traces every line of towtank while it shrinks a
# failure, and a property test whose examples are whole simulations then hits its hang bound
# (test_vehicle_inputs.py: a 7 s shrink took over 90 s traced) and reports the bound, not the
# failing example. Without it the shrunk example is reported as it is found.
settings.register_profile("towtank", deadline=None,
                          phases=tuple(p for p in Phase if p is not Phase.explain))
settings.load_profile("towtank")


# ------------------------------------------------------------------ generated days, once each
_real_make_hull_day = syn_days.make_hull_day
_TEMPLATES: dict[Any, tuple[Path, Any]] = {}  # the arguments -> (template folder, truth)
_TEMPLATE_ROOT = Path(tempfile.mkdtemp(prefix="towtank-test-days-"))
atexit.register(shutil.rmtree, _TEMPLATE_ROOT, ignore_errors=True)


def _hashable(value: Any) -> Any:
    """``value`` as a key (lists and dicts as tuples); TypeError where it has none."""
    if isinstance(value, list | tuple):
        return tuple(_hashable(v) for v in value)
    if isinstance(value, dict):
        return tuple(sorted((k, _hashable(v)) for k, v in value.items()))
    hash(value)
    return value


def make_hull_day_once(out_dir: str | Path, **kw: Any) -> Any:
    """:func:`towtank.testing.days.make_hull_day`, each distinct day generated once per session
    (per xdist worker) and copied into ``out_dir`` with fresh modification times. The generator
    is seeded, so the copy is the day it would write: the same files and the same truth (a copy
    of it, which the caller may change)."""
    try:
        key = _hashable(kw)
    except TypeError:  # an argument without a value to compare (an array): generated anew
        return _real_make_hull_day(out_dir, **kw)
    if key not in _TEMPLATES:
        template = Path(tempfile.mkdtemp(dir=_TEMPLATE_ROOT))
        _TEMPLATES[key] = (template, _real_make_hull_day(template, **kw))
    template, truth = _TEMPLATES[key]
    shutil.copytree(template, out_dir, copy_function=shutil.copyfile, dirs_exist_ok=True)
    return copy.deepcopy(truth)


# the tests, towtank.testing's helpers and `towtank synth` run in this process use it
syn_days.make_hull_day = syn.make_hull_day = make_hull_day_once  # type: ignore[assignment]


@dataclass
class Day:
    """A generated day: its folder, protocol, truth.json and the processed result."""

    dir: Path
    protocol: Path
    truth: dict[str, Any]
    result: Any  # towtank.pipeline.DayResult

    def run_truth(self, run: int) -> dict[str, Any]:
        return self.truth["runs"][str(int(run))]


def write_hull_protocol(
    day_dir: Path,
    *,
    name: str = "p.toml",
    sheet_format: str = "xlsx",
    channel_style: str = "lab",
    channels: syn.LabChannels | None = None,
    processing: dict[str, Any] | None = None,
    temperature_C: float = 18.0,
) -> Path:
    """The hull protocol of a generated day, written inside the day's folder."""
    sections = syn.hull_protocol_sections(
        ".",
        "out",
        sheet_format=sheet_format,
        channel_style=channel_style,
        channels=channels,
        temperature_C=temperature_C,
    )
    if processing:
        sections["processing"] = dict(processing)
    return syn.write_protocol(day_dir / name, **sections)


def process(protocol: Path, **kw: Any):
    from towtank.pipeline import process_day

    kw.setdefault("jobs", JOBS)
    return process_day(protocol, **kw)


def make_processed_hull_day(
    day_dir: Path,
    *,
    sheet_edit: Callable[[Path], None] | None = None,
    protocol_kw: dict[str, Any] | None = None,
    **make_kw: Any,
) -> Day:
    """Generate a hull day with ``make_hull_day(**make_kw)``, optionally edit its sheet, process."""
    make_kw.setdefault("seed", 3)
    syn.make_hull_day(day_dir, **make_kw)
    if sheet_edit is not None:
        sheet_edit(day_dir)
    pkw = {
        "sheet_format": make_kw.get("sheet_format", "xlsx"),
        "channel_style": make_kw.get("channel_style", "lab"),
        "channels": make_kw.get("channels"),
    }
    pkw.update(protocol_kw or {})
    protocol = write_hull_protocol(day_dir, **pkw)
    return Day(day_dir, protocol, syn.load_truth(day_dir), process(protocol))


# ------------------------------------------------------------------------------ hull days
@pytest.fixture(scope="session")
def hull_day(tmp_path_factory) -> Day:
    """The default synthetic SUT-2 day (seed 3): lab channels in volts with a negative lift gain,
    gzipped CSV run files, an .xlsx run sheet, 200 Hz, realistic default noise."""
    return make_processed_hull_day(tmp_path_factory.mktemp("hull_default"), seed=3)


CUSTOM_CHANNELS = syn.LabChannels(
    time="t [s]",
    speed="V carriage [m/s]",
    accel="A carriage [m/s^2]",
    drag="Load cell X [V]",
    lift="Load cell Y [V]",
    drag_gain=-18.5,  # the drag cell is mounted reversed too
    drag_offset=0.12,
    lift_gain=-31.0,
    lift_offset=-0.05,
)


@pytest.fixture(scope="session")
def hull_day_tdms(tmp_path_factory) -> Day:
    """TDMS run files with a custom [channels] mapping: other column names, both load cells in
    volts with NEGATIVE gains and non-zero offsets; an .xlsx sheet."""
    return make_processed_hull_day(
        tmp_path_factory.mktemp("hull_tdms"),
        seed=11,
        file_format="tdms",
        sheet_format="xlsx",
        channel_style="lab",
        channels=CUSTOM_CHANNELS,
    )


MANUAL_RUN = 15  # hull, 0 deg, 1.6 m/s steady run: its steady window is set by hand
MANUAL_OFFSETS = (1.0, 4.5)  # [s] after the truth plateau start


def _add_manual_window(day_dir: Path) -> None:
    truth = syn.load_truth(day_dir)["runs"][str(MANUAL_RUN)]
    sheet_path = day_dir / "run_sheet.csv"
    sheet = pd.read_csv(sheet_path, dtype=str, keep_default_na=False)
    sheet["window_start_s"] = ""
    sheet["window_end_s"] = ""
    row = sheet["run"].astype(int) == MANUAL_RUN
    sheet.loc[row, "window_start_s"] = f"{truth['t_plateau_start'] + MANUAL_OFFSETS[0]:.3f}"
    sheet.loc[row, "window_end_s"] = f"{truth['t_plateau_start'] + MANUAL_OFFSETS[1]:.3f}"
    sheet.to_csv(sheet_path, index=False, lineterminator="\n")


@pytest.fixture(scope="session")
def hull_day_csv(tmp_path_factory) -> Day:
    """Plain .csv run files (not gzipped) with canonical channel names, a .csv sheet, and a
    manual steady window written into one row of the sheet."""
    return make_processed_hull_day(
        tmp_path_factory.mktemp("hull_csv"),
        seed=12,
        file_format="csv",
        sheet_format="csv",
        channel_style="canonical",
        sheet_edit=_add_manual_window,
    )


@pytest.fixture(scope="session", params=["default", "tdms", "csv"])
def any_hull_day(request) -> Day:
    """Each of the three hull days in turn."""
    name = {"default": "hull_day", "tdms": "hull_day_tdms", "csv": "hull_day_csv"}[request.param]
    return request.getfixturevalue(name)


@pytest.fixture(scope="session")
def fin_day(tmp_path_factory) -> Day:
    """The NACA 0015 fin day: TDMS (float32) run files, canonical channels, .csv sheet."""
    d = tmp_path_factory.mktemp("fin")
    syn.make_fin_day(d, seed=5)
    protocol = syn.write_protocol(d / "p.toml", **syn.fin_protocol_sections(".", "out"))
    return Day(d, protocol, syn.load_truth(d), process(protocol))


# ------------------------------------------------------------------------- the sample days
@dataclass(frozen=True)
class SampleOutputs:
    """A shipped sample day processed by ``towtank process --no-report -q``."""

    code: int  # the command's exit status
    out: Path  # its output folder (with the run cache, .cache)


def _run_folder(tmp_path_factory) -> Path | None:
    """The folder every xdist worker of this run shares (None without xdist: one process)."""
    if "PYTEST_XDIST_WORKER" not in os.environ:
        return None
    return tmp_path_factory.getbasetemp().parent  # pytest-N, above popen-gw0, popen-gw1, ...


@contextlib.contextmanager
def _locked(path: Path):
    """An exclusive lock on ``path`` between processes (none where fcntl is missing: Windows,
    where each worker then builds its own)."""
    try:
        import fcntl
    except ImportError:  # pragma: no cover - Windows
        yield
        return
    with open(path, "a") as fh:
        fcntl.flock(fh, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(fh, fcntl.LOCK_UN)


def built_once(tmp_path_factory, name: str, build: Callable[[Path], Any]) -> tuple[Any, Path]:
    """``build(out)`` once per test run: the first xdist worker that asks builds into a folder
    of the run that every worker shares (under a lock, the others wait) and keeps what it
    returned beside it (pickled: a DayResult, an exit status); later askers read that. Without
    xdist, once per session. Returns (what build returned, the folder ``out``)."""
    shared = _run_folder(tmp_path_factory)
    if shared is None:
        out = tmp_path_factory.mktemp(name) / "out"
        return build(out), out
    home = shared / f"shared-{name}"
    out, value_file = home / "out", home / "value.pickle"
    home.mkdir(exist_ok=True)
    with _locked(home / ".lock"):
        if not value_file.exists():
            value = build(out)
            value_file.write_bytes(pickle.dumps(value))
            return value, out
    return pickle.loads(value_file.read_bytes()), out  # written by this run's own worker


@pytest.fixture(scope="session")
def sample_outputs(tmp_path_factory) -> Callable[[str], SampleOutputs]:
    """``sample_outputs(name)``: ``protocols/<name>.toml`` (sut2_hull, naca0015_fin) processed
    once per test run (:func:`built_once`: shared by the xdist workers) into a run folder. The
    folder is shared: tests only read it (a test that writes there copies it first)."""
    done: dict[str, SampleOutputs] = {}

    def get(name: str) -> SampleOutputs:
        if name not in done:
            from towtank.commands.cli import main

            def build(out: Path) -> int:
                return main(["process", str(ROOT / "protocols" / f"{name}.toml"), "--no-report",
                             "--out", str(out), "-q", "--jobs", str(JOBS)])

            code, out = built_once(tmp_path_factory, f"sample_{name}", build)
            done[name] = SampleOutputs(code, out)
        return done[name]

    return get


@dataclass(frozen=True)
class SampleReport:
    """A shipped sample day processed by :func:`towtank.process_day` with its report."""

    day: Any  # towtank.results.DayResult
    out: Path  # its output folder (with the run cache, .cache)


@pytest.fixture(scope="session")
def sample_report(tmp_path_factory, sample_outputs) -> Callable[[str], SampleReport]:
    """``sample_report(name)``: ``protocols/<name>.toml`` (sut2_hull, naca0015_fin) processed
    with its report (PDF, workbook, figures) by ``towtank.process_day(protocol, out=...,
    report=True)`` once per test run (:func:`built_once`: shared by the xdist workers). Writing
    a report is the longest part of a day, so the tests that read a sample day's written report
    share this one (the golden comparison, the front doors). The runs come from the run cache
    of the session's ``towtank process`` of the day (:func:`sample_outputs`), which reduced
    them (the golden comparison, tests/test_golden_outputs.py, holds these outputs to the
    ones recorded from a day reduced afresh). The folder is shared: tests only read it."""
    done: dict[str, SampleReport] = {}

    def get(name: str) -> SampleReport:
        if name not in done:
            import towtank

            def build(out: Path) -> Any:
                reduced = sample_outputs(name).out / ".cache"
                shutil.copytree(reduced, out / ".cache",
                                ignore=shutil.ignore_patterns("day.json"))  # runs, no replay
                return towtank.process_day(ROOT / "protocols" / f"{name}.toml", out=out,
                                           report=True, jobs=JOBS)

            day, out = built_once(tmp_path_factory, f"report_{name}", build)
            done[name] = SampleReport(day, out)
        return done[name]

    return get


# ------------------------------------------------------------------------- many-seed results
@dataclass
class SeedResult:
    seed: int
    fs: float
    coefficients: pd.DataFrame  # coefficients.csv, indexed by symbol
    truth: dict[str, float]  # truth coefficients (model-scale SI)
    rejected: dict[int, str]
    # what the hull fit was given, to refit the same day with other settings
    runs: pd.DataFrame
    reductions: dict[int, Any]  # towtank.reduce.run.RunReduction by run
    tares: dict[str, Any]  # towtank.reduce.tare.TareModel by group
    model: Any  # towtank.ingest.protocol.Model


@pytest.fixture(scope="session")
def seed_result(tmp_path_factory) -> Callable[..., SeedResult]:
    """``seed_result(seed, fs=200.0)``: a realistic-noise SUT-2 day with that seed, processed;
    computed once per (seed, fs) for the whole session, its files deleted afterwards. TDMS
    float64 run files and a CSV sheet: the channels are rounded before they are written, so a
    float64 TDMS file holds exactly the numbers a CSV, gzip or .xlsx day's reader returns, and
    the day's coefficients are the same to the last bit, without formatting and parsing the
    decimal text (half the cost of a day)."""
    cache: dict[tuple[int, float], SeedResult] = {}

    def get(seed: int, fs: float = 200.0) -> SeedResult:
        key = (int(seed), float(fs))
        if key not in cache:
            d = tmp_path_factory.mktemp(f"seed{seed}_{int(fs)}hz")
            truth = syn.make_hull_day(d, seed=seed, fs=fs, file_format="tdms",
                                     sheet_format="csv")
            day = process(write_hull_protocol(d, sheet_format="csv"))
            assert day.hull is not None, day.warnings
            cache[key] = SeedResult(
                seed=int(seed),
                fs=float(fs),
                coefficients=day.hull.coefficients.set_index("symbol"),
                truth=dict(truth.coefficients or {}),
                rejected=dict(day.rejected),
                runs=day.runs,
                reductions=day.reductions,
                tares=day.tares,
                model=day.protocol.model,
            )
            shutil.rmtree(d, ignore_errors=True)
        return cache[key]

    return get


# --- vehicle tests: one shipped vehicle predicted and turned


@dataclass
class VehicleTurn:
    """``towtank predict`` of a shipped vehicle protocol, then ``towtank simulate --manoeuvre
    turning`` of its model.json: the folders and what each command printed."""

    predicted: Path  # predict's --out (model.json)
    turn: Path  # simulate's --out (metrics.csv, manoeuvre.csv)
    predict_out: str
    predict_err: str
    simulate_out: str
    simulate_err: str


@pytest.fixture(scope="session")
def series58_turn(tmp_path_factory) -> VehicleTurn:
    """protocols/series58_vehicle.toml predicted, then turned with 10 deg of rudder at its
    design speed (1.25 m/s), both in-process, once for the session (no figure)."""
    base = tmp_path_factory.mktemp("series58_turn")
    printed = []
    with pytest.MonkeyPatch.context() as patch:
        _skip_command_figures(patch)
        printed += _run_printing(
            ["predict", str(ROOT / "protocols" / "series58_vehicle.toml"),
             "--out", str(base / "pred")])
        printed += _run_printing(
            ["simulate", str(base / "pred" / "model.json"), "--manoeuvre", "turning",
             "--rudder-deg", "10", "--out", str(base / "turn")])
    return VehicleTurn(base / "pred", base / "turn", *printed)


def _run_printing(args: list[str]) -> list[str]:
    """``towtank ARGS`` in-process, which must exit 0: [what it printed, its stderr]."""
    import contextlib
    import io

    from towtank.commands.cli import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(args)
    assert code == 0, (args, err.getvalue())
    return [out.getvalue(), err.getvalue()]


def _skip_command_figures(patch: pytest.MonkeyPatch) -> None:
    """``simulate`` without drawing manoeuvre.png and ``identify`` without identify.png (a
    third of a short simulation's time, a quarter of a short identification's), for the
    tests that assert on the commands' numbers and words, not on their figures."""
    import towtank.commands.identify as identify
    import towtank.commands.simulate as simulate

    patch.setattr(simulate, "_figure", lambda *args, **kwargs: None)
    patch.setattr(identify, "save_identify_figure", lambda *args, **kwargs: None)


@pytest.fixture
def no_command_figures(monkeypatch) -> None:
    """``towtank simulate`` and ``identify`` in this test draw no figure."""
    _skip_command_figures(monkeypatch)


# ------------------------------------------------------------------------------ workbook
def workbook_block(path: Path, sheet: str, title_start: str) -> pd.DataFrame:
    """The table under the first row of ``sheet`` whose first cell starts with ``title_start``
    (a block title: give enough of it not to match the text of a warning above it)."""
    from openpyxl import load_workbook

    ws = load_workbook(path, read_only=True)[sheet]
    rows = [list(r) for r in ws.iter_rows(values_only=True)]
    start = next(i for i, r in enumerate(rows) if str(r[0] or "").startswith(title_start))
    header = [str(h).split(" [")[0] for h in rows[start + 1] if h is not None]
    body = []
    for r in rows[start + 2:]:
        if r[0] is None or (len(header) > 1 and all(c is None for c in r[1:len(header)])):
            break  # a blank row, or a note under the table
        body.append(r[: len(header)])
    return pd.DataFrame(body, columns=header)



# ------------------------------------------------------------- PDF pages not read by a test
def draw_only_pages(mp: pytest.MonkeyPatch, keep: Callable[[Any], bool]) -> None:
    """Make :func:`towtank.report.pdf.write_pdf` draw only the pages ``keep(page)`` selects
    (a :class:`towtank.report.pdf.Page`); every other page of the plan is a blank page, still
    headed and numbered, so the PDF holds the whole plan in order. For tests that read a few
    pages of a report: the pages they do not read cost the seconds of drawing a report."""
    from towtank.report import pdf

    real_render = pdf._render

    def render(day: Any, page: Any, plan: list[Any], grids: Any = None) -> Any:
        return real_render(day, page, plan, grids) if keep(page) else pdf._page()

    mp.setattr(pdf, "_render", render)


# --------------------------------------------------- the adversarial rounds' processed day
@dataclass(frozen=True)
class TrustDay:
    """A synthetic SUT-2 day (seed 5, CSV run files and sheet) and its protocol, processed by
    ``towtank.process_day(protocol, out=out, report=False, jobs=1)``, which writes what
    ``towtank process --no-report -q --jobs 1`` writes (with the run cache and the replay
    record). Tests only read ``dir`` and ``out``: a test that writes copies them first."""

    dir: Path  # the day's folder: data/, run_sheet.csv, truth.json
    protocol: Path  # its protocol, in a folder of its own (paths to ``dir`` absolute)
    out: Path  # the processed output folder, with .cache
    day: Any  # towtank.results.DayResult


@pytest.fixture(scope="session")
def trust_day(tmp_path_factory) -> TrustDay:
    """The day the adversarial-round tests (test_trust_round2.py, test_trust_round3_runtime.py)
    plant things into copies of, processed once per test run (:func:`built_once`)."""

    def build(out: Path) -> Any:
        import towtank

        home = out.parent
        syn.make_hull_day(home / "day", seed=5, file_format="csv", sheet_format="csv")
        sections = syn.hull_protocol_sections(str(home / "day"), "out", sheet_format="csv")
        protocol = syn.write_protocol(home / "protocol" / "protocol.toml", **sections)
        return towtank.process_day(protocol, out=out, report=False, jobs=JOBS)

    day, out = built_once(tmp_path_factory, "trust_day", build)
    return TrustDay(out.parent / "day", out.parent / "protocol" / "protocol.toml", out, day)


def pytest_addoption(parser):
    parser.addoption("--run-slow", action="store_true", default=False,
                     help="also run the tests marked slow (the coverage study: hours)")
    parser.addoption("--floors", action="store_true", default=False,
                     help="also run the tests marked floors (the commands a lab runs, each in "
                          "a new process: .ci/run runs them on the minimum versions)")
    parser.addoption("--bench", action="store_true", default=False,
                     help="also run the tests marked bench (the campaign benchmark's smoke run, "
                          "a dozen new processes: .ci/run runs it apart from the suite)")
    parser.addoption("--heavy", action="store_true", default=False,
                     help="also run the tests marked heavy (each more than 1.5 CPU-s: whole "
                          "days, new processes, signals, coverage over many draws, mypy; "
                          ".ci/run runs them as a step of their own: --heavy -m heavy)")


def pytest_collection_modifyitems(config, items):
    skips = []
    if not (config.getoption("--run-slow") or os.environ.get("TOWTANK_RUN_SLOW")):
        skips.append(("slow", pytest.mark.skip(
            reason="slow: run with --run-slow (or TOWTANK_RUN_SLOW=1)")))
    if not config.getoption("--floors"):
        skips.append(("floors", pytest.mark.skip(
            reason="floors: run on the minimum versions by .ci/run (--floors); the same "
                   "commands run in-process in test_docs_commands_run.py")))
    if not config.getoption("--bench"):
        skips.append(("bench", pytest.mark.skip(
            reason="bench: the benchmark's smoke run, run apart by .ci/run (--bench)")))
    if not config.getoption("--heavy"):
        # deselected, not skipped: the run ends with their number, not with a line for each
        keep, heavy = [], []
        for item in items:
            (keep if item.get_closest_marker("heavy") is None else heavy).append(item)
        if heavy:
            config.hook.pytest_deselected(items=heavy)
            items[:] = keep
    for item in items:
        for marker, skip in skips:
            if item.get_closest_marker(marker) is not None:  # a mark, not a folder's name
                item.add_marker(skip)


def pytest_collection(session):
    """Each pytest-xdist worker collects every test module, and where no bytecode is kept yet (a
    fresh checkout, or bytecode writing switched off until the run switched it on) each rewrites
    the asserts of every test module and compiles it, the same ones at the same moment: about 20
    CPU-s a worker, the same work twice. The first worker's collection goes through the modules
    in order; worker k of n first imports the modules of its k-th share backwards, from the end
    of the share, until it meets one whose bytecode is written (by a worker before it): each
    module is then compiled about once. A module is imported here as its collection would (the
    same name, with pytest's assertion rewriting); one that fails to import is left to the
    collection, which reports it."""
    worker = os.environ.get("PYTEST_XDIST_WORKER", "")
    count = os.environ.get("PYTEST_XDIST_WORKER_COUNT", "")
    if (sys.dont_write_bytecode or not worker.startswith("gw") or not worker[2:].isdigit()
            or not count.isdigit() or int(count) < 2 or int(worker[2:]) == 0):
        return
    k, n = int(worker[2:]), int(count)
    files = sorted(Path(__file__).resolve().parent.glob("test_*.py"))
    # where pytest keeps a rewritten module's bytecode (_pytest.assertion.rewrite)
    tag = f"{sys.implementation.cache_tag}-pytest-{pytest.__version__}.pyc"
    for path in reversed(files[k * len(files) // n:(k + 1) * len(files) // n]):
        cache = (Path(sys.pycache_prefix, *path.parent.parts[1:]) if sys.pycache_prefix
                 else path.parent / "__pycache__")
        if path.stem in sys.modules or (cache / f"{path.stem}.{tag}").exists():
            break
        try:
            importlib.import_module(path.stem)
        except (Exception, pytest.skip.Exception):  # noqa: BLE001 - the collection reports it
            sys.modules.pop(path.stem, None)


#: Collections of the middle generation between two full collections in a test process
#: (Python's default: 10).
FULL_COLLECTION_EVERY = 100


def pytest_collection_finish(session):
    """What is loaded by now (modules, the collected tests) lives for the whole session: the
    cyclic garbage collector leaves it out of its scans (gc.freeze), so that a full collection
    scans what the tests made, not the libraries' millions of objects again. A full collection
    is also made a tenth as often (after 100 collections of the middle generation, not 10):
    each one scans every object the tests keep alive, and the cycles they leave (figures,
    frames) are mostly freed by the younger generations' collections before then."""
    gc.freeze()
    young, middle, _ = gc.get_threshold()
    gc.set_threshold(young, middle, FULL_COLLECTION_EVERY)
