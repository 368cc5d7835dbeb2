"""Bytecode for the Python processes a test run or a benchmark starts, where the environment
switches writing it off.

``PYTHONDONTWRITEBYTECODE`` (set in Python's container images and in many sandboxes) stops
Python from writing the compiled modules (``.pyc``) beside their sources. A source tree
imported that way is compiled again in every new process: towtank's modules cost 0.9 CPU-s per
start on a 2-core CI machine (``import towtank.commands.cli, towtank.pipeline,
towtank.report.pdf``: 2.9–3.1 CPU-s without the bytecode, 2.0–2.1 with it), which an installed
package never pays.

Two remedies. The test run switches writing on again as Python's default has it
(:func:`write_bytecode_again`): beside each source, in ``__pycache__`` (which git ignores),
where the installed libraries keep the bytecode pip compiled for them, so theirs is read, not
made again; when it ends it removes the folders it made (:func:`remove_new_pycache`), so that
the environment's wish holds after the run. The benchmark, which copies nothing into the
checkout, keeps its processes' bytecode under a folder of its own (:func:`bytecode_env`,
``PYTHONPYCACHEPREFIX``); there Python looks for every module's bytecode under that folder
only, the libraries' too, and compiles each library module once more per folder: a
pytest-xdist run on two cores started and collected its 2,542 tests in 47–49 CPU-s (30–31 s)
that way, and in 28–30 CPU-s (17–21 s) with the bytecode beside the sources (2026-11-29, a
fresh checkout each time).
"""

from __future__ import annotations

import os
import shutil
import sys
from collections.abc import Iterable, Mapping
from pathlib import Path

__all__ = ["bytecode_env", "pycache_folders", "remove_new_pycache", "write_bytecode_again"]

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


def write_bytecode_again() -> bool:
    """Bytecode written by this process and the processes it starts from now on, where the
    environment switches writing off: beside each source, as Python does by default (a
    folder named by ``PYTHONPYCACHEPREFIX`` is still used); True if writing was off."""
    if not os.environ.get(NO_BYTECODE):
        return False
    os.environ.pop(NO_BYTECODE)
    sys.dont_write_bytecode = False
    return True


def pycache_folders(roots: Iterable[Path]) -> set[Path]:
    """The ``__pycache__`` folders under each of ``roots`` (their own included)."""
    return {Path(top) / "__pycache__" for root in roots
            for top, dirs, _ in os.walk(root) if "__pycache__" in dirs}


def remove_new_pycache(roots: Iterable[Path], before: set[Path]) -> None:
    """Remove the ``__pycache__`` folders under ``roots`` that are not in ``before`` (those a
    run made after :func:`write_bytecode_again`); the others are left as they are."""
    roots = tuple(roots)
    for folder in sorted(pycache_folders(roots) - before):
        shutil.rmtree(folder, ignore_errors=True)
