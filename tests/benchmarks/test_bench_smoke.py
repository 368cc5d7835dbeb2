"""Smoke test of the campaign benchmark (``python -m towtank.testing.bench``) at a tiny size.

It runs the whole bench end to end and checks that ``bench.json`` holds every figure. No timing
is asserted: the figures depend on the machine. Marked ``bench``: the benchmark starts a dozen
new processes (its cold-start and worker measurements), so it runs apart from the unit tests,
in ``.ci/run``'s own step (``python -m pytest --bench tests/benchmarks/test_bench_smoke.py``).
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.bench

TOP_LEVEL = {
    "runs", "fs_hz", "jobs", "csv_mb", "largest_file_mb", "rows", "generation_s", "machine",
    "startup_help_s", "parse_single_s", "parse_parallel_s", "cold_s", "cold_over_parse_single",
    "cold_over_parse_parallel", "rerun_s", "rerun_over_cold", "added_s", "added_over_cold",
    "peak_rss_main_mb", "peak_rss_workers_mb", "peak_rss_over_largest_file", "scales", "growth",
    "baseline_rss_main_mb", "baseline_rss_workers_mb", "worker_rss_above_baseline_per_largest_file",
    "main_rss_above_baseline_per_run_kb", "parse_single_cpu_s", "cold_cpu_s", "rerun_cpu_s",
    "added_cpu_s", "repeat",
    "peak_rss_by_scale_mb", "status_cold", "status_added", "bench_rss_mb", "targets",
}
#: The campaign's runs at 1x: the smallest whose pool (2x + 1 runs) is one generated chunk
#: (towtank.testing.bench.CHUNK_RUNS); sting tares and an accelerated tare, all reduced "ok".
RUNS = 6
SCALE_FIELDS = {"runs", "csv_mb", "cold_s", "ratio", "rss_main_mb", "rss_workers_mb", "cpu_s"}
TARGETS = {"cold_over_parse", "rerun_over_cold", "added_over_cold", "growth_2x"}


def _bench(workdir: Path) -> subprocess.CompletedProcess[str]:
    cmd = [sys.executable, "-m", "towtank.testing.bench", "--runs", str(RUNS), "--fs", "200",
           "--scales", "1,2", "--workdir", str(workdir), "--markdown"]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=600)


def test_bench_end_to_end(tmp_path: Path) -> None:
    proc = _bench(tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert "cold process" in proc.stdout and "| runs |" in proc.stdout
    res = json.loads((tmp_path / "bench.json").read_text())
    assert TOP_LEVEL <= set(res), TOP_LEVEL - set(res)
    assert res["runs"] == RUNS and res["fs_hz"] == 200
    assert set(res["scales"]) == {"1", "2"}
    for s, row in res["scales"].items():
        assert SCALE_FIELDS <= set(row), (s, SCALE_FIELDS - set(row))
        assert row["runs"] == RUNS * int(s)
    assert set(res["growth"]) == {"1", "2"}
    assert set(res["targets"]) == TARGETS
    for t in res["targets"].values():
        assert {"value", "limit", "met", "what"} <= set(t)
    for key in ("parse_single_s", "parse_parallel_s", "cold_s", "rerun_s", "added_s",
                "startup_help_s", "peak_rss_main_mb", "peak_rss_workers_mb", "csv_mb"):
        assert math.isfinite(res[key]) and res[key] > 0, key
    # every run of the sheet was processed (one added for the incremental measurement)
    assert sum(res["status_cold"].values()) == RUNS
    assert sum(res["status_added"].values()) == RUNS + 1
    assert res["status_cold"].get("ok", 0) >= RUNS - 2

    # the generated campaign is kept: the pool the next bench run asks for (the same runs,
    # rate and seed) is there, with no run generated again
    from towtank.testing.bench import ensure_pool

    said: list[str] = []
    pool, seconds = ensure_pool(tmp_path, 2 * RUNS + 1, 200.0, 1, 1, log=said.append)
    assert seconds == 0.0 and not said and pool.is_dir()
