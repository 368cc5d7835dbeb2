"""Latency of ``towtank watch``: from a run file's close to its verdict line and to state.json.

``python -m towtank.testing.bench_watch [--runs 50] [--gap-s 3] [--fs 200]`` generates a hull
day (the sample day's plan, repeated to ``--runs`` runs), starts ``towtank watch --no-browser
--no-server`` on it with an empty data folder, then writes the run files one by one the way
LabVIEW does (opened, appended in ten blocks 0.1 s apart, closed), ``--gap-s`` apart. For each
run it takes the time from the file's close to the verdict line on the command's stdout, to
the new state.json (its modification time) that holds the verdict, and to the page's update:
the event the page server pushes to every open page (``GET /events``) for that state (the
page then redraws); with ``--browser``, also to the verdict shown on the page itself, open
in headless Chromium (selenium; Debian's chromium and chromium-driver). It prints p50, p95 and
the largest of each. Not a unit test: it takes minutes.
"""

from __future__ import annotations

import argparse
import json
import os
import queue
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
import urllib.request
from pathlib import Path
from typing import Any

import numpy as np

from towtank.testing import synthetic as syn
from towtank.testing.browser import browser_missing, free_port, start_chromium
from towtank.testing.days import RunSpec, hull_day_plan

BLOCKS = 10
BLOCK_PAUSE_S = 0.1
TIMEOUT_S = 60.0
#: The checkout this module is in: the code a watch of :func:`start_watch` runs.
CHECKOUT = Path(__file__).resolve().parents[2]


def start_watch(protocol: Path, *options: str,
                stderr: int = subprocess.PIPE) -> subprocess.Popen[str]:
    """``towtank watch PROTOCOL --no-browser OPTIONS`` of this checkout as a process of its
    own, in a session of its own (its process group, page server included, can be ended at
    once); stdout (and ``stderr``) piped as text."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(CHECKOUT), *filter(None, [os.environ.get("PYTHONPATH")])])}
    return subprocess.Popen([sys.executable, "-m", "towtank", "watch", str(protocol),
                             "--no-browser", *options], stdout=subprocess.PIPE, stderr=stderr,
                            text=True, env=env, start_new_session=True)


def watch_session(protocol: Path, **kw: Any) -> tuple[Any, list[str]]:
    """A :class:`towtank.live.session.WatchSession` of ``protocol`` in this process (one
    worker; no report and no live figures unless ``kw`` asks for them), and the list its
    lines go to."""
    # loaded on use: the benchmark's own process never holds a session
    from towtank.ingest.protocol import load_protocol, with_output_dir
    from towtank.live.session import WatchSession

    p = load_protocol(protocol)
    p, out = with_output_dir(p, p.campaign.output_dir)
    lines: list[str] = []
    kw.setdefault("report", False)
    kw.setdefault("live_figures", False)
    return WatchSession(p, out, jobs=1, echo=lines.append, **kw), lines


def plan_of(n: int) -> list[RunSpec]:
    """The sample hull day's runs (void ones aside), repeated to ``n`` runs."""
    base = [r for r in hull_day_plan() if r.status != "void"]
    return [base[i % len(base)] for i in range(n)]


def labview_write(src: Path, dst: Path, blocks: int = BLOCKS,
                  pause_s: float = BLOCK_PAUSE_S) -> float:
    """Write ``src`` into ``dst`` as LabVIEW does: opened once, ``blocks`` blocks appended
    ``pause_s`` [s] apart, closed; the time of the close (``time.time()``)."""
    data = src.read_bytes()
    n = len(data)
    with open(dst, "wb") as fh:
        for i in range(blocks):
            fh.write(data[i * n // blocks:(i + 1) * n // blocks])
            fh.flush()
            if i < blocks - 1:
                time.sleep(pause_s)
    return time.time()


def _reader(stream, q: queue.Queue) -> None:
    for line in stream:
        q.put((time.time(), line))
    q.put((time.time(), None))


def _wait_line(q: queue.Queue, text: str) -> float:
    end = time.monotonic() + TIMEOUT_S
    while time.monotonic() < end:
        try:
            t, line = q.get(timeout=0.5)
        except queue.Empty:
            continue
        if line is None:
            raise RuntimeError("towtank watch ended")
        if text in line:
            return t
    raise RuntimeError(f"no line with {text!r} within {TIMEOUT_S:g} s")


def _wait_state(path: Path, run: int, version: int) -> tuple[float, int]:
    """(mtime of the first state.json after ``version`` holding run's verdict, its version)."""
    end = time.monotonic() + TIMEOUT_S
    while time.monotonic() < end:
        try:
            mtime = os.stat(path).st_mtime_ns / 1e9
            state = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            time.sleep(0.01)
            continue
        if state["version"] > version and any(v["run"] == run for v in state["verdicts"]):
            return mtime, int(state["version"])
        time.sleep(0.01)
    raise RuntimeError(f"state.json never gave run {run}")


def _listen(port: int, events: list[tuple[float, int]]) -> None:
    """The page's event stream: (arrival time, version) of every event, as a page gets it."""
    end = time.monotonic() + TIMEOUT_S
    while time.monotonic() < end:  # the server starts after the runs already there
        try:
            stream = urllib.request.urlopen(f"http://127.0.0.1:{port}/events", timeout=TIMEOUT_S)
            break
        except OSError:
            time.sleep(0.05)
    else:
        return
    for raw in stream:
        line = raw.decode("utf-8", "replace").strip()
        if line.startswith("data:"):
            try:
                events.append((time.time(), int(json.loads(line[5:])["version"])))
            except (ValueError, KeyError, TypeError):
                continue


def _wait_event(events: list[tuple[float, int]], version: int) -> float:
    end = time.monotonic() + TIMEOUT_S
    while time.monotonic() < end:
        for t, v in list(events):
            if v >= version:
                return t
        time.sleep(0.005)
    raise RuntimeError(f"the page server never pushed version {version}")


def _wait_shown(driver: Any, run: int) -> float:
    """The time the page in ``driver`` first shows ``run``'s verdict."""
    from selenium.common.exceptions import WebDriverException  # loaded on use: --browser only
    from selenium.webdriver.common.by import By

    end = time.monotonic() + TIMEOUT_S
    while time.monotonic() < end:
        try:
            if driver.find_element(By.ID, "verdict-head").text.startswith(f"Run {run} "):
                return time.time()
        except WebDriverException:  # the page is being redrawn
            pass
        time.sleep(0.005)
    raise RuntimeError(f"the page never showed run {run}")


def bench(runs: int, gap_s: float, fs: float, folder: Path,
          browser: bool = False) -> dict[str, list[float]]:
    """The latencies [s] of ``runs`` runs: {"verdict": [...], "state": [...], "page": [...]}
    and, with ``browser``, "shown": to the verdict on the page in headless Chromium."""
    day = folder / "day"
    syn.make_hull_day(day, runs=plan_of(runs), fs=fs, file_format="csv", sheet_format="csv")
    shutil.move(day / "data", folder / "all")
    (day / "data").mkdir()
    sections: Any = syn.hull_protocol_sections("day", "out", sheet_format="csv")
    protocol = syn.write_protocol(folder / "p.toml", **sections)
    port = free_port()
    proc = start_watch(protocol, "--port", str(port), stderr=subprocess.DEVNULL)
    q: queue.Queue = queue.Queue()
    threading.Thread(target=_reader, args=(proc.stdout, q), daemon=True).start()
    state = folder / "out" / ".live" / "state.json"
    out: dict[str, list[float]] = {"verdict": [], "state": [], "page": [], "shown": []}
    events: list[tuple[float, int]] = []
    driver = None
    try:
        _wait_line(q, "Ctrl-C to stop")
        threading.Thread(target=_listen, args=(port, events), daemon=True).start()
        version = _wait_state_any(state)
        if browser:
            driver = start_chromium(folder / "chromium")
            driver.get(f"http://127.0.0.1:{port}/")
        files = sorted((folder / "all").iterdir())
        for k, src in enumerate(files, start=1):
            start = time.monotonic()
            closed = labview_write(src, day / "data" / src.name)
            said = _wait_line(q, f"run {k}  ")
            written, version = _wait_state(state, k, version)
            pushed = _wait_event(events, version)
            out["verdict"].append(said - closed)
            out["state"].append(written - closed)
            out["page"].append(pushed - closed)
            shown = ""
            if driver is not None:
                out["shown"].append(_wait_shown(driver, k) - closed)
                shown = f", on the page {out['shown'][-1]:6.3f} s"
            print(f"run {k:3d}: verdict {said - closed:6.3f} s, state.json "
                  f"{written - closed:6.3f} s, page event {pushed - closed:6.3f} s{shown}",
                  flush=True)
            time.sleep(max(0.0, gap_s - (time.monotonic() - start)))
    finally:
        if driver is not None:
            driver.quit()
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGINT)
            try:
                proc.wait(timeout=60)
            except subprocess.TimeoutExpired:
                proc.kill()
    return out


def _wait_state_any(path: Path) -> int:
    end = time.monotonic() + TIMEOUT_S
    while time.monotonic() < end:
        try:
            return int(json.loads(path.read_text(encoding="utf-8"))["version"])
        except (OSError, ValueError, KeyError):
            time.sleep(0.05)
    raise RuntimeError("state.json never appeared")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=50)
    ap.add_argument("--gap-s", type=float, default=3.0, help="from one file's start to the next")
    ap.add_argument("--fs", type=float, default=200.0, help="sample rate of the runs [Hz]")
    ap.add_argument("--keep", type=Path, help="work in this folder and keep it")
    ap.add_argument("--browser", action="store_true",
                    help="also time the verdict shown on the page in headless Chromium")
    args = ap.parse_args(argv)
    if args.browser and (missing := browser_missing()):
        print(f"--browser needs Chromium: {missing}.", file=sys.stderr)
        return 2
    folder = args.keep or Path(tempfile.mkdtemp(prefix="bench_watch-"))
    folder.mkdir(parents=True, exist_ok=True)
    try:
        lat = bench(args.runs, args.gap_s, args.fs, folder, browser=args.browser)
    finally:
        if args.keep is None:
            shutil.rmtree(folder, ignore_errors=True)
    print()
    print(f"{args.runs} runs at {args.fs:g} Hz, {args.gap_s:g} s apart, written in {BLOCKS} "
          f"blocks {BLOCK_PAUSE_S:g} s apart; {os.cpu_count()} cores")
    print("| from the file's close to | p50 | p95 | max |")
    print("|---|---:|---:|---:|")
    for key, label in (("verdict", "the verdict line"), ("state", "state.json updated"),
                       ("page", "the page's update event"),
                       ("shown", "the verdict shown on the page (Chromium)")):
        if not lat[key]:
            continue
        v = np.asarray(lat[key])
        print(f"| {label} | {np.percentile(v, 50):.2f} s | {np.percentile(v, 95):.2f} s | "
              f"{v.max():.2f} s |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
