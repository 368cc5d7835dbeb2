"""A bound on how long a call in a test may take, so that a call that hangs fails the test
instead of holding up the run (a bound on hangs, not a speed requirement)."""

from __future__ import annotations

import signal
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

__all__ = ["Hang", "hang_bound"]


class Hang(BaseException):
    """A call that did not answer within its bound (not an Exception: ``main()`` would turn
    one into exit 3)."""


@contextmanager
def hang_bound(seconds: float) -> Iterator[None]:
    """Raise :class:`Hang` in the main thread if the block runs longer than ``seconds`` [s]
    (SIGALRM; the previous handler restored after the block)."""

    def alarm(signum: int, frame: Any) -> None:
        raise Hang(f"no answer within {seconds:g} s")

    before = signal.signal(signal.SIGALRM, alarm)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, before)
