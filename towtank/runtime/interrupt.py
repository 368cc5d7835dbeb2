"""Ctrl-C in the ``towtank`` command: exit 130 with one sentence, whatever was running.

:func:`watching` (the command line's ``main`` runs in it) makes SIGINT raise KeyboardInterrupt
in the main thread, and records it. The worker processes ignore SIGINT
(:mod:`towtank.runtime.parallel`); this process ends them.

Python drops an exception raised inside a finalizer or a weakref callback ("Exception ignored
in ..."), and pandas, matplotlib and the garbage collector run many: a Ctrl-C that came while
one ran would be lost, the day would go on and end with exit 0. Such a Ctrl-C is raised again
:data:`AGAIN_S` later, wherever the main thread then is (by SIGALRM: a signal, so that it is not
raised inside the same finalizer). :func:`check`, called before the outputs are put in place,
raises one that a library's own ``except`` dropped.
"""

from __future__ import annotations

import contextlib
import signal
import sys
import threading
from collections.abc import Iterator
from typing import Any

#: Delay before a Ctrl-C that a finalizer dropped is raised again [s].
AGAIN_S = 0.01

_seen: list[bool] = []  # a Ctrl-C came (while watching)
_state = {"handled": False}  # its sentence is written: the process is ending


def _handler(signum: int, frame: object) -> None:
    """SIGINT, or SIGALRM for a Ctrl-C raised again: KeyboardInterrupt."""
    if _state["handled"]:
        return  # the process is ending already
    _seen.append(True)
    raise KeyboardInterrupt


@contextlib.contextmanager
def watching() -> Iterator[list[bool]]:
    """Within the block: SIGINT raises KeyboardInterrupt in the main thread and is recorded in
    the list yielded; one that a finalizer dropped is raised again.

    Outside the main thread, or where someone else (a notebook, a test harness) handles
    Ctrl-C already, nothing is changed (the list stays empty)."""
    if (threading.current_thread() is not threading.main_thread()
            or signal.getsignal(signal.SIGINT) is not signal.default_int_handler):
        yield []
        return
    previous_hook = sys.unraisablehook
    can_again = hasattr(signal, "setitimer") and hasattr(signal, "SIGALRM")
    previous_alarm = signal.getsignal(signal.SIGALRM) if can_again else None

    def unraisable(info: Any) -> None:
        if (can_again and isinstance(info.exc_type, type)
                and issubclass(info.exc_type, KeyboardInterrupt)
                and _seen and not _state["handled"]):
            signal.signal(signal.SIGALRM, _handler)
            signal.setitimer(signal.ITIMER_REAL, AGAIN_S)
            return
        previous_hook(info)

    _seen.clear()
    _state["handled"] = False
    signal.signal(signal.SIGINT, _handler)
    sys.unraisablehook = unraisable
    try:
        yield _seen
    finally:
        if signal.getsignal(signal.SIGINT) is _handler:
            signal.signal(signal.SIGINT, signal.default_int_handler)
        if can_again and signal.getsignal(signal.SIGALRM) is _handler:
            signal.setitimer(signal.ITIMER_REAL, 0)
            signal.signal(signal.SIGALRM, previous_alarm)
        if sys.unraisablehook is unraisable:
            sys.unraisablehook = previous_hook
        _seen.clear()
        _state["handled"] = False


def handled() -> None:
    """The interruption is reported: further Ctrl-C are ignored while the process ends."""
    if _seen:
        _state["handled"] = True


def check() -> None:
    """Raise KeyboardInterrupt if a Ctrl-C came (while :func:`watching`) and was dropped."""
    if _seen and not _state["handled"]:
        raise KeyboardInterrupt
