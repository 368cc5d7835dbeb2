"""The day's messages as objects: a warning is a :class:`Notice`, a rejected run a
:class:`Rejection`.

Each is a sentence and fields saying where it comes from. ``str()`` of either is the sentence
towtank prints and writes (the terminal, runs.csv's ``reason``, the report, the workbook); a
program picks or groups messages by their fields (stage, run, file, kind), never by their
words.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import PurePath
from typing import Literal, get_args

__all__ = ["REJECTION_KINDS", "STAGES", "Notice", "Rejection", "RejectionKind", "Stage",
           "notices"]

#: The step of the day a message comes from.
Stage = Literal["protocol", "sheet", "reduce", "tare", "hull", "fins", "scaling", "captive",
                "vehicle", "export"]
#: Every :data:`Stage`, in the order of the pipeline.
STAGES: tuple[str, ...] = get_args(Stage)

#: Why a run is rejected: its sheet row is wrong (``"sheet"``), its file is also another
#: run's (``"duplicate_file"``), its path cannot be opened (``"unreadable"``), its data cannot
#: be reduced (``"run_error"``), an unexpected error reducing it (``"internal_error"``), the
#: process reducing it died (``"crashed"``) or its tare group has no usable sting run
#: (``"no_tare"``).
RejectionKind = Literal["sheet", "duplicate_file", "unreadable", "run_error", "internal_error",
                        "crashed", "no_tare"]
#: Every :data:`RejectionKind`.
REJECTION_KINDS: tuple[str, ...] = get_args(RejectionKind)


def _check_stage(stage: str, what: str) -> None:
    if stage not in STAGES:
        raise ValueError(f"a {what}'s stage is one of {', '.join(STAGES)}, not {stage!r}")


@dataclass(frozen=True)
class Notice:
    """One warning of the day: a sentence and where it comes from.

    ``str(notice)`` is the sentence, as ``towtank process`` prints it and the report and the
    workbook list it; the fields say where it comes from, so that a program picks warnings by
    stage, run or file and never by their words.

    Attributes
    ----------
    text : str
        The sentence
    stage : Stage
        The step it comes from: ``"protocol"``, ``"sheet"``, ``"reduce"``, ``"tare"``,
        ``"hull"``, ``"fins"``, ``"scaling"``, ``"vehicle"`` or ``"export"``
    run : int or None
        The run it is about; None for the day or several runs
    file : str or None
        The file it is about (as the sheet names it); None for none or several
    """

    text: str
    stage: Stage
    run: int | None = None
    file: str | None = None

    def __post_init__(self) -> None:
        _check_stage(self.stage, "notice")

    def __str__(self) -> str:
        return self.text


def notices(texts: Iterable[str], stage: Stage, run: int | None = None,
            file: str | None = None) -> list[Notice]:
    """The sentences ``texts`` of one stage (and run, file) as :class:`Notice` objects."""
    return [Notice(str(t), stage, run, file) for t in texts]


@dataclass(frozen=True)
class Rejection:
    """Why one run of the day is not used.

    ``str(rejection)`` is the sentence runs.csv's ``reason``, the terminal and the report give:
    ``run 7: run_007.csv: the speed never reaches a plateau`` (``run N: file: reason``, or
    ``run N: reason`` where the reason names the file itself).

    Attributes
    ----------
    run : int
        The run number of the sheet
    file : str
        The run's file, as the sheet names it
    stage : Stage
        The step that rejected it (``"sheet"``, ``"reduce"`` or ``"tare"``)
    reason : str
        What is wrong, without the run number and the file prefix
    kind : RejectionKind
        A short stable identifier of the way it was rejected (:data:`REJECTION_KINDS`)
    file_prefix : bool
        Whether the sentence puts ``file:`` before the reason (False where the reason is
        about the file by name, or about the sheet's row)
    """

    run: int
    file: str
    stage: Stage
    reason: str
    kind: RejectionKind
    file_prefix: bool = True

    def __post_init__(self) -> None:
        _check_stage(self.stage, "rejection")
        if self.kind not in REJECTION_KINDS:
            raise ValueError(f"a rejection's kind is one of {', '.join(REJECTION_KINDS)}, "
                             f"not {self.kind!r}")

    @classmethod
    def of_run_error(cls, run: int, file: str, sentence: str) -> Rejection:
        """The rejection of a run whose data cannot be reduced, from the one sentence the
        reading or reduction gave (:class:`towtank.errors.RunError`): ``file:`` is put
        before it unless it names the file already, and a leading ``file:`` of its own
        becomes the prefix."""
        # the raise site's sentence is read once, here, where the rejection is made
        if sentence.startswith(f"{file}:"):
            return cls(run, file, "reduce", sentence[len(file) + 1:].lstrip(), "run_error")
        named = file in sentence or PurePath(file).name in sentence
        return cls(run, file, "reduce", sentence, "run_error", file_prefix=not named)

    @property
    def detail(self) -> str:
        """The sentence without its ``run N:``: ``file: reason``, or the reason alone."""
        return f"{self.file}: {self.reason}" if self.file_prefix else self.reason

    def __str__(self) -> str:
        return f"run {self.run}: {self.detail}"
