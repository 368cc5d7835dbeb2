"""Captive runs drawn and inspected as what they measured (the views #35 left for later).

* The appendix thumbnails, ``watch``'s latest-run plot and ``inspect``'s plot of a captive run
  draw X, Y and N against time (the load trace the day's reduction keeps in
  ``RunReduction.captive``), the kept window or PMM cycles shaded, a PMM run's motion on top;
  not the speed and −fx of a resistance run.
* ``towtank inspect`` on a balance file without ``--protocol`` shows its channels, rate, loads
  and PMM cycles, says in one sentence what needs the protocol, and exits 0.

One small generated captive day (a drift, a sway and a yaw run) serves every test.
"""

from __future__ import annotations

import io
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest
from matplotlib.figure import Figure

from towtank.commands.inspect import inspect_run
from towtank.ingest.protocol import load_protocol
from towtank.reduce.captive import TRACE_COLUMNS, CaptiveRun
from towtank.reduce.run import reduce_record
from towtank.report import figures, pdf
from towtank.report.captive_thumb import captive_trace
from towtank.testing.captive import CaptiveRunSpec, make_captive_day

PLAN = [
    CaptiveRunSpec(1, "drift", drift_deg=8.0),
    CaptiveRunSpec(2, "sway", amplitude_m=0.1, frequency_hz=0.35),
    CaptiveRunSpec(3, "yaw", amplitude_m=0.1, frequency_hz=0.35),
]


@pytest.fixture(scope="session")
def day(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("captive_views")
    make_captive_day(root, plan=PLAN, seed=5)
    return root


@pytest.fixture(scope="session")
def reductions(day: Path) -> dict:
    protocol = load_protocol(day / "protocol.toml")
    sheet = pd.read_csv(day / "run_sheet.csv")
    out = {}
    for row in sheet.to_dict("records"):
        run, red, rejection, _ = reduce_record(protocol, row)
        assert rejection is None, rejection
        out[run] = red
    return out


def _column(cr: CaptiveRun, name: str) -> np.ndarray:
    assert cr.trace is not None
    return cr.trace[:, TRACE_COLUMNS.index(name)]


def test_the_reduction_keeps_the_whole_runs_loads_at_10_hz(reductions: dict) -> None:
    """The trace is the balance's loads over the whole run; over a static run's steady window
    its Y is the run's Y (no inertia at constant speed) and N is the moment about O."""
    red = reductions[1]
    cr = CaptiveRun.from_arrays(red.run, red.file, red.captive)
    t = _column(cr, "t")
    assert t[0] < red.windows["still_pre"][1] and t[-1] > red.windows["still_post"][0]
    assert np.median(np.diff(t)) == pytest.approx(0.1, rel=0.01)
    steady = (t > red.windows["steady"][0] + 0.2) & (t < red.windows["steady"][1] - 0.2)
    mean = cr.rows.iloc[0]
    assert np.mean(_column(cr, "Y")[steady]) == pytest.approx(mean["Y"], rel=0.02)
    assert np.mean(_column(cr, "N")[steady]) == pytest.approx(mean["N"], rel=0.02)
    assert np.isnan(_column(cr, "sway")).all()  # a drift run has no PMM motion


def test_a_malformed_trace_is_refused(reductions: dict) -> None:
    red = reductions[2]
    bad = dict(red.captive)
    bad["trace"] = bad["trace"][::-1].copy()  # time running backwards
    with pytest.raises(ValueError, match="trace"):
        CaptiveRun.from_arrays(red.run, red.file, bad)


def _lines(ax) -> list[np.ndarray]:  # noqa: ANN001 - an Axes
    return [np.asarray(line.get_ydata(), dtype=float) for line in ax.get_lines()]


def _drawn(lines: list[np.ndarray], values: np.ndarray) -> bool:
    return any(y.shape == values.shape and np.allclose(y, values, equal_nan=True)
               for y in lines)


@pytest.mark.parametrize("run", [1, 2, 3])
def test_run_plot_draws_x_y_n_not_speed_and_drag(reductions: dict, run: int) -> None:
    """watch's and inspect's plot (fig_run) of a captive run: X, Y on the right, N on the
    left; neither the speed nor the −fx 'drag' of a resistance run's plot."""
    red = reductions[run]
    cr = CaptiveRun.from_arrays(red.run, red.file, red.captive)
    fig = figures.fig_run(red, f"run {run}")
    ax = fig.axes[0]
    twin = next(a for a in fig.axes if a is not ax and a.get_shared_x_axes().joined(a, ax))
    assert _drawn(_lines(twin), _column(cr, "X")) and _drawn(_lines(twin), _column(cr, "Y"))
    assert _drawn(_lines(ax), _column(cr, "N"))
    every = [y for a in fig.axes for y in _lines(a)]
    assert not _drawn(every, red.thumb["U"]) and not _drawn(every, red.thumb["drag"])
    assert "N" in ax.get_ylabel() and "X" in twin.get_ylabel()


def test_pmm_plot_shades_the_kept_cycles_and_draws_the_motion(reductions: dict) -> None:
    red = reductions[3]
    cr = CaptiveRun.from_arrays(red.run, red.file, red.captive)
    ct = captive_trace(red)
    assert ct is not None and len(ct.kept) == cr.cycles_used >= 3
    assert ct.kept[0][0] == pytest.approx(cr.cycles["t_start"].iloc[0])
    fig = Figure()
    ax = fig.add_subplot()
    twin = figures.thumbnail_twin(ax)
    figures.run_thumbnail(ax, red, twin=twin)
    # each kept cycle shaded; the steady window itself is not (its dropped cycles stay white)
    spans = [p.get_x() for p in twin.patches]
    assert all(any(abs(s - a) < 1e-9 for s in spans) for a, _ in ct.kept)
    assert not any(abs(s - red.windows["steady"][0]) < 1e-9 for s in spans)
    band = ax.child_axes
    assert len(band) == 1 and len(band[0].get_lines()) == 2  # sway and yaw
    assert any("sway ±" in t.get_text() and "yaw ±" in t.get_text() for t in ax.texts)


def test_appendix_thumbnails_of_a_captive_day(reductions: dict) -> None:
    """The PDF's appendix page: every captive cell labelled N and X, Y and its legend naming
    the loads and the kept cycles, not the speed and drag."""
    runs = pd.DataFrame([{"run": r, "config": "hull", "angle_deg": 0.0, "status": "ok",
                          "speed_mean": red.speed_mean, "test": PLAN[r - 1].test,
                          "reason": ""} for r, red in reductions.items()])
    day = SimpleNamespace(runs=runs, reductions=reductions, previews={}, rejected=[])
    grid = pdf.ThumbGrid()
    fig = grid.draw(day, [1, 2, 3])
    cells = grid.cells[:3]
    assert all("N" in ax.get_ylabel() and "X" in twin.get_ylabel() for ax, twin in cells)
    assert "sway" in cells[1][0].get_title("left") and "yaw" in cells[2][0].get_title("left")
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert any("$X$" in s for s in labels) and "kept PMM cycles" in labels
    assert not any("speed" in s or "drag" in s for s in labels)
    # the next page's cells start clean: the motion band is gone with its run
    grid.draw(day, [1])
    assert not grid.cells[1][0].child_axes and not grid.cells[0][0].child_axes


def _inspect(path: Path, tmp_path: Path, protocol: Path | None = None) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    code = inspect_run(path, protocol, png=tmp_path / "plot.png", out=out, err=err)
    return code, out.getvalue(), err.getvalue()


def test_inspect_a_balance_file_without_its_protocol(day: Path, tmp_path: Path) -> None:
    """Was: the proposed [channels] block, then 'the drag channel is missing', exit 1."""
    code, out, err = _inspect(day / "data" / "run_003.csv", tmp_path)
    assert code == 0, err
    assert err == ""
    assert "at 100 Hz" in out and "balance file: fx, fy, mz, sway, yaw" in out
    assert "steady means at the balance point" in out
    assert "PMM cycles of the sway" in out and " kept" in out
    needs = [line for line in out.splitlines() if "need the campaign's protocol" in line]
    assert len(needs) == 1 and "izz_kg_m2" in needs[0] and "balance_x_m" in needs[0]
    assert (tmp_path / "plot.png").stat().st_size > 10_000


def test_inspect_a_static_balance_file_without_its_protocol(day: Path, tmp_path: Path) -> None:
    code, out, err = _inspect(day / "data" / "run_001.csv", tmp_path)
    assert code == 0, err
    assert "balance file: fx, fy, mz (" in out and "PMM cycles" not in out


def test_a_file_neither_drag_nor_balance_still_says_what_is_missing(tmp_path: Path) -> None:
    t = np.arange(0, 20, 0.01)
    path = tmp_path / "run_009.csv"
    pd.DataFrame({"time": t, "speed": np.clip(t - 3, 0, 1.5), "fy": np.zeros_like(t)}).to_csv(
        path, index=False)
    code, _, err = _inspect(path, tmp_path / "elsewhere")
    assert code == 1 and "drag channel is missing" in err


def test_inspect_with_the_protocol_plots_the_loads_about_o(day: Path, tmp_path: Path) -> None:
    code, out, err = _inspect(day / "data" / "run_002.csv", tmp_path, day / "protocol.toml")
    assert code == 0, err
    assert "hydrodynamic loads about O" in out
    assert (tmp_path / "plot.png").exists()
