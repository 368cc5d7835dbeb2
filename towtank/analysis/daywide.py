"""Day-wide faults: one mistake that rejects every run said once, not once per run.

A wrong extension, a missing gain or a misnamed column rejects every run for the same reason;
listing it 41 times (and drawing 41 empty thumbnails) hides it. A reason is the same for two
runs when it is word for word the same once each run's own file name and number are taken out
(and, for a rejection, the numbers it quotes: each run's own sample counts and times).
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import PurePath
from typing import Any

import pandas as pd

from towtank.ingest.calibration import UNITS
from towtank.messages import Rejection

__all__ = ["RejectionGroup", "group_rejections", "group_run_warnings", "grouped_warnings",
           "run_warning_lines", "unit_label_sentences", "sheet_note_sentences",
           "temperature_sentences", "temperature_problems",
           "run_ranges", "run_reason", "own_reason", "and_list", "MIN_GROUP"]

#: Fewest runs a day-wide fault groups; it must also be at least half the day's runs that are
#: not void (a fault in 3 of 40 files is those files' own, and is listed run by run).
MIN_GROUP = 3


@dataclass(frozen=True)
class RejectionGroup:
    """Runs rejected for one reason.

    Attributes
    ----------
    runs : list of int
        The runs, ascending.
    sentence : str
        One sentence for all of them (a single run: its own reason).
    day_wide : bool
        True when the same fault rejected at least :data:`MIN_GROUP` runs and half the day.
    """

    runs: list[int]
    sentence: str
    day_wide: bool


def run_ranges(runs: list[int]) -> str:
    """Run numbers as ranges: ``1–39, 41, 42``."""
    out: list[str] = []
    runs = sorted(runs)
    i = 0
    while i < len(runs):
        j = i
        while j + 1 < len(runs) and runs[j + 1] == runs[j] + 1:
            j += 1
        out.append(f"{runs[i]}–{runs[j]}" if j - i >= 2 else
                   ", ".join(str(r) for r in runs[i:j + 1]))
        i = j + 1
    return ", ".join(out)


def own_reason(run: Any, file: Any, reason: Any) -> str:
    """The reason without the ``run N:`` and ``file:`` prefixes the pipeline puts in front."""
    sentence = str(reason).strip() if isinstance(reason, str) and reason else "no reason given"
    for prefix in (f"run {run}:", f"{file}:"):
        if sentence.startswith(prefix):
            sentence = sentence[len(prefix):].strip()
    return sentence


def _placeholders(run: int | str, file: Any, text: str) -> str:
    """``text`` with this run's file name, stem and number replaced by placeholders."""
    name = str(file) if isinstance(file, str) else ""
    for part in sorted({name, PurePath(name).name, PurePath(name).stem} - {""}, key=len,
                       reverse=True):
        text = text.replace(part, "\x00file")
    return re.sub(rf"\brun {run}\b", "run \x00n", text)


def _generic(run: int, file: Any, warning: str) -> str:
    """A per-run warning without its ``run N:`` and ``file:`` prefixes and with this run's
    file name, stem and number replaced by placeholders."""
    return _placeholders(run, file, own_reason(run, file, warning))


#: A number in a sentence (``3001``, ``-0.144887``, ``1.2e-3``), not part of a name (``Fx1``).
_NUMBER = re.compile(r"(?<![\w.])[-+−]?\d+(?:[.,]\d+)?(?:[eE][-+]?\d+)?(?![\w])")


def _same_rejection(rejection: Rejection) -> tuple[str, str]:
    """A rejection's kind and its reason with the run's own file name, run number and the
    numbers it quotes replaced by placeholders: equal for the runs of one fault."""
    return rejection.kind, _NUMBER.sub("\x00#", _placeholders(rejection.run, rejection.file,
                                                                rejection.reason))


def group_rejections(runs: pd.DataFrame, rejected: Mapping[int, Rejection],
                     min_group: int = MIN_GROUP) -> list[RejectionGroup]:
    """The rejected runs (``rejected``, of the day whose runs.csv table is ``runs``) grouped
    by kind and reason: a fault shared by at least ``min_group`` runs and half the runs that
    are not void is one :class:`RejectionGroup` (its sentence the first run's reason); every
    other rejected run is its own. Two rejections are one fault when they are of one kind and
    their reasons are word for word the same once each run's file name, run number and the
    numbers they quote are taken out.

    Returns
    -------
    list of RejectionGroup
        In order of each group's first run.
    """
    if not rejected:
        return []
    n_used = int((runs["status"] != "void").sum())
    by_reason: dict[tuple[str, str], list[Rejection]] = {}
    for run in sorted(rejected):
        by_reason.setdefault(_same_rejection(rejected[run]), []).append(rejected[run])
    groups: list[RejectionGroup] = []
    for members in by_reason.values():
        if len(members) >= min_group and 2 * len(members) >= n_used:
            numbers = [m.run for m in members]
            first = members[0]
            every = "every run that is not void" if len(members) == n_used else \
                f"{len(members)} of the {n_used} runs that are not void"
            groups.append(RejectionGroup(
                numbers,
                f"one fault rejected {every} (runs {run_ranges(numbers)}), shown for "
                f"{first.file}: {first.reason}",
                True))
        else:
            groups += [RejectionGroup([m.run], str(m), False) for m in members]
    return sorted(groups, key=lambda g: g.runs[0])


def run_reason(run: int, remarks: Any, rejected: Mapping[int, Rejection]) -> str:
    """Why a run is not used, as the report lists it: a rejected run's own reason (without
    its run number and file), a void run's remarks, "no reason given" for none."""
    if run in rejected:
        return rejected[run].reason
    return remarks.strip() if isinstance(remarks, str) and remarks.strip() else \
        "no reason given"


def _files(members: list[tuple[int, Any]]) -> str:
    """``run_001.lvm … run_042.lvm`` (the first and last file of runs in run order)."""
    files = [str(f) for _, f in sorted(members, key=lambda m: m[0])]
    return files[0] if len(files) == 1 else f"{files[0]} … {files[-1]}"


def _by_text(items: list[tuple[int, Any, str]]) -> dict[str, list[tuple[int, Any, str]]]:
    """``(run, file, warning)`` by the warning's text without the run's own file and number."""
    by_text: dict[str, list[tuple[int, Any, str]]] = {}
    for run, file, w in items:
        by_text.setdefault(_generic(run, file, w), []).append((run, file, w))
    return by_text


def grouped_warnings(items: list[tuple[int, Any, str]], min_group: int = MIN_GROUP
                     ) -> set[tuple[int, str]]:
    """The ``(run, warning)`` of ``items`` that :func:`group_run_warnings` says once for the
    day (the report leaves them out of its notes on single runs)."""
    return {(m[0], m[2]) for members in _by_text(items).values() if len(members) >= min_group
            for m in members}


def group_run_warnings(items: list[tuple[int, Any, str]], min_group: int = MIN_GROUP
                       ) -> list[str]:
    """The day's lines for per-run warnings ``(run, file, warning)``: a warning that is word
    for word the same in at least ``min_group`` runs once each run's file name and number are
    taken out (``DragR`` left unmapped in every file) is one sentence naming how many runs and
    the first and last file; every other one stays ``run N: warning.``. In order of each
    line's first run."""
    return [line for _, _, line in run_warning_lines(items, min_group)]


def run_warning_lines(items: list[tuple[int, Any, str]], min_group: int = MIN_GROUP
                      ) -> list[tuple[int | None, Any, str]]:
    """:func:`group_run_warnings` with the run and file of each line: ``(run, file, line)``
    for a line about one run, ``(None, None, line)`` for a warning said once for many."""
    lines: list[tuple[int, int | None, Any, str]] = []
    for generic, members in _by_text(items).items():
        if len(members) >= min_group:
            text = own_reason("\x00n", "\x00file", generic)
            text = text.replace("\x00file", "each run's file").replace("run \x00n", "each run")
            first = min(m[0] for m in members)
            lines.append((first, None, None,
                          f"{len(members)} runs ({_files([m[:2] for m in members])}; "
                          f"runs {run_ranges([m[0] for m in members])}): "
                          f"{text.rstrip('.')}."))
        else:
            lines += [(m[0], m[0], m[1], f"run {m[0]}: {m[2].rstrip('.')}.") for m in members]
    return [(run, file, line) for _, run, file, line in sorted(lines, key=lambda x: x[0])]


def unit_label_sentences(items: list[tuple[int, Any, dict[str, tuple[str, str]]]]) -> list[str]:
    """One sentence per set of channels that had no unit label, over the day's runs ``(run,
    file, units)`` (units: channel → (unit, source), source ``"assumed"`` when no unit was
    stated): ``drag and lift had no unit label in 42 run files (run_001.lvm … run_042.lvm):
    taken as N; state `unit` in [channels] to silence this.``"""
    groups: dict[tuple[tuple[str, str], ...], list[tuple[int, Any]]] = {}
    for run, file, units in items:
        key = tuple((c, u) for c, (u, src) in units.items() if src == "assumed")
        if key:
            groups.setdefault(key, []).append((run, file))
    out = []
    for key, members in sorted(groups.items(), key=lambda g: min(m[0] for m in g[1])):
        by_unit: dict[str, list[str]] = {}
        for c, u in key:
            by_unit.setdefault(u, []).append(c)
        names = and_list([c for c, _ in key])
        taken = f"taken as {key[0][1]}" if len(by_unit) == 1 else "; ".join(
            f"{and_list(cs)} taken as {u}" for u, cs in by_unit.items())
        n = len(members)
        files = f"{n} run file{'s' if n > 1 else ''} ({_files(members)})"
        out.append(f"{names} had no unit label in {files}: {taken}; state `unit` in "
                   "[channels] to silence this.")
    return out + _unknown_label_sentences(items)


def _unknown_label_sentences(items: list[tuple[int, Any, dict[str, tuple[str, str]]]]
                             ) -> list[str]:
    """One sentence per channel and unit label towtank does not convert (source
    ``"unknown"``): ``drag's unit label 'lb' is not one towtank converts in 42 run files
    (...): taken as N; ...``."""
    groups: dict[tuple[str, str], list[tuple[int, Any]]] = {}
    for run, file, units in items:
        for c, (u, src) in units.items():
            if src == "unknown":
                groups.setdefault((c, u), []).append((run, file))
    out = []
    for (c, u), members in sorted(groups.items(), key=lambda g: min(m[0] for m in g[1])):
        n = len(members)
        out.append(f"{c}'s unit label '{u}' is not one towtank converts in {n} run "
                   f"file{'s' if n > 1 else ''} ({_files(members)}): taken as "
                   f"{UNITS.get(c, 'SI')}; state `unit` in [channels] to silence this.")
    return out


def and_list(names: list[str]) -> str:
    """``a``, ``a and b``, ``a, b and c``."""
    return names[0] if len(names) == 1 else ", ".join(names[:-1]) + " and " + names[-1]


def sheet_note_sentences(notes: list[str]) -> list[str]:
    """One sentence for the run sheet's lines of text read as notes (the first three shown,
    each cut at 80 characters); none without notes."""
    if not notes:
        return []
    shown = "; ".join(repr(n if len(n) <= 80 else n[:77] + "...") for n in notes[:3])
    shown += "; ..." if len(notes) > 3 else ""
    return [f"the run sheet's {len(notes)} line(s) of text among or below the table are read "
            f"as notes, not runs: {shown}."]


def temperature_sentences(sheet: pd.DataFrame, *, air: bool = False) -> list[str]:
    """A sentence per run (void ones aside) whose temperature lies outside 0–40 °C [°C]:
    outside the ITTC water properties' range in water, the usual range of a rig in air."""
    return [sentence for _, sentence in temperature_problems(sheet, air=air)]


def temperature_problems(sheet: pd.DataFrame, *, air: bool = False) -> list[tuple[int, str]]:
    """:func:`temperature_sentences` with each sentence's run: ``(run, sentence)``."""
    out = []
    for rec in sheet.to_dict("records"):
        temp = rec["water_temp_C"]
        if rec["status"] != "void" and not 0.0 <= temp <= 40.0:
            out.append((int(rec["run"]),
                f"run {rec['run']}: air temperature {temp:g} °C is outside 0–40 °C, the usual "
                "range of a test rig in air (a unit mistake?)." if air else
                f"run {rec['run']}: water temperature {temp:g} °C is outside 0–40 °C, where the "
                "ITTC water properties are extrapolated (a unit mistake?)."
            ))
    return out
