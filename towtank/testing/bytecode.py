"""Bytecode for the Python processes a test run or a benchmark starts, where the environment
switches writing it off.

``PYTHONDONTWRITEBYTECODE`` (set in Python's container images and in many sandboxes) stops
Python from writing the compiled modules (``.pyc``) beside their sources. A source tree
imported that way is compiled again in every new process: towtank's modules cost 0.9 CPU-s per
start on a 2-core CI machine (``import towtank.commands.cli, towtank.pipeline,
towtank.report.pdf``: 2.9–3.1 CPU-s without the bytecode, 2.0–2.1 with it), which an installed
package never pays. The bytecode is then written under a folder of the caller's
(``PYTHONPYCACHEPREFIX``, :data:`sys.pycache_prefix`), never beside the sources.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Mapping
from pathlib import Path

__all__ = ["bytecode_env", "keep_bytecode_under"]

#: The variable that switches bytecode writing off.
NO_BYTECODE = "PYTHONDONTWRITEBYTECODE"
#: The variable that names the folder bytecode is written under.
PREFIX = "PYTHONPYCACHEPREFIX"


def bytecode_env(env: Mapping[str, str], folder: Path) -> dict[str, str]:
    """``env`` for a new Python process that keeps its bytecode: where ``env`` switches
    writing off, writing is switched on again under ``folder`` (or under the folder ``env``
    already names); elsewhere ``env`` as it is (a copy)."""
    out = dict(env)
    if out.get(NO_BYTECODE):
        out.pop(NO_BYTECODE)
        out.setdefault(PREFIX, str(folder))
    return out


def keep_bytecode_under(folder: Path) -> bool:
    """Bytecode kept under ``folder`` by this process and the processes it starts from now on,
    where the environment switches writing off (:func:`bytecode_env` applied to
    :data:`os.environ`, and this interpreter's own switches set to match); True if so."""
    if not os.environ.get(NO_BYTECODE):
        return False
    env = bytecode_env(os.environ, folder)
    os.environ.pop(NO_BYTECODE)
    os.environ[PREFIX] = env[PREFIX]
    sys.pycache_prefix = env[PREFIX]
    sys.dont_write_bytecode = False
    return True
