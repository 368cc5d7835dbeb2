"""Run-level parallelism: reduce runs over the machine's cores, results in sheet order."""

from __future__ import annotations

import multiprocessing as mp
import os
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor
from typing import Any, TypeVar

T = TypeVar("T")


def default_jobs() -> int:
    """All the cores this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)


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
    the outputs do not depend on the number of jobs.
    """
    jobs = default_jobs() if jobs is None else max(1, int(jobs))
    jobs = min(jobs, len(records)) if records else 1
    if jobs <= 1:
        for rec in records:
            yield func(protocol, rec, debug=debug)
        return
    ctx = mp.get_context("fork")
    chunk = max(1, len(records) // (4 * jobs))
    with ProcessPoolExecutor(max_workers=jobs, mp_context=ctx) as pool:
        yield from pool.map(_call, [(func, protocol, rec, debug) for rec in records],
                            chunksize=chunk)


def _call(args: tuple[Callable[..., Any], Any, dict[str, Any], bool]) -> Any:
    func, protocol, rec, debug = args
    return func(protocol, rec, debug=debug)
