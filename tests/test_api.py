"""The public Python API (towtank.process_day and friends) in scripts, ``python -c``, ``python -``
and in-process: the same coefficients as the command line, no traceback, nothing rejected."""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

import pandas as pd
import pytest

import towtank

ROOT = Path(__file__).resolve().parents[1]
HULL = ROOT / "protocols" / "sut2_hull.toml"


@pytest.fixture(scope="module")
def cli_coefficients(tmp_path_factory) -> pd.DataFrame:
    from towtank.commands.cli import main

    out = tmp_path_factory.mktemp("cli") / "out"
    assert main(["process", str(HULL), "--out", str(out), "--no-report", "-q"]) == 0
    return pd.read_csv(out / "coefficients.csv")


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


def test_process_day_in_process_returns_the_day(cli_coefficients):
    day = towtank.process_day(HULL, jobs=1)
    assert day.n_rejected == 0 and not day.rejected
    _same(day.coefficients.pipe(lambda d: pd.read_csv(
        pd.io.common.StringIO(d.to_csv(index=False)))), cli_coefficients)
    assert set(day.runs["status"]) == {"ok", "void"}
    assert list(day.fins.columns)[:2] == ["run", "angle_deg"] and day.fins.empty
    assert len(day.scaling) == 4 and "drag_ittc57" in day.scaling
    assert isinstance(day.warnings, list)


def test_process_day_writes_what_the_cli_writes(tmp_path, cli_coefficients):
    out = tmp_path / "out"
    towtank.process_day(str(HULL), out=out, report=False)
    _same(pd.read_csv(out / "coefficients.csv"), cli_coefficients)
    assert {"runs.csv", "fins.csv", "scaling.csv", "provenance.json"} <= {
        p.name for p in out.iterdir()}
    assert not (out / "report.pdf").exists()


def test_read_and_reduce_one_run():
    protocol = towtank.load_protocol(HULL)
    raw = towtank.read_run(ROOT / "sample_runs/sut2_hull/data/run_021.csv.gz", protocol)
    assert raw.fs == pytest.approx(200.0) and raw.drag.size == raw.time.size
    red = towtank.reduce_run(raw, protocol, run=21, file="run_021.csv.gz")
    assert red.windows["steady"] is not None and red.speed_mean > 0.5
    day = towtank.process_day(protocol, jobs=1)  # the same run, reduced as the day does
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
