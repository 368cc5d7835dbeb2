"""Campaign-scale benchmark: ``python -m towtank.testing.bench [--runs 500] [--fs 1000] [--scales
1,2,4]``.

Separate from the unit tests. It writes a large synthetic campaign (plain CSV run files from
:mod:`towtank.testing.synthetic`, lab-style channels in volts) into a work folder, keeps it there
so that
the next bench run does not generate it again, and measures, from one bench run:

* ``parse``: :func:`pyarrow.csv.read_csv` of every run file of the 1x campaign, once in this
  single process and once spread over the same number of worker processes as ``towtank``
  (``--jobs``); both figures are reported, and the ratios are given against both;
* ``cold``: ``towtank process PROTOCOL --no-report --jobs N --out DIR`` as a subprocess into a
  fresh output folder, interpreter start-up included;
* ``rerun``: the same command again, nothing changed (every run from the cache);
* ``added``: one run appended to the run sheet and the data folder, then the command again;
* the peak resident memory (``ru_maxrss``) of the ``towtank`` process itself and of its worker
  processes, against the largest single run file;
* the cold time at every scale of ``--scales`` (the campaign repeated with new runs), as ratios
  to the 1x cold time.

The page cache is warmed (every file read once) before anything is timed, so parse and process
both read the files from memory. The figures are printed as a table and written to
``bench.json`` in the work folder. Generating the campaign is not timed.
"""

from __future__ import annotations

import argparse
import csv
import ctypes
import json
import multiprocessing as mp
import os
import platform
import resource
import shutil
import subprocess
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace
from pathlib import Path
from typing import Any

import pyarrow.csv  # noqa: F401 - imported before the clock starts, as in a warm process
import pyarrow.csv as pacsv

from towtank.runtime.parallel import default_jobs
from towtank.testing import synthetic as syn
from towtank.testing.bytecode import bytecode_env
from towtank.testing.synthetic import RunSpec, hull_protocol_sections, write_protocol

PLAN_VERSION = 1  # bump when the generated campaign changes
CHUNK_RUNS = 20  # runs generated per chunk (the unit of generation, caching and parallelism)
BLOCK_RUNS = 40  # runs of one tare group (one "day" of the campaign)

TARGETS = {
    # name: (limit, description)
    "cold_over_parse": (3.0, "cold process time / single-process parse time"),
    "rerun_over_cold": (0.15, "unchanged re-run / cold"),
    "added_over_cold": (0.25, "one run added / cold"),
    "growth_4x": (4.4, "cold time at 4x the runs / cold time at 1x"),
}

# Runs ``towtank`` in the child exactly as the console script does, then writes the peak
# resident memory of the process itself and of its (reaped) worker processes.
_CHILD = """\
import json, resource, sys
from towtank.commands.cli import main
rc = main(sys.argv[2:])
me = resource.getrusage(resource.RUSAGE_SELF)
kids = resource.getrusage(resource.RUSAGE_CHILDREN)
with open(sys.argv[1], "w") as fh:
    json.dump({"rc": rc, "self_kb": me.ru_maxrss, "children_kb": kids.ru_maxrss,
               "cpu_s": me.ru_utime + me.ru_stime + kids.ru_utime + kids.ru_stime}, fh)
import gc; gc.freeze()  # as towtank.commands.cli.entry does before exiting
sys.exit(rc)
"""


# ============================================================================ the campaign
def block_plan(group: str) -> list[Any]:
    """One tare group's runs: sting tares, hull steady at 0-15 deg, accelerated and transverse.

    40 runs with short plateaus (2 s) and brisk ramps, so a run at 1 kHz is ~10 s and ~0.4 MB
    of CSV.
    """
    plan: list[Any] = []
    for v in (0.4, 0.8, 1.2, 1.6, 2.0):
        plan.append(RunSpec("sting", 0.0, v, 1.0, tare_group=group))
    for acc in (0.5, 1.0):
        plan.append(RunSpec("sting", 0.0, 2.0, acc, test="accel", tare_group=group))
    for ang in (0.0, 2.5, 5.0, 7.5, 10.0, 12.5, 15.0):
        for v in (0.8, 1.2, 1.6, 2.0):
            plan.append(RunSpec("hull", ang, v, 1.0, tare_group=group))
    for acc in (0.5, 1.0):
        plan.append(RunSpec("hull", 0.0, 2.0, acc, test="accel", tare_group=group))
    for v in (0.2, 0.3):
        plan.append(RunSpec("hull", 90.0, v, 0.15, tare_group=group, remarks="transverse tow"))
    plan.append(RunSpec("hull", 90.0, 0.3, 0.2, test="accel", tare_group=group,
                        remarks="transverse tow"))
    assert len(plan) == BLOCK_RUNS
    return [replace(r, plateau_s=2.0) for r in plan]


def campaign_plan(first: int, last: int) -> list[Any]:
    """RunSpecs of runs ``first``..``last`` (1-based, inclusive) of the endless campaign."""
    out = []
    for number in range(first, last + 1):
        block, pos = divmod(number - 1, BLOCK_RUNS)
        out.append(replace(block_plan(f"T{block + 1:03d}")[pos], run=number))
    return out


def _gen_chunk(args: tuple[str, int, float, int]) -> str:
    """Write chunk ``k`` of the pool (runs k·CHUNK_RUNS+1 ...); returns its folder."""
    pool, k, fs, seed = args
    d = Path(pool) / f"chunk_{k:04d}"
    if (d / "done").exists():
        return str(d)
    shutil.rmtree(d, ignore_errors=True)
    plan = campaign_plan(k * CHUNK_RUNS + 1, (k + 1) * CHUNK_RUNS)
    groups = sorted({r.tare_group for r in plan})
    syn.make_hull_day(
        d, seed=seed * 100_003 + k, fs=fs, file_format="csv", sheet_format="csv",
        runs=plan, tares={g: syn.TareTruth() for g in groups},
    )
    (d / "done").write_text("ok\n")
    return str(d)


def ensure_pool(workdir: Path, n_runs: int, fs: float, seed: int, jobs: int,
                log: Any = print) -> tuple[Path, float]:
    """The generated runs 1..n_runs (or more) under ``workdir``; generated only when missing.

    Returns the pool folder and the seconds spent generating (0 when everything was there).
    """
    pool = workdir / f"pool-v{PLAN_VERSION}-fs{fs:g}-seed{seed}"
    pool.mkdir(parents=True, exist_ok=True)
    n_chunks = -(-n_runs // CHUNK_RUNS)
    todo = [k for k in range(n_chunks) if not (pool / f"chunk_{k:04d}" / "done").exists()]
    if not todo:
        return pool, 0.0
    log(f"generating {len(todo) * CHUNK_RUNS} synthetic runs at {fs:g} Hz in {pool} "
        f"(once; kept for the next bench runs) ...")
    t0 = time.perf_counter()
    args = [(str(pool), k, fs, seed) for k in todo]
    if jobs > 1 and len(todo) > 1:
        with ProcessPoolExecutor(max_workers=jobs, mp_context=mp.get_context("fork")) as ex:
            list(ex.map(_gen_chunk, args))
    else:
        for a in args:
            _gen_chunk(a)
    return pool, time.perf_counter() - t0


def _pool_rows(pool: Path, n_runs: int) -> tuple[list[str], list[dict[str, str]]]:
    """Header and sheet rows of runs 1..n_runs from the pool's chunk sheets."""
    header: list[str] = []
    rows: list[dict[str, str]] = []
    k = 0
    while len(rows) < n_runs:
        with open(pool / f"chunk_{k:04d}" / "run_sheet.csv", newline="") as fh:
            reader = csv.DictReader(fh)
            header = list(reader.fieldnames or [])
            for row in reader:
                row["file"] = f"chunk_{k:04d}/{row['file']}"  # pool-relative, fixed below
                rows.append(row)
        k += 1
    return header, rows[:n_runs]


def _link(src: Path, dst: Path) -> None:
    try:
        os.link(src, dst)
    except OSError:
        shutil.copy2(src, dst)


def write_sheet(path: Path, header: list[str], rows: list[dict[str, str]]) -> None:
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=header, lineterminator="\n")
        w.writeheader()
        w.writerows(rows)


def build_campaign(workdir: Path, pool: Path, n_runs: int, name: str) -> dict[str, Any]:
    """A campaign folder of runs 1..n_runs: data/ (hard links into the pool), sheet, protocol."""
    d = workdir / "campaigns" / name
    shutil.rmtree(d, ignore_errors=True)
    (d / "data").mkdir(parents=True)
    header, rows = _pool_rows(pool, n_runs)
    files = []
    for row in rows:
        src = pool / row["file"].split("/")[0] / "data" / row["file"].split("/")[1]
        row["file"] = src.name
        _link(src, d / "data" / src.name)
        files.append(d / "data" / src.name)
    write_sheet(d / "run_sheet.csv", header, rows)
    protocol = write_protocol(
        d / "protocol.toml",
        header=f"towtank.testing.bench campaign: {n_runs} synthetic runs",
        **hull_protocol_sections(".", "out", sheet_format="csv"),
    )
    return {"dir": d, "protocol": protocol, "files": files, "header": header, "rows": rows}


def append_run(camp: dict[str, Any], pool: Path, number: int) -> Path:
    """Add run ``number`` of the pool to the campaign's sheet and data folder."""
    _, rows = _pool_rows(pool, number)
    row = rows[number - 1]
    src = pool / row["file"].split("/")[0] / "data" / row["file"].split("/")[1]
    row["file"] = src.name
    _link(src, camp["dir"] / "data" / src.name)
    camp["rows"].append(row)
    camp["files"].append(camp["dir"] / "data" / src.name)
    write_sheet(camp["dir"] / "run_sheet.csv", camp["header"], camp["rows"])
    return src


# ============================================================================ measurements
def warm(files: list[Path]) -> int:
    """Read every file once (page cache); returns the bytes read."""
    n = 0
    for f in files:
        with open(f, "rb") as fh:
            n += len(fh.read())
    return n


def _parse_one(path: str) -> int:
    return pacsv.read_csv(path).num_rows


def _parse_many(paths: list[str]) -> int:
    return sum(_parse_one(p) for p in paths)


_LAST_PARSE_CPU = [0.0]


def parse_time(files: list[Path], jobs: int) -> tuple[float, int]:
    """Seconds to pyarrow-parse every file, in this process (jobs=1) or over ``jobs`` workers.

    The workers are forked fresh (their start-up is included), each takes an interleaved share.
    """
    paths = [str(f) for f in files]
    if jobs <= 1:
        t0 = time.perf_counter()
        c0 = time.process_time()
        rows = _parse_many(paths)
        _LAST_PARSE_CPU[0] = time.process_time() - c0
        return time.perf_counter() - t0, rows
    t0 = time.perf_counter()
    with ProcessPoolExecutor(max_workers=jobs, mp_context=mp.get_context("fork")) as ex:
        rows = sum(ex.map(_parse_many, [paths[i::jobs] for i in range(jobs)]))
    return time.perf_counter() - t0, rows


_CHILD_ENV: dict[str, str] | None = None


def child_env(workdir: Path) -> dict[str, str]:
    """The environment of the timed ``towtank`` processes.

    Where bytecode writing is switched off (``PYTHONDONTWRITEBYTECODE``, common in sandboxes and
    containers) every start would compile towtank's modules again, which an installed package
    never does: the bytecode is then kept under the work folder (``PYTHONPYCACHEPREFIX``) and
    written by the untimed warm-up run.
    """
    return bytecode_env(os.environ, workdir / "pycache")


def _become_subreaper() -> bool:
    """Adopt the orphans of the processes this one starts (Linux ``PR_SET_CHILD_SUBREAPER``).

    ``towtank``'s workers are forked by a fork server, a child of ``towtank`` that outlives it by
    a moment; adopted here, the fork server is reaped by this process, and with it the CPU time
    and peak memory of the workers it reaped.
    """
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        return libc.prctl(36, 1, 0, 0, 0) == 0  # PR_SET_CHILD_SUBREAPER
    except (OSError, AttributeError):  # pragma: no cover - not Linux
        return False


def _reap_orphans(timeout_s: float = 10.0) -> tuple[float, float]:
    """Reap the adopted processes; (largest peak RSS [kB], CPU time [s]) of them and theirs."""
    peak_kb, cpu = 0.0, 0.0
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        try:
            pid, _, ru = os.wait4(-1, os.WNOHANG)
        except ChildProcessError:
            break  # none left
        if pid == 0:
            time.sleep(0.01)
            continue
        peak_kb = max(peak_kb, float(ru.ru_maxrss))
        cpu += ru.ru_utime + ru.ru_stime
    return peak_kb, cpu


_SUBREAPER: list[bool] = []


def run_towtank(args: list[str], tmp: Path) -> dict[str, Any]:
    """Run ``towtank ARGS`` in a fresh interpreter; wall time and peak memory.

    The wall time ends when ``towtank`` exits; the memory and CPU time include every process it
    started (its workers and their fork server, adopted and reaped here where the system allows).
    """
    if not _SUBREAPER:
        _SUBREAPER.append(_become_subreaper())
    out_json = tmp / f"rusage-{time.monotonic_ns()}.json"
    cmd = [sys.executable, "-c", _CHILD, str(out_json), *args]
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True, env=_CHILD_ENV)
    wall = time.perf_counter() - t0
    orphan_kb, orphan_cpu = _reap_orphans() if _SUBREAPER[0] else (0.0, 0.0)
    if proc.returncode not in (0, 1):
        raise RuntimeError(
            f"towtank {' '.join(args)} failed (exit {proc.returncode}):\n{proc.stderr[-4000:]}"
        )
    info = json.loads(out_json.read_text())
    out_json.unlink()
    return {
        "seconds": wall,
        "rc": proc.returncode,
        "rss_main_mb": info["self_kb"] / 1024.0,
        "rss_workers_mb": max(info["children_kb"], orphan_kb) / 1024.0,
        "cpu_s": info["cpu_s"] + orphan_cpu,
    }


def startup_time(repeat: int = 3) -> float:
    """Best wall time of ``towtank --help`` (the console script, else ``python -m towtank``)."""
    script = Path(sys.executable).with_name("towtank")
    cmd = [str(script), "--help"] if script.exists() else [sys.executable, "-m", "towtank",
                                                           "--help"]
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True,
                       env=_CHILD_ENV)
        best = min(best, time.perf_counter() - t0)
    return best


def status_counts(out_dir: Path) -> dict[str, int]:
    counts: dict[str, int] = {}
    with open(out_dir / "runs.csv", newline="") as fh:
        for row in csv.DictReader(fh):
            counts[row["status"]] = counts.get(row["status"], 0) + 1
    return counts


def process(protocol: Path, out: Path, jobs: int, tmp: Path) -> dict[str, Any]:
    res = run_towtank(["process", str(protocol), "--no-report", "--quiet", "--jobs", str(jobs),
                       "--out", str(out)], tmp)
    res["status"] = status_counts(out)
    return res


# ============================================================================ report
def _ratio(a: float, b: float) -> float:
    return a / b if b > 0 else float("nan")


def run_bench(
    workdir: Path,
    *,
    runs: int = 500,
    fs: float = 1000.0,
    scales: tuple[int, ...] = (1, 2, 4),
    jobs: int | None = None,
    seed: int = 1,
    repeat: int = 1,
    log: Any = print,
) -> dict[str, Any]:
    """Generate (once) and measure; returns the figures written to ``bench.json``.

    With ``repeat`` > 1 every measurement is repeated and its best (smallest) time kept, which
    filters out other load on the machine; peak memory is the largest seen.
    """
    global _CHILD_ENV
    jobs = default_jobs() if jobs is None else max(1, jobs)
    repeat = max(1, repeat)
    scales = tuple(sorted(set(scales) | {1}))
    workdir = workdir.resolve()
    workdir.mkdir(parents=True, exist_ok=True)
    _CHILD_ENV = child_env(workdir)
    tmp = workdir / "tmp"
    tmp.mkdir(exist_ok=True)
    pool, gen_s = ensure_pool(workdir, max(scales) * runs + 1, fs, seed, jobs, log)

    camps = {s: build_campaign(workdir, pool, s * runs, f"x{s}") for s in scales}
    base = camps[1]
    for s in scales:
        warm(camps[s]["files"])
    sizes = [f.stat().st_size for f in base["files"]]
    csv_bytes = sum(sizes)
    outs = workdir / "out"
    shutil.rmtree(outs, ignore_errors=True)
    # untimed run on a small campaign: interpreter, libraries and bytecode into the caches
    # (its peak memory is the baseline: interpreter and libraries, hardly any data)
    tiny = build_campaign(workdir, pool, min(runs, 4), "warmup")
    baseline = process(tiny["protocol"], outs / "warmup", jobs, tmp)

    log(f"campaign: {runs} runs, {csv_bytes / 1e6:.0f} MB of CSV at {fs:g} Hz; "
        f"jobs = {jobs}; measuring{f' (best of {repeat})' if repeat > 1 else ''} ...")
    res: dict[str, Any] = {
        "runs": runs,
        "fs_hz": fs,
        "jobs": jobs,
        "repeat": repeat,
        "csv_mb": csv_bytes / 1e6,
        "largest_file_mb": max(sizes) / 1e6,
        "generation_s": gen_s,
        "machine": {
            "cpus": os.cpu_count(),
            "python": platform.python_version(),
            "platform": platform.platform(),
            "load_average_at_start": list(os.getloadavg()),
        },
    }
    res["startup_help_s"] = startup_time(max(3, repeat))
    parse_1, parse_j, parse_cpu = [], [], []
    for _ in range(repeat):
        t, rows_1 = parse_time(base["files"], 1)
        parse_1.append(t)
        parse_cpu.append(_LAST_PARSE_CPU[0])
        t, rows_j = parse_time(base["files"], jobs)
        parse_j.append(t)
        assert rows_1 == rows_j
    res["parse_single_s"], res["parse_parallel_s"] = min(parse_1), min(parse_j)
    res["parse_single_cpu_s"] = min(parse_cpu)
    res["rows"] = rows_1

    out1 = outs / "x1"
    seen: dict[str, list[dict[str, Any]]] = {"cold": [], "rerun": [], "added": []}
    for _ in range(repeat):
        camp = build_campaign(workdir, pool, runs, "x1")
        shutil.rmtree(out1, ignore_errors=True)
        seen["cold"].append(process(camp["protocol"], out1, jobs, tmp))
        seen["rerun"].append(process(camp["protocol"], out1, jobs, tmp))
        append_run(camp, pool, runs + 1)
        seen["added"].append(process(camp["protocol"], out1, jobs, tmp))
    cold, rerun, added = (min(seen[k], key=lambda r: r["seconds"])
                          for k in ("cold", "rerun", "added"))
    everything = [r for v in seen.values() for r in v]
    res["cold_s"] = cold["seconds"]
    res["cold_over_parse_single"] = _ratio(cold["seconds"], res["parse_single_s"])
    res["cold_over_parse_parallel"] = _ratio(cold["seconds"], res["parse_parallel_s"])
    res["rerun_s"] = rerun["seconds"]
    res["rerun_over_cold"] = _ratio(rerun["seconds"], cold["seconds"])
    res["added_s"] = added["seconds"]
    res["added_over_cold"] = _ratio(added["seconds"], cold["seconds"])
    for k in ("cold", "rerun", "added"):  # CPU seconds (process and workers): load-robust
        res[f"{k}_cpu_s"] = min(r["cpu_s"] for r in seen[k])
    res["status_cold"] = cold["status"]
    res["status_added"] = added["status"]
    res["peak_rss_main_mb"] = max(r["rss_main_mb"] for r in everything)
    res["peak_rss_workers_mb"] = max(r["rss_workers_mb"] for r in everything)
    res["peak_rss_over_largest_file"] = _ratio(
        max(res["peak_rss_main_mb"], res["peak_rss_workers_mb"]), res["largest_file_mb"]
    )
    # above the baseline of a 4-run day (libraries), per MB of the largest run file
    res["baseline_rss_main_mb"] = baseline["rss_main_mb"]
    res["baseline_rss_workers_mb"] = baseline["rss_workers_mb"]
    res["worker_rss_above_baseline_per_largest_file"] = _ratio(
        res["peak_rss_workers_mb"] - baseline["rss_workers_mb"], res["largest_file_mb"]
    )
    res["main_rss_above_baseline_per_run_kb"] = _ratio(
        1024.0 * (res["peak_rss_main_mb"] - baseline["rss_main_mb"]), runs + 1
    )

    scale_rows = {1: {"runs": runs, "csv_mb": res["csv_mb"], "cold_s": cold["seconds"],
                      "ratio": 1.0, "rss_main_mb": cold["rss_main_mb"],
                      "rss_workers_mb": cold["rss_workers_mb"], "cpu_s": res["cold_cpu_s"],
                      "status": cold["status"]}}
    for s in scales:
        if s == 1:
            continue
        tries = []
        for _ in range(repeat):
            shutil.rmtree(outs / f"x{s}", ignore_errors=True)
            tries.append(process(camps[s]["protocol"], outs / f"x{s}", jobs, tmp))
        r = min(tries, key=lambda r: r["seconds"])
        scale_rows[s] = {
            "runs": s * runs,
            "csv_mb": sum(f.stat().st_size for f in camps[s]["files"]) / 1e6,
            "cold_s": r["seconds"],
            "ratio": _ratio(r["seconds"], cold["seconds"]),
            "rss_main_mb": max(t["rss_main_mb"] for t in tries),
            "rss_workers_mb": max(t["rss_workers_mb"] for t in tries),
            "cpu_s": min(t["cpu_s"] for t in tries),
            "status": r["status"],
        }
    res["scales"] = {str(s): v for s, v in sorted(scale_rows.items())}
    res["growth"] = {str(s): v["ratio"] for s, v in sorted(scale_rows.items())}
    res["peak_rss_by_scale_mb"] = {
        str(s): max(v["rss_main_mb"], v["rss_workers_mb"]) for s, v in sorted(scale_rows.items())
    }
    res["bench_rss_mb"] = _self_rss_mb()
    res["targets"] = _targets(res, max(scales))
    (workdir / "bench.json").write_text(json.dumps(res, indent=2, sort_keys=True) + "\n")
    shutil.rmtree(tmp, ignore_errors=True)
    return res


def _self_rss_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def _targets(res: dict[str, Any], top: int) -> dict[str, Any]:
    values = {
        "cold_over_parse": res["cold_over_parse_single"],
        "rerun_over_cold": res["rerun_over_cold"],
        "added_over_cold": res["added_over_cold"],
    }
    out: dict[str, Any] = {}
    for name, v in values.items():
        limit, what = TARGETS[name]
        out[name] = {"value": v, "limit": limit, "met": bool(v <= limit), "what": what}
    if top > 1:
        limit = 1.1 * top  # linear: k times the runs within 10 % of k times the time
        v = res["growth"][str(top)]
        out[f"growth_{top}x"] = {"value": v, "limit": limit, "met": bool(v <= limit),
                                 "what": f"cold time at {top}x the runs / cold time at 1x"}
    return out


def format_table(res: dict[str, Any]) -> str:
    """The compact text table printed at the end."""
    j = res["jobs"]
    lines = [
        f"towtank bench: {res['runs']} runs, {res['csv_mb']:.0f} MB CSV at {res['fs_hz']:g} Hz, "
        f"{res['rows']:,} rows; {j} jobs, {res['machine']['cpus']} CPUs; page cache warm"
        + (f"; best of {res['repeat']}" if res.get("repeat", 1) > 1 else ""),
        f"  {'towtank --help (start-up)':<38}{res['startup_help_s']:8.2f} s",
        f"  {'parse, pyarrow, 1 process':<38}{res['parse_single_s']:8.2f} s   "
        f"cpu {res['parse_single_cpu_s']:.2f} s",
        f"  {f'parse, pyarrow, {j} worker processes':<38}{res['parse_parallel_s']:8.2f} s",
        f"  {'cold process (start-up included)':<38}{res['cold_s']:8.2f} s   "
        f"{res['cold_over_parse_single']:.2f}x parse(1 proc), "
        f"{res['cold_over_parse_parallel']:.2f}x parse({j} procs); cpu {res['cold_cpu_s']:.2f} s",
        f"  {'unchanged re-run':<38}{res['rerun_s']:8.2f} s   "
        f"{100 * res['rerun_over_cold']:.1f} % of cold; cpu {res['rerun_cpu_s']:.2f} s",
        f"  {'one run added':<38}{res['added_s']:8.2f} s   "
        f"{100 * res['added_over_cold']:.1f} % of cold; cpu {res['added_cpu_s']:.2f} s",
        f"  {'peak RSS: towtank process':<38}{res['peak_rss_main_mb']:8.0f} MB",
        f"  {'peak RSS: largest worker':<38}{res['peak_rss_workers_mb']:8.0f} MB   "
        f"largest run file {res['largest_file_mb']:.2f} MB",
        f"  {'  above a 4-run day (libraries)':<38}"
        f"main +{res['peak_rss_main_mb'] - res['baseline_rss_main_mb']:.0f} MB "
        f"({res['main_rss_above_baseline_per_run_kb']:.0f} kB/run), worker "
        f"+{res['peak_rss_workers_mb'] - res['baseline_rss_workers_mb']:.0f} MB "
        f"({res['worker_rss_above_baseline_per_largest_file']:.1f}x the largest file)",
        "  scaling of the cold time:",
    ]
    for s, v in res["scales"].items():
        lines.append(
            f"    {s:>2}x {v['runs']:6d} runs {v['csv_mb']:7.0f} MB {v['cold_s']:8.2f} s  "
            f"x{v['ratio']:.2f}   cpu {v['cpu_s']:6.2f} s   "
            f"peak RSS {max(v['rss_main_mb'], v['rss_workers_mb']):.0f} MB"
        )
    lines.append("  targets:")
    for t in res["targets"].values():
        mark = "ok  " if t["met"] else "MISS"
        lines.append(f"    [{mark}] {t['what']}: {t['value']:.3f} (<= {t['limit']:g})")
    return "\n".join(lines)


def markdown_row(res: dict[str, Any]) -> str:
    top = max(res["scales"], key=int)
    return (
        "| runs | MB CSV | parse (1 proc) | parse (" + str(res["jobs"]) + " procs) | cold | "
        "cold/parse | re-run | /cold | one added | /cold | peak RSS | 1x→" + top + "x |\n"
        "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n"
        f"| {res['runs']} | {res['csv_mb']:.0f} | {res['parse_single_s']:.2f} s | "
        f"{res['parse_parallel_s']:.2f} s | {res['cold_s']:.2f} s | "
        f"{res['cold_over_parse_single']:.2f} | {res['rerun_s']:.2f} s | "
        f"{100 * res['rerun_over_cold']:.0f} % | {res['added_s']:.2f} s | "
        f"{100 * res['added_over_cold']:.0f} % | "
        f"{max(res['peak_rss_main_mb'], res['peak_rss_workers_mb']):.0f} MB | "
        f"×{res['growth'][top]:.2f} |"
    )


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        prog="python -m towtank.testing.bench",
        description="Time towtank on a large synthetic campaign (see the module docstring).",
    )
    ap.add_argument("--runs", type=int, default=500, help="runs of the 1x campaign (500)")
    ap.add_argument("--fs", type=float, default=1000.0, help="sampling rate [Hz] (1000)")
    ap.add_argument("--workdir", type=Path, default=Path("/tmp/towtank-bench"),
                    help="where the campaign is generated and kept (/tmp/towtank-bench)")
    ap.add_argument("--scales", default="1,2,4",
                    help="campaign sizes, multiples of --runs, for the growth figures (1,2,4)")
    ap.add_argument("--jobs", "-j", type=int, help="towtank --jobs (default: all cores)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--repeat", type=int, default=1,
                    help="repeat every measurement and keep the best time (1)")
    ap.add_argument("--markdown", action="store_true", help="also print a README table row")
    args = ap.parse_args(argv)
    try:
        scales = tuple(int(s) for s in args.scales.split(",") if s.strip())
    except ValueError:
        ap.error("--scales takes whole numbers separated by commas, e.g. 1,2,4")
    if args.runs < 1 or not scales or min(scales) < 1:
        ap.error("--runs and every scale must be at least 1")
    res = run_bench(args.workdir, runs=args.runs, fs=args.fs, scales=scales, jobs=args.jobs,
                    seed=args.seed, repeat=args.repeat)
    print(format_table(res))
    if args.markdown:
        print()
        print(markdown_row(res))
    print(f"figures written to {args.workdir.resolve() / 'bench.json'}")
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
