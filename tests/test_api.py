"""The public Python API (towtank.process_day and friends) in scripts, ``python -c``, ``python -``
and in-process: the same coefficients as the command line, no traceback, nothing rejected."""

from __future__ import annotations

import subprocess
import sys
import textwrap
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pandas as pd
import pytest

import towtank

ROOT = Path(__file__).resolve().parents[1]
HULL = ROOT / "protocols" / "sut2_hull.toml"
RUN_21 = ROOT / "sample_runs" / "sut2_hull" / "data" / "run_021.csv.gz"


@pytest.fixture(scope="session")
def cli_coefficients(sample_outputs) -> pd.DataFrame:
    """coefficients.csv of ``towtank process protocols/sut2_hull.toml --no-report`` (the
    session's run of the command, tests/conftest.py)."""
    done = sample_outputs("sut2_hull")
    assert done.code == 0
    return pd.read_csv(done.out / "coefficients.csv")


SCRIPT = """\
import towtank
day = towtank.process_day({protocol!r}, jobs=2)
day.coefficients.to_csv({out!r}, index=False)
print("rejected", day.n_rejected)
"""

GUARDED = """\
import towtank


def main():
    day = towtank.process_day({protocol!r}, jobs=2)
    day.coefficients.to_csv({out!r}, index=False)
    print("rejected", day.n_rejected)


if __name__ == "__main__":
    main()
"""


def _same(a: pd.DataFrame, b: pd.DataFrame) -> None:
    pd.testing.assert_frame_equal(a.reset_index(drop=True), b.reset_index(drop=True))


@pytest.mark.heavy
@pytest.mark.parametrize("how", ["script", "guarded-script", "python -c", "python -"])
def test_process_day_from_a_plain_program(how, tmp_path, cli_coefficients):
    """No main guard (the workers would re-run the script), -c and stdin: all 41 runs reduced,
    no traceback, the command line's coefficients."""
    out = tmp_path / "coefficients.csv"
    code = (GUARDED if how == "guarded-script" else SCRIPT).format(protocol=str(HULL),
                                                                  out=str(out))
    if how in ("script", "guarded-script"):
        script = tmp_path / "analyse.py"
        script.write_text(code)
        args, stdin = [sys.executable, str(script)], None
    elif how == "python -c":
        args, stdin = [sys.executable, "-c", code], None
    else:
        args, stdin = [sys.executable, "-"], code
    res = subprocess.run(args, input=stdin, capture_output=True, text=True, cwd=tmp_path,
                         timeout=600)
    assert res.returncode == 0, res.stderr
    assert "Traceback" not in res.stderr and "rejected 0" in res.stdout
    _same(pd.read_csv(out), cli_coefficients)


@pytest.mark.heavy
def test_process_day_in_process_returns_the_day(cli_coefficients, sample_hull_day):
    day = sample_hull_day  # towtank.process_day(HULL, ...) in this session
    assert day.n_rejected == 0 and not day.rejected
    _same(day.coefficients.pipe(lambda d: pd.read_csv(
        pd.io.common.StringIO(d.to_csv(index=False)))), cli_coefficients)
    assert set(day.runs["status"]) == {"ok", "void"}
    assert day.fins is None and list(day.table("fins").columns)[:2] == ["run", "angle_deg"]
    assert len(day.scaling.table) == 4 and "drag_ittc57" in day.scaling.table
    assert isinstance(day.warnings, tuple)


def test_process_day_writes_what_the_cli_writes(tmp_path, cli_coefficients):
    out = tmp_path / "out"
    towtank.process_day(str(HULL), out=out, report=False, jobs=1)
    _same(pd.read_csv(out / "coefficients.csv"), cli_coefficients)
    assert {"runs.csv", "fins.csv", "scaling.csv", "provenance.json"} <= {
        p.name for p in out.iterdir()}
    assert not (out / "report.pdf").exists()


def test_read_and_reduce_one_run(sample_hull_day):
    protocol = towtank.load_protocol(HULL)
    raw = towtank.read_run(ROOT / "sample_runs/sut2_hull/data/run_021.csv.gz", protocol)
    assert raw.fs == pytest.approx(200.0) and raw.drag.size == raw.time.size
    red = towtank.reduce_run(raw, protocol, run=21, file="run_021.csv.gz")
    assert red.windows["steady"] is not None and red.speed_mean > 0.5
    day = sample_hull_day  # the same run, reduced as the day does
    assert red.drag_mean_raw == day.reductions[21].drag_mean_raw
    assert red.speed_mean == day.reductions[21].speed_mean


def test_bad_protocol_is_a_protocol_error(tmp_path):
    bad = tmp_path / "p.toml"
    bad.write_text("[campaign]\nname = 1\n")
    with pytest.raises(towtank.ProtocolError):
        towtank.process_day(bad)


def test_public_names():
    assert set(towtank.__all__) >= {"process_day", "load_protocol", "read_run", "reduce_run",
                                    "DayResult", "ProtocolError"}
    for name in towtank.__all__:
        assert getattr(towtank, name) is not None
    code = textwrap.dedent("""\
        import sys, towtank
        assert "pandas" not in sys.modules and "towtank.pipeline" not in sys.modules
    """)
    subprocess.run([sys.executable, "-c", code], check=True)


def _session() -> str:
    """The code block of docs/api.md's "A notebook session"."""
    text = (ROOT / "docs" / "api.md").read_text(encoding="utf-8")
    section = text.split("## A notebook session", 1)[1]
    return section.split("```python\n", 1)[1].split("```", 1)[0]


def test_the_notebook_session_of_the_docs_runs(monkeypatch, capsys):
    """Every statement of docs/api.md's notebook session runs, from the repository's folder,
    and gives what its comment says: the summary table, 90 % intervals inside the 95 % ones,
    the estimate's own interval equal to the table's, and figures from the results."""
    import ast

    import matplotlib

    matplotlib.use("Agg")
    monkeypatch.chdir(ROOT)
    code = _session()
    names: dict[str, object] = {}
    for node in ast.parse(code).body:  # one statement at a time, as a notebook's cells
        exec(compile(ast.Module([node], []), "docs/api.md", "exec"), names)
    printed = capsys.readouterr().out
    day, ci, est = names["day"], names["ci"], names["est"]
    assert "X_udot" in printed and "[0.025" in printed and "0.975]" in printed
    coef = day.coefficients.set_index("symbol")
    assert list(ci.columns) == ["lower", "upper"] and ci.index.name == "symbol"
    wide = day.hull.conf_int()
    assert wide["lower"].to_numpy() == pytest.approx(coef.loc[wide.index, "ci_low"].to_numpy())
    assert (ci["lower"] > wide["lower"]).all() and (ci["upper"] < wide["upper"]).all()
    assert est.conf_int(0.10) == pytest.approx(tuple(ci.loc["X_udot"]))
    assert est.agreement.agrees
    assert len(names["fig"].axes[0].lines) + len(names["fig"].axes[0].containers) > 0
    assert len(repr(day)) < 5000 and "DataFrame" not in repr(day)
    assert len(day._repr_html_()) < 20000 and "X_udot" in day._repr_html_()
    # the scaling stage gives its own table: the hull's is not written into
    assert day.hull.coefficients["prototype_value"].isna().all()
    assert day.prototype_values["prototype_value"].notna().all()
    assert coef["prototype_value"].to_numpy() == pytest.approx(
        day.prototype_values.set_index("symbol").loc[coef.index, "prototype_value"].to_numpy())
    import dataclasses

    with pytest.raises(dataclasses.FrozenInstanceError):
        day.hull = None
    import matplotlib.pyplot as plt

    plt.close("all")


def test_conf_int_follows_alpha_with_the_estimates_own_dof():
    """A 90 % interval is value ∓ t₀.₉₅(ν)·u_c: narrower than the 95 % one by t₀.₉₅/t₀.₉₇₅ at
    each estimate's own Welch–Satterthwaite ν."""
    import math

    from scipy import stats

    from towtank.analysis.hull import Estimate

    e = Estimate("X_udot", -0.017, 0.0005, -0.017 - stats.t.ppf(0.975, 6) * 0.0005,
                 -0.017 + stats.t.ppf(0.975, 6) * 0.0005, "m", 6, dof=6.0)
    lo, hi = e.conf_int(0.10)
    assert hi - lo == pytest.approx(2 * stats.t.ppf(0.95, 6) * 0.0005, rel=1e-12)
    assert (lo, hi) != pytest.approx((e.ci_low, e.ci_high))
    assert e.conf_int() == (e.ci_low, e.ci_high)
    assert math.isinf(Estimate("x", 1.0, 0.1, 0, 2, "m", 1, dof=0.0).conf_int(0.2)[1])


def test_namespace_and_reprs_are_short():
    public = [n for n in dir(towtank) if not n.startswith("__")]
    assert "Any" not in public and "annotations" not in public
    assert set(dir(towtank)) == set(towtank.__all__)
    assert towtank.DayResult.__module__ == "towtank.results"


def test_verdicts_are_typed_and_survive_copy():
    import copy
    import pickle

    from towtank.analysis.hull import Agreement, agreement

    v = agreement(1.000, 1.010, 0.001, 0.0)
    assert isinstance(v, Agreement) and not v.agrees
    assert v.difference == pytest.approx(0.010) and v.tolerance == pytest.approx(0.002)
    assert str(v) == "DISAGREE: difference +0.01 kg exceeds 0.002 kg"  # the CSV's sentence
    assert not isinstance(v, str) and v.verdict == "DISAGREE"  # a verdict, not a string
    for again in (copy.deepcopy(v), pickle.loads(pickle.dumps(v))):
        assert isinstance(again, Agreement) and again.agrees is False and again == v
    assert agreement(1.0, 1.001, 0.001, 0.0).agrees


@pytest.mark.heavy
def test_a_fin_day_shows_as_its_runs_and_its_fin_result(sample_fin_day):
    """A day without hull coefficients: its summary is the runs by configuration and status,
    its FinResult prints in one line and gives fins.csv; nothing raises for the absent stages."""
    day = sample_fin_day
    assert day.hull is None and day.fins is not None
    text = str(day.summary())
    assert "fin" in text and "ok" in text and len(repr(day)) < 5000
    assert "stages: fins" in repr(day)
    assert repr(day.fins).startswith("FinResult(") and "\n" not in repr(day.fins)
    pd.testing.assert_frame_equal(day.fins.to_frame(), day.table("fins"))
    assert day.coefficients.empty and list(day.coefficients.columns)[:2] == ["symbol", "value"]
    assert isinstance(day.fins, towtank.FinResult)
    assert "<table" in day._repr_html_() and "<table" in day.tare._repr_html_()
    from towtank.report import figures

    fig = figures.fig_fin_coefficients(day.fins)  # the result drawn, not the day
    assert fig is not None and len(fig.axes) == 2
    assert len(figures.fig_fin_forces(day.fins).axes) == len(
        figures.fig_fin_forces(day).axes)


def test_a_notice_is_its_sentence_with_its_stage():
    from towtank.results import Notice, notices

    n = Notice("run 3: the speed varies.", "reduce", run=3, file="run_003.csv")
    assert str(n) == "run 3: the speed varies." and f"{n}" == str(n)
    assert (n.stage, n.run, n.file) == ("reduce", 3, "run_003.csv")
    assert n == Notice("run 3: the speed varies.", "reduce", 3, "run_003.csv")
    assert n != Notice("run 3: the speed varies.", "sheet", 3, "run_003.csv")
    assert [(m.text, m.stage, m.run) for m in notices(["a.", "b."], "hull")] == [
        ("a.", "hull", None), ("b.", "hull", None)]
    with pytest.raises(ValueError, match="stage"):
        Notice("text", "fitting")  # type: ignore[arg-type]
    with pytest.raises(AttributeError):
        n.text = "other"  # type: ignore[misc]



# ------------------------------------------------------------ one vocabulary of the results
@pytest.fixture(scope="session")
def sample_hull_day(sample_report):
    """The sample hull day as ``towtank.process_day(HULL, out=..., report=True)`` returns it:
    the session's day (tests/conftest.py), which the golden comparison writes anyway."""
    return sample_report("sut2_hull").day


@pytest.fixture(scope="session")
def sample_fin_day(sample_report):
    """The sample fin day as ``towtank.process_day`` returns it: the session's day
    (tests/conftest.py), which the golden comparison writes anyway."""
    return sample_report("naca0015_fin").day


@pytest.fixture(scope="session")
def remus_sine(tmp_path_factory):
    """REMUS's predicted model (neutrally buoyant) and one period (10 s) of a noisy rudder
    sine recorded at 10 Hz."""
    import contextlib
    import io
    import json

    import numpy as np

    from towtank.commands.cli import main
    from towtank.vehicle.simulate import simulate

    out = tmp_path_factory.mktemp("remus")
    with contextlib.redirect_stdout(io.StringIO()):
        assert main(["predict", str(ROOT / "protocols" / "remus_vehicle.toml"), "--out",
                     str(out)]) == 0
    model = json.loads((out / "model.json").read_text())
    model["buoyancy_N"] = model["weight_N"]
    record = simulate(model, "sine", 1.5, rudder_deg=10.0, period_s=10.0, duration_s=10.0,
                      sample_hz=10.0)
    record = record[["t_s", "x_m", "y_m", "psi_deg", "u_m_s", "v_m_s", "r_deg_s",
                     "rudder_deg", "sternplane_deg"]].copy()
    rng = np.random.default_rng(1)
    for column, sd in {"u_m_s": 0.01, "v_m_s": 0.01, "r_deg_s": 0.2, "psi_deg": 0.5}.items():
        record[column] += rng.normal(0.0, sd, len(record))
    return model, record


@pytest.fixture(scope="session")
def short_identification(remus_sine):
    """N_ur and N_uudr of REMUS by the filter from :func:`remus_sine`: an IdentifyResult with
    estimates and intervals, which is all the vocabulary test reads (the filter's accuracy
    is tested in test_identify*.py)."""
    model, record = remus_sine
    return towtank.identify(model, record, ["N_ur", "N_uudr"], check=False)


@pytest.mark.heavy
def test_identify_takes_one_symbol_alone(remus_sine):
    """``estimate="N_ur"`` is the list ``["N_ur"]``, not the letters N, _, u, r."""
    model, record = remus_sine
    result = towtank.identify(model, record, "N_ur", check=False)
    assert list(result.params.index) == ["N_ur"]


#: Every result with estimates: (class name, a factory of one from the test's request). A new
#: result with estimates (the captive-model result) joins here.
RESULTS_WITH_ESTIMATES: tuple[tuple[str, Callable[[pytest.FixtureRequest], Any]], ...] = (
    ("HullResult", lambda request: request.getfixturevalue("sample_hull_day").hull),
    ("FinResult", lambda request: request.getfixturevalue("sample_fin_day").fins),
    ("ScalingResult", lambda request: request.getfixturevalue("sample_hull_day").scaling),
    ("TareResult", lambda request: request.getfixturevalue("sample_hull_day").tare),
    ("IdentifyResult", lambda request: request.getfixturevalue("short_identification")),
    ("CaptiveResult", lambda request: _captive_result(request)),
)


@pytest.mark.heavy
@pytest.mark.parametrize(("name", "factory"), RESULTS_WITH_ESTIMATES,
                         ids=[n for n, _ in RESULTS_WITH_ESTIMATES])
def test_every_result_with_estimates_speaks_one_vocabulary(name, factory, request):
    """params and bse are Series by symbol, conf_int has the columns lower and upper at every
    level (the 90 % interval inside the 95 % one), summary() is a Summary, to_frame() a
    DataFrame."""
    from towtank.results import Summary

    result = factory(request)
    assert type(result).__name__ == name and type(result).__module__.startswith(
        "towtank.results")
    params, bse = result.params, result.bse
    for series in (params, bse):
        assert isinstance(series, pd.Series) and series.index.name == "symbol"
        assert len(series) > 0 and series.index.is_unique
    assert list(bse.index) == list(params.index)
    wide, narrow = result.conf_int(0.05), result.conf_int(0.10)
    assert list(wide.columns) == list(narrow.columns) == ["lower", "upper"]
    assert list(wide.index) == list(narrow.index) == list(params.index)
    known = wide.notna().all(axis=1) & narrow.notna().all(axis=1)
    assert known.any()
    assert (wide.loc[known, "lower"] <= narrow.loc[known, "lower"]).all()
    assert (narrow.loc[known, "upper"] <= wide.loc[known, "upper"]).all()
    assert (narrow.loc[known, "lower"] <= params[known]).all()
    assert (params[known] <= narrow.loc[known, "upper"]).all()
    pd.testing.assert_frame_equal(result.conf_int(), wide)
    for summary in (result.summary(), result.summary(0.10)):
        assert isinstance(summary, Summary) and list(params.index)[0] in str(summary)
    assert isinstance(result.to_frame(), pd.DataFrame) and len(result.to_frame()) > 0
    # in a notebook: its summary table, never its raw frames
    assert result._repr_html_() == result.summary()._repr_html_()
    frame = result.to_frame()  # a copy: editing it leaves the result as it was
    frame["edited"] = 1.0
    assert "edited" not in result.to_frame()


def _captive_result(request: pytest.FixtureRequest) -> Any:
    from towtank.testing.captive import simulated_result

    return simulated_result(seed=1)


@pytest.mark.parametrize(("call", "error", "words"), [
    (lambda: towtank.process_day(None), TypeError, "protocol must be the path"),
    (lambda: towtank.process_day({"campaign": {}}), TypeError, "not dict"),
    (lambda: towtank.process_day(HULL, jobs="2"), TypeError, "jobs must be a whole number"),
    (lambda: towtank.process_day(HULL, jobs=0), ValueError, "jobs must be at least 1"),
    (lambda: towtank.process_day(HULL, date="2024-13-40"), ValueError,
     "'2024-13-40' is not a date that exists"),
    (lambda: towtank.process_day(HULL, date=20240517), TypeError, "date must be a text"),
    (lambda: towtank.read_run(RUN_21, 5), TypeError, "protocol must be the path"),
    (lambda: towtank.read_run(RUN_21, HULL, segment="2"), TypeError, "segment must be"),
    (lambda: towtank.reduce_run(str(RUN_21), HULL), TypeError,
     "reduce_run takes the RawRun that towtank.read_run returns, not str"),
    (lambda: towtank.reduce_run(towtank.read_run(RUN_21, HULL), HULL, run=21, window_s=5.0),
     TypeError, "window_s must be a (start, end) pair"),
], ids=["process-none", "process-dict", "jobs-text", "jobs-0", "date-13-40", "date-int",
        "read-int-protocol", "segment-text", "reduce-a-path", "window-one-number"])
def test_a_wrong_argument_is_one_sentence_naming_it(call, error, words):
    """A notebook's slips with the API's arguments: the error Python uses for them (TypeError
    for the wrong kind, ValueError for the wrong value), raised before anything is read or
    written, in one sentence that names the argument (not an AttributeError from deep inside,
    nor a date the report would print as given)."""
    with pytest.raises(error) as caught:
        call()
    text = str(caught.value)
    assert words in text and "\n" not in text
    assert caught.traceback[-1].path.name == "api.py"


def test_an_empty_summary_says_so():
    """A summary without rows (a hull stage that gave no coefficient) prints its title and
    "(no estimates)", never pandas' "Empty DataFrame"."""
    from towtank.results import Summary

    text = str(Summary(title="day: Hull coefficients (0 estimates)", table=pd.DataFrame(),
                       notes=("12 runs, 12 reduced, 0 rejected",)))
    assert "(no estimates)" in text and "Empty DataFrame" not in text
    assert text.splitlines()[-1] == "12 runs, 12 reduced, 0 rejected"


def test_the_days_tables_are_copies_to_edit(sample_hull_day, sample_fin_day):
    """``day.coefficients`` and ``day.table(...)`` are the day's CSV tables as copies: a
    column added to one is in neither the day nor its stage's result afterwards (on the hull
    day without a [vehicle], coefficients.csv was the hull result's own frame)."""
    for day, get, own in (
            (sample_hull_day, lambda d: d.coefficients, lambda d: d.hull.coefficients),
            (sample_hull_day, lambda d: d.table("scaling"), lambda d: d.scaling.table),
            (sample_fin_day, lambda d: d.table("fins"), lambda d: d.fins.table)):
        frame = get(day)
        frame["edited"] = 1.0
        assert "edited" not in get(day) and "edited" not in own(day)
