"""Run-level parallelism: reduce runs over the machine's cores, results in sheet order.

How the work is spread (campaign scale, hundreds of runs):

* The workers come from a *fork server* (``multiprocessing``'s "forkserver" start method) that
  imports the reduction's libraries once (:data:`PRELOAD`: pyarrow, scipy's filters, the
  reduction modules) and forks every worker from that warm state. The main process never
  imports them itself: it reads the run sheet, consults the cache and loads the fitting
  libraries while the fork server loads the reduction's, one core each.
* :func:`prestart` starts the pool early (the ``process`` command calls it before it even loads
  pandas); the first :func:`map_runs` call then uses it. Without it, :func:`map_runs` starts a
  pool of its own, or reduces a handful of records in this process.
* Records are sent to the workers in small chunks (a few runs each), so the last chunks keep
  every core busy; a reduction comes back as it is (a few kB: means, windows and decimated
  samples; the raw channels never cross the process boundary), chunk by chunk and in order, so
  the caller can store each in the cache while the workers go on.
* A worker that dies (killed, out of memory, a crash inside a library) costs only the record
  it was on: the records not yet returned are done again one per worker, and the one whose
  worker dies again gets the caller's ``on_crash`` result (a rejected run).
* Where there is no fork server (Windows), or the calling program could not be imported safely
  by a worker (a script that calls towtank at its top level, without
  ``if __name__ == "__main__":``; a program read from standard input), the records are reduced
  in this process: see :func:`main_is_importable`.
* Ctrl-C (SIGINT, which a terminal sends to the whole process group) is the main process's to
  handle: the fork server, the workers and :func:`run_beside`'s processes ignore it from birth
  (each is started with SIGINT blocked, and ignores it before unblocking it). Once interrupted,
  the main process ends them: the writers and a fork server still loading are killed, the
  workers finish their current chunk and stop (:meth:`_Pool.close`).
"""

from __future__ import annotations

import ast
import contextlib
import gc
import importlib
import multiprocessing as mp
import os
import select
import signal
import sys
import threading
import time
import traceback
import warnings
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import Executor, ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from multiprocessing import forkserver, resource_tracker
from pathlib import Path
from typing import Any, TypeVar

from towtank.runtime.pause import pause_at
from towtank.runtime.storage import chained_errno, os_error

T = TypeVar("T")

#: Records per task sent to a worker (at most); small enough to balance the tail.
MAX_CHUNK = 8

#: Fewest records worth starting a pool for when none was started beforehand: below it the
#: records are reduced in this process (starting the fork server costs about one library load).
MIN_RECORDS_FOR_POOL = 16

#: Modules the fork server imports once, before it forks any worker; the first makes it (and
#: so every worker) ignore Ctrl-C.
PRELOAD = ("towtank.runtime._ignore_sigint", "numpy", "pyarrow", "pyarrow.csv", "scipy.signal",
           "scipy.ndimage", "towtank.reduce.run")

_lock = threading.Lock()
_prestarted: dict[str, Any] = {}  # "pool": _Pool started by prestart(), until map_runs takes it


def default_jobs() -> int:
    """All the cores this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)


#: The environment variable that sets the processes towtank uses when neither the command line
#: (``--jobs``), the caller (``jobs=``) nor the protocol (``[processing] jobs``) says: a whole
#: number of at least 1, e.g. ``TOWTANK_JOBS=1`` on a machine whose cores other work holds.
JOBS_VARIABLE = "TOWTANK_JOBS"


def jobs_setting() -> tuple[int | None, str]:
    """:data:`JOBS_VARIABLE` read once: the processes it asks for (None when it is unset, empty
    or not a whole number of at least 1) and its text ("" when unset), for
    :func:`towtank.runner.settle_jobs`'s note on a value it leaves aside."""
    text = os.environ.get(JOBS_VARIABLE, "").strip()
    usable = text.isascii() and text.isdigit() and len(text) <= 9 and int(text) >= 1
    return (int(text) if usable else None), text


def environment_jobs() -> int | None:
    """The processes :data:`JOBS_VARIABLE` asks for: None when it is unset, empty or not a
    whole number of at least 1 (:func:`towtank.runner.settle_jobs` says so in a note)."""
    return jobs_setting()[0]


def usable_jobs(jobs: int | None) -> int:
    """Worker processes for a request of ``jobs`` (None: :data:`JOBS_VARIABLE`, else every
    core): at least one and never more than the cores this process may use (each worker holds
    a day's libraries, ~200 MB)."""
    cores = default_jobs()
    if jobs is None:
        jobs = environment_jobs()
    return cores if jobs is None else max(1, min(int(jobs), cores))


def fork_beside(jobs: int | None) -> bool:
    """Whether independent tasks of a request of ``jobs`` run in forked processes beside this
    one (:func:`run_beside`'s ``fork``): more than one usable job. One job (``--jobs 1``, a
    one-core machine) is one process throughout."""
    return usable_jobs(jobs) > 1


def chunk_size(n_records: int, jobs: int) -> int:
    """Records per task: about eight tasks per worker, at most :data:`MAX_CHUNK`."""
    return max(1, min(MAX_CHUNK, n_records // (8 * jobs)))


_SAFE_TOP_LEVEL = (
    ast.Import, ast.ImportFrom, ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef, ast.Pass,
)


def _guarded(node: ast.stmt) -> bool:
    """``if __name__ == "__main__":`` (either way round)."""
    if not isinstance(node, ast.If) or not isinstance(node.test, ast.Compare):
        return False
    sides = [node.test.left, *node.test.comparators]
    names = [s.id for s in sides if isinstance(s, ast.Name)]
    consts = [s.value for s in sides if isinstance(s, ast.Constant)]
    return names == ["__name__"] and consts == ["__main__"]


def _harmless(node: ast.stmt) -> bool:
    """A top-level statement a worker may run again: imports, definitions, constants."""
    if isinstance(node, _SAFE_TOP_LEVEL) or _guarded(node):
        return True
    if isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant):
        return True  # a docstring
    if isinstance(node, ast.Assign | ast.AnnAssign) and node.value is not None:
        return all(isinstance(n, ast.Constant | ast.Name | ast.Attribute | ast.Tuple | ast.List |
                              ast.Dict | ast.Set | ast.Load | ast.Store | ast.expr_context)
                   or isinstance(n, ast.operator | ast.unaryop | ast.BinOp | ast.UnaryOp)
                   for n in ast.walk(node.value))
    return False


def main_is_importable() -> bool:
    """Whether a worker process may import the calling program's ``__main__`` safely.

    A worker started by ``multiprocessing`` (spawn or fork server) runs the parent's main
    script again as ``__mp_main__``. That is harmless for ``python -m``, ``python -c``, IPython,
    Jupyter and the ``towtank`` command, and for a script whose top level only imports, defines
    and assigns constants (its work under ``if __name__ == "__main__":``). A script that calls
    towtank at its top level would run again in every worker (and multiprocessing refuses
    that), and a program read from standard input cannot be found again: for those the runs
    are reduced in the calling process instead.
    """
    main = sys.modules.get("__main__")
    if main is None or getattr(getattr(main, "__spec__", None), "name", None):
        return True  # python -m, Jupyter's kernel: imported by name, guarded by convention
    path = getattr(main, "__file__", None)
    if path is None:
        return True  # python -c, the interactive interpreter, IPython
    try:
        tree = ast.parse(Path(path).read_bytes())
    except (OSError, SyntaxError, ValueError):
        return False  # '<stdin>' (python -), a deleted or unreadable script
    return all(_harmless(node) for node in tree.body)


def _context() -> Any | None:
    """The fork-server context with :data:`PRELOAD`, or None where there is none or the
    calling program is not safe for workers to import (:func:`main_is_importable`)."""
    if "forkserver" not in mp.get_all_start_methods():
        return None  # pragma: no cover - Windows
    if not main_is_importable():
        return None
    ctx = mp.get_context("forkserver")
    ctx.set_forkserver_preload(list(PRELOAD))
    return ctx


#: Seconds between a worker's checks that the process that started it is still there.
WATCH_INTERVAL_S = 0.5


def _die_with(parent_pid: int) -> None:
    """Make this worker end as soon as ``parent_pid`` (the process that asked for the pool)
    ends, however it ends (SIGKILL, SIGTERM, the out-of-memory killer).

    Nothing else would end it: a worker's own parent is the fork server, and the fork server
    stays as long as any worker holds its "alive" pipe, which every worker does. A daemon
    thread waits on a pidfd of ``parent_pid`` (Linux ≥ 5.3: readable the moment the process
    exits, even before it is reaped); elsewhere it looks every :data:`WATCH_INTERVAL_S`
    seconds whether the process still exists.
    """

    def gone() -> bool:
        try:
            os.kill(parent_pid, 0)
        except OSError:  # no such process (or it is another user's now)
            return True
        try:  # a zombie is gone too: killed, waiting for its own parent to reap it
            with open(f"/proc/{parent_pid}/stat", "rb") as fh:
                return fh.read().rsplit(b")", 1)[1].split()[0] == b"Z"
        except (OSError, IndexError):
            return False

    def watch() -> None:
        try:
            fd = os.pidfd_open(parent_pid)
        except (AttributeError, OSError):
            fd = None
        if fd is not None:
            select.select([fd], [], [])
            os._exit(1)
        while not gone():
            time.sleep(WATCH_INTERVAL_S)
        os._exit(1)

    threading.Thread(target=watch, name="towtank-parent-watch", daemon=True).start()


@contextlib.contextmanager
def _sigint_blocked() -> Iterator[None]:
    """SIGINT blocked in the calling thread meanwhile: a process forked or spawned from it is
    born with SIGINT blocked (the mask is inherited, through exec too) and so cannot be stopped
    by a Ctrl-C before it has set itself to ignore it. A Ctrl-C that comes meanwhile is
    delivered when the block ends (in the main thread: KeyboardInterrupt there)."""
    if not hasattr(signal, "pthread_sigmask"):  # pragma: no cover - Windows
        yield
        return
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)


def _ignore_sigint() -> None:
    """In a child process: Ctrl-C is the main process's to handle. SIGINT is ignored, then
    unblocked (a Ctrl-C that came while it was blocked is dropped)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if hasattr(signal, "pthread_sigmask"):
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})


def _worker_init(parent_pid: int | None = None) -> None:
    """In each worker: Ctrl-C is the main process's to handle (no traceback from every
    worker), the worker dies with the main process, and pyarrow parses on this worker's core
    only (the others have workers)."""
    _ignore_sigint()  # already ignored since its fork (PRELOAD); this in case that failed
    leave_inherited_alone()  # the fork server's preloaded modules
    # a library's warning (numpy, npTDMS...) is not for the terminal: what matters reaches
    # the run's notes and reasons
    warnings.simplefilter("ignore")
    if parent_pid is not None:
        _die_with(parent_pid)
    try:
        # loaded on use: pyarrow is loaded in the workers only, not in every
        # process that imports this module (the command line's, towtank inspect's)
        import pyarrow

        pyarrow.set_cpu_count(1)
    except Exception:  # noqa: BLE001 - a tuning knob only  # pragma: no cover
        pass


def _ready() -> int:
    return os.getpid()


def _start_forkserver() -> None:
    """Start the fork server now, from this thread, with SIGINT blocked: it is born unable to
    be stopped by Ctrl-C, and ignores it from the first module it preloads."""
    # the resource tracker unblocks SIGINT in the calling thread after starting itself: first
    resource_tracker.ensure_running()
    with _sigint_blocked():
        forkserver.ensure_running()


def end_forkserver() -> None:
    """Kill this process's fork server, if it has one: one still loading its libraries (for
    seconds), or an idle one after Ctrl-C (its interpreter takes a while to wind down); the
    next pool starts another. Not while a pool's workers run: they would be orphaned."""
    # the standard library has no public way: its private names, each looked up with care
    server = getattr(forkserver, "_forkserver", None)
    with getattr(server, "_lock", None) or contextlib.nullcontext():
        pid = getattr(server, "_forkserver_pid", None)
        if not isinstance(pid, int):
            return
        try:
            os.kill(pid, signal.SIGKILL)
        except OSError:
            pass
        stop = getattr(server, "_stop_unlocked", None)
        if stop is not None:
            with contextlib.suppress(OSError):
                stop()  # reaps it and forgets it


class _Pool:
    """A process pool whose workers are started in a background thread.

    Starting a fork-server worker waits until the server has loaded :data:`PRELOAD`; the thread
    lets this process go on meanwhile. The fork server itself is started here, by the calling
    thread, so that it runs from now on.
    """

    def __init__(self, jobs: int, ctx: Any) -> None:
        self.jobs = jobs
        self.ctx = ctx
        self.executor: Executor = ProcessPoolExecutor(
            max_workers=jobs, mp_context=ctx, initializer=_worker_init,
            initargs=(os.getpid(),),
        )
        self._stopping = threading.Event()
        try:
            _start_forkserver()
        except OSError:
            pass  # no fork server: the workers cannot start, map_runs reduces here
        except BaseException:  # Ctrl-C while it started (delivered as the block ended)
            end_forkserver()
            self.executor.shutdown(wait=False, cancel_futures=True)
            raise
        self._starter = threading.Thread(target=self._start, name="towtank-pool", daemon=True)
        self._starter.start()

    def _start(self) -> None:
        try:
            with _sigint_blocked():  # a fork server this thread (re)starts is born without it
                for _ in range(self.jobs):
                    if self._stopping.is_set():
                        return
                    self.executor.submit(_ready)
        except Exception:  # noqa: BLE001 - a pool that cannot start fails again in map()
            pass

    def close(self, *, interrupted: bool = False) -> None:
        """Wait for the workers to finish their tasks and end.

        ``interrupted`` (Ctrl-C, or the caller stopped): no more workers are started, the
        tasks not begun are dropped, and the fork server is killed: at once if it is still
        loading its libraries (no worker born yet; this also frees the thread waiting for it),
        else once the workers have ended. A worker is never killed: one killed while it sends
        a result would leave the pool's result pipe half written and its thread waiting for
        the rest for ever; each ends after its current task (a chunk: :data:`MAX_CHUNK`
        records at most), ignoring Ctrl-C meanwhile.
        """
        if interrupted:
            self._stopping.set()
            if not getattr(self.executor, "_processes", None):
                end_forkserver()
        self._starter.join()
        self.executor.shutdown(wait=True, cancel_futures=True)
        if interrupted:
            end_forkserver()  # idle now


def prestart(jobs: int | None = None) -> bool:
    """Start the worker pool now, for the next :func:`map_runs` call of this process.

    The workers load the reduction's libraries while this process reads the sheet; returns
    False (and starts nothing) for one job or where there is no fork server.
    """
    jobs = usable_jobs(jobs)
    ctx = _context() if jobs > 1 else None
    if ctx is None:
        return False
    with _lock:
        if "pool" not in _prestarted:
            _prestarted["pool"] = _Pool(jobs, ctx)
    return True


def discard_prestarted(*, interrupted: bool = False) -> None:
    """Stop a pool that :func:`prestart` started and no :func:`map_runs` call took
    (``interrupted``: see :meth:`_Pool.close`)."""
    with _lock:
        pool = _prestarted.pop("pool", None)
    if pool is not None:
        pool.close(interrupted=interrupted)


def load_in_background(modules: Sequence[str]) -> threading.Thread:
    """Import ``modules`` in a background thread; join it before using them.

    While this process only waits for the workers' results, the thread loads what the later
    stages need (the fitting libraries), on the core the waiting leaves free. Import errors are
    left for the later stages' own imports to raise.
    """

    def load() -> None:
        for name in modules:
            try:
                importlib.import_module(name)
            except Exception:  # noqa: BLE001 - raised again, in place, by the stage needing it
                pass

    thread = threading.Thread(target=load, name="towtank-imports", daemon=True)
    thread.start()
    return thread


def map_runs(
    func: Callable[..., T],
    protocol: Any,
    records: Sequence[dict[str, Any]],
    *,
    jobs: int | None = None,
    debug: bool = False,
    on_crash: Callable[[dict[str, Any]], T] | None = None,
    preload: Sequence[str] = (),
) -> Iterator[T]:
    """``func(protocol, record, debug=debug)`` for every record, in order.

    ``preload`` names modules the later stages need: while worker processes reduce the records
    and this process only waits, a thread imports them (:func:`load_in_background`). The
    thread runs only then, and is joined before anything runs here, so that this process
    never imports a module while the thread does (two threads importing one package at once
    can see it half-initialised: "module 'scipy' has no attribute '_lib'").

    With ``jobs`` > 1 the records are spread over worker processes (``func`` must be a
    module-level function, ``protocol`` and the records picklable); results still come back in
    sheet order, so the outputs do not depend on the number of jobs. A pool started by
    :func:`prestart` is used (and closed) by this call.

    When a worker dies (killed, out of memory, a crash inside a library), the records not yet
    returned are done again one at a time, each in a worker of its own, so that only the record
    that kills its worker is lost: its result is ``on_crash(record)`` (without ``on_crash`` the
    error is raised). Where workers cannot be started at all, the records are done here.
    """
    records = list(records)
    with _lock:
        pool = _prestarted.pop("pool", None)
    if pool is None:
        n_jobs = usable_jobs(jobs)
        n_jobs = min(n_jobs, len(records))
        ctx = _context() if n_jobs > 1 and len(records) >= MIN_RECORDS_FOR_POOL else None
        if ctx is not None:
            pool = _Pool(n_jobs, ctx)
    if pool is None:
        for rec in records:
            yield func(protocol, rec, debug=debug)
        return
    done = 0
    broken: BaseException | None = None
    stopped = False
    loading = load_in_background(preload) if preload else None
    try:
        chunk = chunk_size(len(records), pool.jobs)
        tasks = [
            (func, protocol, records[i : i + chunk], debug)
            for i in range(0, len(records), chunk)
        ]
        try:
            # not executor.map: on Ctrl-C it cancels the queued tasks, and Python 3.11's pool,
            # seeing its workers killed, then fails on them with a traceback of its own
            futures = [pool.executor.submit(_run_chunk, task) for task in tasks]
            for future in futures:
                results = future.result()
                yield from results
                done += len(results)
        except BrokenProcessPool as exc:
            broken = exc
        except OSError as exc:  # no worker could be started (no fork server here)
            if done:
                raise
            broken = exc
    except BaseException as exc:
        # Ctrl-C, or the caller stopped iterating (GeneratorExit): the rest is not wanted
        stopped = not isinstance(exc, Exception)
        raise
    finally:
        pool.close(interrupted=stopped)
        if loading is not None:
            loading.join()  # nothing is imported here while the thread imports
    if broken is None:
        return
    if isinstance(broken, OSError):
        for rec in records:
            yield func(protocol, rec, debug=debug)
        return
    for rec in records[done:]:
        yield _alone(func, protocol, rec, debug, pool.ctx, on_crash)


def _alone(
    func: Callable[..., T],
    protocol: Any,
    rec: dict[str, Any],
    debug: bool,
    ctx: Any,
    on_crash: Callable[[dict[str, Any]], T] | None,
) -> T:
    """One record in a worker of its own; ``on_crash(rec)`` if that worker dies."""
    with ProcessPoolExecutor(max_workers=1, mp_context=ctx, initializer=_worker_init,
                             initargs=(os.getpid(),)) as one:
        with _sigint_blocked():  # a fork server started again here is born without Ctrl-C
            future = one.submit(func, protocol, rec, debug=debug)
        try:
            return future.result()
        except BrokenProcessPool:
            if on_crash is None:
                raise
            return on_crash(rec)


def _run_chunk(task: tuple[Callable[..., Any], Any, list[dict[str, Any]], bool]) -> list[Any]:
    """In a worker: one chunk of records."""
    func, protocol, records, debug = task
    return [func(protocol, rec, debug=debug) for rec in records]


def leave_inherited_alone() -> None:
    """In a forked process: what it inherited lives until the process ends, so the cyclic
    garbage collector leaves it out of its scans (Python's :func:`gc.freeze`): a collection
    scans what this process makes, not the parent's objects again, and writes nothing to the
    memory pages it shares with the parent."""
    gc.freeze()


def run_beside(tasks: Sequence[tuple[str, Callable[[], object]]], *, fork: bool = True
               ) -> None:
    """Run independent ``(name, task)`` pairs at once: the first here, the others forked.

    For tasks that share nothing and write their own files (the parts of the report). Without
    ``fork`` (one job asked for), or where forking is not available or not safe (another
    thread is running), they run here one after another. A task that fails here raises as it
    is; one that fails (or dies) in its process makes a RuntimeError naming it, with its
    traceback as a note, once every task has ended; or an ``OSError`` of the storage errno
    (``ENOSPC``...) when a task failed for the storage (an ``OSError`` with that errno raised or
    in its chain), so that a full disk met in a forked writer stays a full disk
    (:mod:`towtank.runtime.storage`).
    The forked processes ignore Ctrl-C: when this process is interrupted (KeyboardInterrupt
    here), it kills them before the exception goes on.
    """
    if not fork or len(tasks) < 2 or "fork" not in mp.get_all_start_methods() or (
        threading.active_count() > 1
    ):
        for _, task in tasks:
            task()
        return
    ctx = mp.get_context("fork")
    children: list[tuple[str, Any, Any]] = []
    try:
        with _sigint_blocked():  # born blocking Ctrl-C, until they ignore it
            for name, task in tasks[1:]:
                recv, send = ctx.Pipe(duplex=False)
                proc = ctx.Process(target=_run_in_child, args=(task, send), daemon=True)
                proc.start()
                send.close()
                children.append((name, proc, recv))
        pause_at("writing")
        try:
            tasks[0][1]()
        except Exception:
            _outcomes(children)  # the others end first; then this task's own error
            raise
        failures = _outcomes(children)
    except BaseException as exc:
        if not isinstance(exc, Exception):  # Ctrl-C: the others' work is not wanted
            _kill_children(children)
        raise
    if failures:
        codes = [code for _, _, code in failures if code is not None]
        error: Exception = (os_error(codes[0]) if codes
                            else RuntimeError("; ".join(f for f, _, _ in failures)))
        for what, trace, _ in failures:
            error.add_note(trace or what)
        raise error


def _outcomes(children: list[tuple[str, Any, Any]]) -> list[tuple[str, str, int | None]]:
    """Wait for each forked task; the failures as (what failed, traceback, storage errno or
    None)."""
    failures: list[tuple[str, str, int | None]] = []
    for name, proc, recv in children:
        try:
            outcome = recv.recv()
        except EOFError:
            outcome = ("the process running it stopped abruptly", "", None)
        proc.join()
        recv.close()
        if outcome is not None:
            failures.append((f"{name}: {outcome[0]}", outcome[1], outcome[2]))
    return failures


def _kill_children(children: list[tuple[str, Any, Any]]) -> None:
    """Kill the forked tasks and reap them."""
    for _, proc, _ in children:
        with contextlib.suppress(Exception):
            proc.kill()
    for _, proc, recv in children:
        with contextlib.suppress(Exception):
            proc.join()
            recv.close()


def _run_in_child(task: Callable[[], object], send: Any) -> None:
    """In a forked process: one task; sends None, or (error, traceback, storage errno or
    None)."""
    _ignore_sigint()  # born blocking it: a Ctrl-C is the parent's, which then ends this one
    leave_inherited_alone()
    try:
        task()
        outcome = None
    except BaseException as exc:  # noqa: BLE001 - reported to the parent, which raises
        outcome = (f"{type(exc).__name__}: {exc}", traceback.format_exc(), chained_errno(exc))
    send.send(outcome)
    send.close()
