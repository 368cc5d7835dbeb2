"""Run-level parallelism: reduce runs over the machine's cores, results in sheet order.

How the work is spread (campaign scale, hundreds of runs):

* The first record is reduced in this process before any worker exists. Every lazy import it
  needs (pyarrow, scipy's filters) and every per-process cache it fills (filter design, water
  properties) is then inherited by the forked workers, copy-on-write, instead of being paid
  again in each worker.
* The workers are forked (POSIX) and find the function, the protocol and the records in this
  module's memory; only record numbers are sent to them, in small chunks (a few runs each), so
  the protocol is never pickled and the last chunks keep every core busy.
* A reduction comes back as it is (a few kB: means, windows and decimated samples; the raw
  channels never cross the process boundary), chunk by chunk and in order, so the caller can
  store each in the cache while the workers go on.
"""

from __future__ import annotations

import itertools
import multiprocessing as mp
import os
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor
from typing import Any, TypeVar

T = TypeVar("T")

#: Records per task sent to a worker (at most); small enough to balance the tail.
MAX_CHUNK = 8

# Work of the running map_runs calls, by token; read by the forked workers (never pickled).
_TASKS: dict[int, tuple[Callable[..., Any], Any, Sequence[dict[str, Any]], bool]] = {}
_TOKENS = itertools.count(1)


def default_jobs() -> int:
    """All the cores this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)


def chunk_size(n_records: int, jobs: int) -> int:
    """Records per task: about eight tasks per worker, at most :data:`MAX_CHUNK`."""
    return max(1, min(MAX_CHUNK, n_records // (8 * jobs)))


def map_runs(
    func: Callable[..., T],
    protocol: Any,
    records: Sequence[dict[str, Any]],
    *,
    jobs: int | None = None,
    debug: bool = False,
) -> Iterator[T]:
    """``func(protocol, record, debug=debug)`` for every record, in order.

    With ``jobs`` > 1 the records are spread over worker processes (fork, so the protocol and
    the imported modules are shared copy-on-write); results still come back in sheet order, so
    the outputs do not depend on the number of jobs. Without fork (not POSIX) the records are
    reduced in this process.
    """
    records = list(records)
    jobs = default_jobs() if jobs is None else max(1, int(jobs))
    jobs = min(jobs, len(records) - 1) if len(records) > 1 else 1
    if jobs <= 1 or "fork" not in mp.get_all_start_methods():
        for rec in records:
            yield func(protocol, rec, debug=debug)
        return
    # the first record here: imports and caches are then shared by the forked workers
    yield func(protocol, records[0], debug=debug)
    rest = records[1:]
    token = next(_TOKENS)
    _TASKS[token] = (func, protocol, rest, debug)
    try:
        chunk = chunk_size(len(rest), jobs)
        tasks = [(token, i, min(i + chunk, len(rest))) for i in range(0, len(rest), chunk)]
        with ProcessPoolExecutor(max_workers=jobs, mp_context=mp.get_context("fork")) as pool:
            for results in pool.map(_run_slice, tasks):
                yield from results
    finally:
        del _TASKS[token]


def _run_slice(task: tuple[int, int, int]) -> list[Any]:
    """In a worker: the records [i0, i1) of the map_runs call ``token``."""
    token, i0, i1 = task
    func, protocol, records, debug = _TASKS[token]
    return [func(protocol, records[i], debug=debug) for i in range(i0, i1)]
