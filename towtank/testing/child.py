"""towtank's commands run one after the other in one new interpreter, for the tests whose
commands need a process of their own (an address-space limit, a FIFO that could block, a file
that could be read without end): one start-up and one import of the libraries for all of them.
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
from collections.abc import Mapping, Sequence

__all__ = ["DONE", "run_in_child"]

#: The line the child writes to stdout and to stderr after each command, with its status.
DONE = "--- towtank child: exit"

_CHILD = """
import json, sys
{prelude}
from towtank.commands.cli import main
for args in json.loads(sys.argv[1]):
    code = {call}
    for stream in (sys.stdout, sys.stderr):
        print({done!r}, code, file=stream, flush=True)
"""


def run_in_child(commands: Sequence[Sequence[str]], *, timeout: float,
                 prelude: str = "", call: str = "main(args)",
                 env: Mapping[str, str] | None = None) -> list[subprocess.CompletedProcess]:
    """Run each of ``commands`` (``towtank`` arguments) in one child process.

    Parameters
    ----------
    commands : sequence of sequences of str
        The commands' arguments, run in this order.
    timeout : float
        Bound on the whole child [s]: a hang raises :class:`subprocess.TimeoutExpired`.
    prelude : str, optional
        Python run in the child before towtank is imported (an address-space limit, ...).
    call : str, default "main(args)"
        The expression that runs one command ``args`` and gives its exit status (a prelude
        may define another function to call).
    env : mapping, optional
        The child's environment (default this process's).

    Returns
    -------
    list of subprocess.CompletedProcess
        Each command's exit status, stdout and stderr. A command after one that ended the
        child gets the child's status (or -1) and what it said last.
    """
    script = _CHILD.format(prelude=prelude, call=call, done=DONE)
    child = subprocess.run([sys.executable, "-c", script, json.dumps([list(c) for c in commands])],
                           capture_output=True, text=True, timeout=timeout,
                           env=None if env is None else dict(env))
    mark = re.compile(rf"^{re.escape(DONE)} (-?\d+)\n", re.M)
    outs, errs = mark.split(child.stdout), mark.split(child.stderr)
    done = []
    for i, args in enumerate(commands):
        if 2 * i + 1 < len(outs) and 2 * i + 1 < len(errs):
            code, out, err = int(outs[2 * i + 1]), outs[2 * i], errs[2 * i]
        else:  # the child ended within this command or an earlier one
            code, out, err = child.returncode or -1, outs[-1], errs[-1]
        done.append(subprocess.CompletedProcess(list(args), code, out, err))
    return done
