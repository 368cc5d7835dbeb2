"""The output folder: what towtank writes there, and the checks before it writes anything.

Writing a day's outputs must never touch an input nor a file towtank did not write
(docs/formats.md §4). :func:`check_output_dir` resolves the folder and refuses, in one
sentence, a folder that is a file, that is, holds or lies inside the data folder, whose
outputs would replace an input, that holds an entry with an output's name towtank did not
write, or that cannot be written.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

from towtank.errors import ProtocolError
from towtank.runtime import manifest

__all__ = ["OUTPUT_NAMES", "OutputFolder", "check_output_dir"]

#: Every entry towtank writes into an output folder (docs/formats.md §5; the cache aside).
OUTPUT_NAMES = frozenset({
    "runs.csv", "coefficients.csv", "fins.csv", "fin_curves.csv", "fin_control.csv",
    "scaling.csv", "tare.csv", "report.xlsx", "report.pdf", "figures", "provenance.json",
    "predicted.csv", "model.json", "export", "pmm.csv",
})


@dataclass(frozen=True)
class OutputFolder:
    """A checked output folder: ``path`` (resolved) and ``recovered``, the sentence saying
    which set of outputs was put back after an interrupted run (None when none was)."""

    path: Path
    recovered: str | None = None


def check_output_dir(out_dir: str | Path, data_dir: str | Path,
                     inputs: Iterable[str | Path] = ()) -> OutputFolder:
    """The output folder, resolved, after checking that writing there cannot touch an input
    nor a file towtank did not write (docs/formats.md §4).

    A set of outputs that an interrupted run left beside a missing output folder is put back
    first (:func:`towtank.runtime.manifest.recover_outputs`); the sentence saying so is
    returned in :attr:`OutputFolder.recovered`, for the day's warnings.

    Parameters
    ----------
    out_dir : str or Path
        The output folder.
    data_dir : str or Path
        The folder of the raw run files ([campaign] data_dir).
    inputs : iterable of str or Path
        The files no output may replace: the protocol, the run sheet, a reference CSV, the run
        files.

    Raises
    ------
    ProtocolError
        ``out_dir`` is a file; it is, holds or lies inside the data folder; one of the
        outputs would replace an input; it holds an entry with an output's name that towtank
        did not write; or it cannot be written.
    """
    out = Path(out_dir).resolve()
    recovered = manifest.recover_outputs(out)
    if out.exists() and not out.is_dir():
        raise ProtocolError(f"the output folder {out} is a file, not a folder.")
    data = Path(data_dir).resolve()
    if out == data or data.is_relative_to(out) or out.is_relative_to(data):
        raise ProtocolError(
            f"the output folder {out} would mix the outputs with the raw run files in {data}; "
            "choose another folder with --out or [campaign] output_dir."
        )
    real_inputs = [(path, Path(path).resolve()) for path in inputs]  # each resolved once
    for name in sorted(OUTPUT_NAMES):
        target = out / name
        for path, real in real_inputs:
            if target == real or real.is_relative_to(target):
                raise ProtocolError(
                    f"the output folder {out} would overwrite the input {path} with the "
                    f"output {name}; choose another folder with --out or [campaign] output_dir."
                )
    manifest.refuse_foreign(out, OUTPUT_NAMES)
    problem = manifest.unwritable(out)
    if problem:
        raise ProtocolError(f"the output folder {out} cannot be written ({problem}); choose "
                            "another folder with --out or [campaign] output_dir.")
    return OutputFolder(out, recovered)
