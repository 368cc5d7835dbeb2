"""Error types that carry one sentence for the user.

``RunError`` rejects one run (the rest of the day goes on); ``ProtocolError`` stops the whole
day before anything is written (exit status 2).
"""

from __future__ import annotations


class TowtankError(Exception):
    """Base class: the message is a complete sentence meant for a lab engineer."""


class ProtocolError(TowtankError):
    """The protocol or the run sheet is unusable: nothing is processed, nothing is written."""


class RunError(TowtankError):
    """One run cannot be used; ``str(err)`` names the run, the file and the reason.

    ``kind``: what went wrong when a caller acts on it (``"missing_channel"``: a channel the
    run needs is not in the file), else ""."""

    def __init__(self, reason: str, run: int | None = None, file: str | None = None,
                 kind: str = ""):
        self.reason = reason
        self.run = run
        self.file = file
        self.kind = kind
        super().__init__(self.sentence())

    def sentence(self) -> str:
        who = []
        if self.run is not None:
            who.append(f"run {self.run}")
        head = ": ".join(filter(None, [", ".join(who), self.file]))
        return f"{head}: {self.reason}" if head else self.reason
