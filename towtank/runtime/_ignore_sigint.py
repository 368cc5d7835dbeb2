"""Imported first by the fork server of :mod:`towtank.runtime.parallel` (its ``PRELOAD``), and
only there: Ctrl-C is the main process's to handle, so the fork server ignores SIGINT from
here on (it loads the reduction's libraries next; a Ctrl-C meanwhile would print its traceback)
and every worker it forks is born ignoring it. Do not import it anywhere else.
"""

import signal

signal.signal(signal.SIGINT, signal.SIG_IGN)
if hasattr(signal, "pthread_sigmask"):  # born with SIGINT blocked (parallel._sigint_blocked)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
