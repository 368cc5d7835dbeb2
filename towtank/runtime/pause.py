"""A test hook: hold the ``towtank`` process at a named stage until a signal comes.

With ``TOWTANK_TEST_PAUSE_AT=<stage>`` (one of :data:`STAGES`) in its environment, the process,
when its main thread reaches that stage, writes the line ``<stage> <pid>`` to the file named by
``TOWTANK_TEST_PAUSE_FILE`` (to standard error without it) and sleeps there until a signal ends
the sleep (Ctrl-C: KeyboardInterrupt) or :data:`MAX_PAUSE_S` seconds have passed, then goes on.
The tests use it to send Ctrl-C at a known moment rather than after a guessed delay
(tests/test_interrupt.py). Without the variable, :func:`pause_at` returns at once; it is not
meant for anything but tests.

The stages, in the order a day meets them:

``start``    the Ctrl-C handler of the command line is installed, nothing else done yet;
``preload``  the worker pool is asked for: its fork server has just been started and loads
             the reduction's libraries;
``reduce``   the first run has come back from the workers, the others are being reduced;
``fits``     every run is reduced and tared; the fitting stages are about to begin;
``writing``  the report's writers run in processes of their own, beside this one.
"""

from __future__ import annotations

import os
import sys
import threading
import time

STAGES = ("start", "preload", "reduce", "fits", "writing")

#: Longest pause: a forgotten variable slows a run down, it never hangs it.
MAX_PAUSE_S = 60.0

_paused: set[str] = set()  # each stage holds the process once


def pause_at(stage: str) -> None:
    """Hold here if ``TOWTANK_TEST_PAUSE_AT`` names ``stage`` (see the module's docstring)."""
    if os.environ.get("TOWTANK_TEST_PAUSE_AT") != stage or stage in _paused:
        return
    if threading.current_thread() is not threading.main_thread():
        return  # only the main thread receives signals
    _paused.add(stage)
    line = f"{stage} {os.getpid()}\n".encode()
    target = os.environ.get("TOWTANK_TEST_PAUSE_FILE")
    if target:
        fd = os.open(target, os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o644)
        try:
            os.write(fd, line)
        finally:
            os.close(fd)
    else:
        sys.stderr.write(line.decode())
        sys.stderr.flush()
    end = time.monotonic() + MAX_PAUSE_S
    while time.monotonic() < end:
        time.sleep(0.05)  # a signal's handler runs here: Ctrl-C raises KeyboardInterrupt
