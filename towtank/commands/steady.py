"""``towtank steady``: a glider's steady glides and spirals over lists of ballast, pitch and
roll (steady.csv, steady.png; docs/formats.md §6, docs/method.md "Steady glide and steady
spiral")."""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any

import pandas as pd

from towtank.commands.storage import write_outputs_or_stop
from towtank.errors import ProtocolError
from towtank.report.steady_figure import save_steady_figure
from towtank.vehicle import schema
from towtank.vehicle.assumptions import guessed, guessed_line
from towtank.vehicle.glider_controls import model_glider_problems
from towtank.vehicle.model import read_model
from towtank.vehicle.spiral import steady_table

__all__ = ["STEADY_OUTPUTS", "MAX_COMBINATIONS", "parse_list", "steady_command"]

#: The files ``steady`` writes.
STEADY_OUTPUTS = frozenset({"steady.csv", "steady.png"})
#: Most combinations of ballast, pitch and roll one call solves [-].
MAX_COMBINATIONS = 5000
_NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
_RANGE = re.compile(rf"^\s*({_NUMBER})\s*:\s*({_NUMBER})\s*:\s*({_NUMBER})\s*$")


def parse_list(text: str, option: str) -> list[float]:
    """The numbers of a list option: ``-200,-300,-450`` (comma-separated) or ``-45:-5:5``
    (start:stop:step, both ends included when the step lands on the stop).

    Raises
    ------
    ProtocolError
        One sentence naming the option and the text.
    """
    how = (f"{option} takes numbers separated by commas (-200,-300,-450) or start:stop:step "
           f"(-45:-5:5), not {text!r}.")
    m = _RANGE.match(text)
    if m:
        start, stop, step = (float(g) for g in m.groups())
        if not step or not all(math.isfinite(v) for v in (start, stop, step)):
            raise ProtocolError(how)
        if (stop - start) / step < 0:
            hint = (f"; towtank reads start:stop:step, so steps of {stop:g} from {start:g} "
                    f"to {step:g} are {start:g}:{step:g}:{stop:g}"
                    if (step - start) * stop > 0 else "")
            raise ProtocolError(f"{option} {text!r}: the step {step:g} does not lead from "
                                f"{start:g} to {stop:g}{hint}.")
        n = int(math.floor((stop - start) / step + 1e-9)) + 1
        if n > MAX_COMBINATIONS:
            raise ProtocolError(f"{option} {text!r} has {n} values, more than the "
                                f"{MAX_COMBINATIONS} towtank steady solves.")
        return [round(start + k * step, 12) for k in range(n)]
    parts = [p.strip() for p in text.split(",")]
    if not parts or any(not re.fullmatch(_NUMBER, p) for p in parts):
        raise ProtocolError(how)
    values = [float(p) for p in parts]
    if not all(math.isfinite(v) for v in values):
        raise ProtocolError(how)
    return values


def _check(model: dict[str, Any], name: str, ballasts: list[float], pitches: list[float],
           rolls: list[float]) -> list[str]:
    glider = model.get("glider")
    if glider is None:
        return [f"{name}: the model has no 'glider' block (ballast, moving mass, wings); give "
                "the protocol a [vehicle.glider] section and run 'towtank predict' again."]
    problems = model_glider_problems(model, name)
    if problems:
        return problems
    lo, hi = glider["ballast_cc"]
    bad = [b for b in ballasts if not lo <= b <= hi]
    if bad:
        problems.append(f"--ballast-cc {bad[0]:g} is outside the glider's ballast range "
                        f"{lo:g} to {hi:g} cc ('ballast_cc' of [vehicle.glider]).")
    bad = [p for p in pitches if not abs(p) < 90.0]
    if bad:
        problems.append(f"--pitch-deg {bad[0]:g} must lie strictly within ±90 deg.")
    bad = [r for r in rolls if not abs(r) < 90.0]
    if bad:
        problems.append(f"--roll-deg {bad[0]:g} must lie strictly within ±90 deg.")
    if rolls and any(rolls) and not glider.get("roll_mass_kg"):
        problems.append(f"{name}: --roll-deg needs a roll mass (roll_mass_kg and "
                        "roll_mass_radius_m in [vehicle.glider]).")
    n = len(ballasts) * len(pitches) * max(1, len(rolls))
    if n > MAX_COMBINATIONS:
        problems.append(f"the lists give {n} combinations, more than the {MAX_COMBINATIONS} "
                        "towtank steady solves.")
    return problems


def steady_command(model_path: Path, ballast_cc: str, pitch_deg: str,
                   roll_deg: str | None = None, out: Path | None = None) -> int:
    """Solve and write steady.csv and steady.png; print the table."""
    name = Path(model_path).name
    ballasts = parse_list(ballast_cc, "--ballast-cc")
    pitches = parse_list(pitch_deg, "--pitch-deg")
    rolls = parse_list(roll_deg, "--roll-deg") if roll_deg is not None else [0.0]
    try:
        model = read_model(model_path)
    except schema.ModelError as exc:
        raise ProtocolError(schema.joined(exc.problems)) from None
    problems = _check(model, name, ballasts, pitches, rolls)
    if problems:
        raise ProtocolError(schema.joined(problems))
    table = steady_table(model, ballasts, pitches, rolls)
    names = [str(a["input"]) for a in guessed(model.get("assumptions") or [])]
    if names:  # every steady state rests on them
        text = f"rests on assumed inputs ({', '.join(names)}: model.json 'assumptions')"
        table["note"] = [f"{n}; {text}" if isinstance(n, str) and n else text
                         for n in table["note"]]
    folder = Path(out) if out is not None else Path.cwd() / "steady"

    def write(tmp: Path) -> None:
        table.to_csv(tmp / "steady.csv", index=False, float_format="%.6g")
        save_steady_figure(table, tmp / "steady.png", str(model.get("name", "glider")))

    write_outputs_or_stop(folder, STEADY_OUTPUTS, write)
    show = table.drop(columns=["note"])
    with pd.option_context("display.width", 200, "display.max_columns", 30,
                           "display.max_rows", 200):
        print(show.to_string(index=False, float_format=lambda v: f"{v:.4g}"))
    failed = int((~table["converged"].astype(bool)).sum())
    line = guessed_line(model.get("assumptions"))
    if line:
        print(line)
    print(f"wrote {folder / 'steady.csv'} and steady.png ({len(table)} rows"
          + (f", {failed} with no steady state: see 'note'" if failed else "") + ")")
    return 0
