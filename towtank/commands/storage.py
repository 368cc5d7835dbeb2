"""Outputs of ``predict`` and ``simulate`` written through the output manifest, with the
storage's errors (a full disk, a read-only file system...) as one sentence and exit 2."""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

from towtank.errors import ProtocolError
from towtank.runtime.manifest import writing_outputs
from towtank.runtime.storage import storage_error

__all__ = ["write_outputs_or_stop"]


def write_outputs_or_stop(folder: Path, names: frozenset[str],
                          write: Callable[[Path], None]) -> None:
    """Write ``names`` into ``folder`` through the output manifest
    (:func:`towtank.runtime.manifest.writing_outputs`) by ``write(tmp)``; a full disk or
    quota, a read-only file system or a refused permission (the errno of
    :data:`towtank.runtime.storage.STORAGE_ERRNOS`, whatever library met it) is a
    ProtocolError (exit 2) saying that the folder is as it was: the outputs are written into
    a temporary folder first and moved into place only when all of them are complete, and a
    folder this call created is removed."""
    folder = Path(folder)
    existed = folder.exists()
    try:
        with writing_outputs(folder, names) as tmp:  # never over a file of the user's
            write(tmp)
    except Exception as exc:  # noqa: BLE001 - only the storage's errors are handled here
        full = storage_error(exc, folder)
        if full is None:
            raise
        if not existed:
            try:
                folder.rmdir()  # only if empty: what this call created
            except OSError:
                pass
        raise ProtocolError(f"the outputs could not be written to {folder} "
                            f"({os.strerror(full.errno or 0)}); the folder is as it was "
                            "before this command.") from None
